//! genpath: genetic path generation (Dutré, Suykens, Willems, "Optimized Monte Carlo Path
//! Generation using Genetic Algorithms", KU Leuven report CW 267, 1998).
//!
//! # Layers
//!
//! The modules import one way, each only from the ones below it, so that each can be read
//! and tested without those above it (`tests/layers.rs` keeps it so; docs/architecture.md
//! tells how a render flows through them):
//!
//! ```text
//! cli (the binary) → check, report → shard → integrators → genetic → guiding → film
//!   → path → sampling → scene → accel → math → image → progress, settings_table
//! ```
//!
//! `integrators` holds the methods, each one file that declares what it is; `genetic` (the
//! GA and its plans) and `guiding` (the spatial guide) are what they learn with; `film` is
//! what every method's samples land on, and its loop; `path` (light transport, the path
//! tracer) uses the samplers and BSDFs of `sampling`, which read the materials, lights and
//! textures of `scene`, which stores its geometry in `accel`'s meshes; `math` holds the
//! geometry and numerics that know no renderer type; `image` reads and writes pictures. A
//! lower module's documentation names an upper one's items in plain backticks, never as a
//! link.

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
