//! genpath: genetic path generation (Dutré, Suykens, Willems, "Optimized Monte Carlo Path
//! Generation using Genetic Algorithms", KU Leuven report CW 267, 1998).

#![deny(unsafe_code)]

pub mod accel;
pub mod check;
pub mod genetic;
pub mod guiding;
pub mod image;
pub mod integrators;
pub mod path;
pub mod progress;
pub mod report;
pub mod sampling;
pub mod scene;
pub mod settings_table;
pub mod shard;
