//! genpath: genetic path generation (Dutré, Suykens, Willems, "Optimized Monte Carlo Path
//! Generation using Genetic Algorithms", KU Leuven report CW 267, 1998).
//!
//! # Layers
//!
//! The lower modules import one way, each only from the ones after it, so that each can be
//! read and tested without those above it:
//!
//! ```text
//! path → sampling → scene → accel → math
//!                         ↘ image
//! ```
//!
//! `path` (light transport, the path tracer) uses the samplers and BSDFs of `sampling`,
//! which read the materials, lights and textures of `scene`, which stores its geometry in
//! `accel`'s meshes; `math` holds the geometry and numerics that know no renderer type.
//! `image` (reading and writing pictures; `scene` reads its textures with it) imports none
//! of them. The methods and the tools
//! (`integrators`, `genetic`, `guiding`, `cli`, `shard`, `report`) sit above `path`. A lower
//! module's documentation names an upper one's items in plain backticks, never as a link.

#![deny(unsafe_code)]

pub mod accel;
pub mod check;
pub mod film;
pub mod genetic;
pub mod guiding;
pub mod image;
pub mod integrators;
pub mod math;
pub mod path;
pub mod progress;
pub mod report;
pub mod sampling;
pub mod scene;
pub mod settings_table;
pub mod shard;
