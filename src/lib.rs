//! genpath: genetic path generation (Dutré, Suykens, Willems, "Optimized Monte Carlo Path
//! Generation using Genetic Algorithms", KU Leuven report CW 267, 1998).

pub mod accel;
pub mod image;
