//! Path guiding (beyond the paper): what the path tracer samples directions from where it
//! has learned where light comes from.
//!
//! * [`Guide`] (`guide.rs`): a pixel's guide, the directional samplers of the mixtures the
//!   genetic algorithm evolved there, per vertex index, with a [`SpatialField`] past them;
//!   [`Vertex`] (`vertex.rs`) is the guide at one vertex, Open PGL's
//!   `SurfaceSamplingDistribution`.
//! * [`SpatialField`] (`field.rs`, built in `field_build.rs`): Open PGL's `Field`, the
//!   kd-tree of regions whose leaves hold directional quadtrees over a square map of the
//!   sphere (`square.rs`), looked up through a lattice per facing (`lattice.rs`); what its
//!   training did is in [`FieldStats`] (`stats.rs`).
//! * [`SampleStorage`] (`storage.rs`): the training records a field is built from, which a
//!   [`PathSegmentStorage`] (`recorder.rs`) fills along each training path.

pub mod bsdf;
pub mod field;
pub mod field_build;
pub mod guide;
pub mod lattice;
pub mod recorder;
pub mod square;
pub mod stats;
pub mod storage;
pub mod vertex;

pub use bsdf::GuidedBsdf;
pub use field::SpatialField;
pub use guide::Guide;
pub use recorder::PathSegmentStorage;
pub use stats::{FieldStats, LevelsTrial};
pub use storage::{Record, SampleStorage};
pub use vertex::{GuideSample, Vertex};
