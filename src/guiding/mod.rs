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
//!   training did is in [`FieldStats`] (`stats.rs`); per region, the share of guided
//!   sampling against the BSDF, fixed or learned from the records (`selection.rs`).
//! * [`SampleStorage`] (`storage.rs`): the training records a field is built from, which a
//!   [`PathSegmentStorage`] (`recorder.rs`) fills along each training path.
//! * [`GuidedBsdf`] (`bsdf.rs`): the material's BSDF at a vertex with the guide's samplers
//!   there, after the `GuidedBSDF` of Open PGL's pbrt-v4 fork: the one BSDF the path
//!   tracer's loop evaluates, weighs and samples at every vertex of a guided path (its
//!   contract is written on the type).
//!
//! # Layering
//!
//! `integrators` → (`genetic`, `guiding`) → transport (`path`) → `sampling` → `scene` →
//! `accel`, with no circle: a guide is made of transport's mixtures and generators, so
//! transport cannot see guiding. The path tracer ([`crate::path::pt`]) stays in transport,
//! where `pt`, `ga`'s pixels without a mixture and the GA's gate use it unguided, and asks
//! what it needs of a guide through two small traits of its own, which guiding implements:
//! [`Guide`] is a [`PathGuide`] (at each vertex: the probability of next-event estimation
//! and the [`GuidedBsdf`] to sample), and [`PathSegmentStorage`] is a [`PathRecorder`].
//! `pt::radiance_guided` is generic over both, so each guide gets its own monomorphised
//! loop, with no virtual call per vertex, and one loop serves guided and unguided paths
//! alike (moving the guided path tracer here instead would have made two loops, one in
//! each layer, that must stay bit for bit the same). Guiding imports nothing of `genetic`
//! or `integrators` (which is why [`GuidesTrial`], the GA trial's outcome that `pg` runs,
//! stays here with the field's statistics that report it).
//!
//! [`PathGuide`]: crate::path::pt::PathGuide
//! [`PathRecorder`]: crate::path::pt::PathRecorder

pub mod bsdf;
pub mod field;
pub mod field_build;
pub mod guide;
pub mod lattice;
mod level;
pub mod recorder;
pub mod selection;
pub mod square;
pub mod stats;
pub mod storage;
pub mod vertex;

pub use bsdf::GuidedBsdf;
pub use field::SpatialField;
pub use guide::Guide;
pub use recorder::PathSegmentStorage;
pub use stats::{FieldStats, GuidesTrial};
pub use storage::{Record, SampleStorage};
pub use vertex::{GuideSample, Vertex};
