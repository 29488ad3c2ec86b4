//! The path recorder (Open PGL's `PathSegmentStorage`): what a training pass's path tracer
//! records along each path for the [`SampleStorage`] a [`SpatialField`] is trained on, as
//! the path tracer's [`PathRecorder`].
//!
//! [`SampleStorage`]: super::SampleStorage
//! [`SpatialField`]: super::SpatialField

use super::lattice::{facing, Lattice};
use super::selection::SelectionRecord;
use super::square::to_square;
use super::storage::{Record, SampleStorage, REACHED};
use crate::path::pt::{PathRecorder, Sampled};
use glam::Vec3;

/// Records collected along paths: the sampled directions' records wait for the radiance
/// the rest of the path brings back; the light samples' outcomes are kept per lattice cell.
#[derive(Debug)]
pub struct PathSegmentStorage {
    pending: Vec<Pending>,
    pub records: Vec<Record>,
    lattice: Lattice,
    /// Per light sample, its facing and lattice cell's index (as the tables of a
    /// [`SpatialField`](super::SpatialField) index them), with the bit `REACHED` set where
    /// it reached a light.
    pub light_tries: Vec<u32>,
    /// Whether it records what the share of guided sampling is learned from, and those
    /// records ([`super::selection`]).
    learns_selection: bool,
    pub selection: Vec<SelectionRecord>,
}

#[derive(Debug)]
struct Pending {
    /// The record, its value still to come.
    record: Record,
    /// `|cos| / pdf` of the sampled direction.
    cos_over_pdf: f32,
    /// The path throughput right after this vertex's sample, and the radiance collected
    /// before the sampled ray was traced.
    beta: Vec3,
    before: Vec3,
    /// `f · |cos| / pdf` of the sampled direction, and the guide's and the BSDF's densities
    /// along it where the share of guided sampling is learned from it.
    weight: Vec3,
    densities: Option<(f64, f64)>,
}

fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

impl PathSegmentStorage {
    /// No records yet, for `records`' lattice.
    pub fn new(records: &SampleStorage) -> Self {
        Self {
            pending: Vec::new(),
            records: Vec::new(),
            lattice: records.lattice().clone(),
            light_tries: Vec::new(),
            learns_selection: records.learns_selection,
            selection: Vec::new(),
        }
    }
}

/// Kept here, beside the recorder it takes, so that the storage need not import it.
impl SampleStorage {
    /// Adds a recorder's records and light tries.
    pub fn add_recorded(&mut self, recorder: PathSegmentStorage) {
        self.records.extend(recorder.records);
        self.light_tries.extend(recorder.light_tries);
        self.selection.extend(recorder.selection);
    }
}

impl PathRecorder for PathSegmentStorage {
    /// A light sample taken at `x` (normal `n`), and whether it reached a light (an
    /// unoccluded emitter that the BSDF reflects).
    fn light_try(&mut self, x: Vec3, n: Vec3, reached: bool) {
        let i = self.lattice.index_facing(x, n) as u32;
        self.light_tries.push(i | if reached { REACHED } else { 0 });
    }

    /// A light sample's record at `x` (normal `n`): `value` is its MIS-weighted `L_e |cos| /
    /// pdf` (throughput excluded).
    fn light(&mut self, x: Vec3, n: Vec3, wi: Vec3, value: Vec3) {
        let value = luminance(value);
        if value > 0.0 && value.is_finite() {
            self.records.push(Record {
                p: x,
                facing: facing(n) as u8,
                dir: to_square(wi),
                value,
            });
        }
    }

    fn records_densities(&self) -> bool {
        self.learns_selection
    }

    /// The direction sampled at vertex `x` (normal `n`), the throughput after the sample
    /// and the radiance collected so far.
    fn sampled(&mut self, x: Vec3, n: Vec3, sampled: Sampled, beta: Vec3, before: Vec3) {
        self.pending.push(Pending {
            record: Record {
                p: x,
                facing: facing(n) as u8,
                dir: to_square(sampled.wi),
                value: 0.0,
            },
            cos_over_pdf: sampled.cos_over_pdf,
            beta,
            before,
            weight: sampled.weight,
            densities: sampled.densities,
        });
    }

    /// Leaves the emission that the last sampled direction found at once (now added, the
    /// estimate being `radiance`) out of that direction's record: see [`super::field`] on
    /// direct light.
    fn emission_seen(&mut self, radiance: Vec3) {
        if let Some(p) = self.pending.last_mut() {
            p.before = radiance;
        }
    }

    /// Ends the path whose estimate is `radiance`: each sampled direction's record gets the
    /// radiance collected after it, divided by the throughput that carried it.
    fn finish(&mut self, radiance: Vec3) {
        for p in self.pending.drain(..) {
            let after = radiance - p.before;
            let li = Vec3::select(p.beta.cmpgt(Vec3::ZERO), after / p.beta, Vec3::ZERO);
            let value = luminance(li) * p.cos_over_pdf;
            if value > 0.0 && value.is_finite() {
                self.records.push(Record { value, ..p.record });
            }
            if let Some((guide_pdf, bsdf_pdf)) = p.densities {
                // `f L_i |cos| / pdf`: the one-sample estimate of the light the vertex
                // reflects, which the share is fitted to.
                let product = luminance(li * p.weight);
                if product > 0.0 && product.is_finite() {
                    self.selection.push(SelectionRecord {
                        p: p.record.p,
                        facing: p.record.facing,
                        product,
                        guide_pdf: guide_pdf as f32,
                        bsdf_pdf: bsdf_pdf as f32,
                    });
                }
            }
        }
    }
}
