//! A spatial guide for the vertices a pixel's mixture does not reach (beyond the paper).
//!
//! The genetic algorithm learns, per pixel, where light arrives from at the first vertices of
//! that pixel's paths. Deeper vertices lie anywhere in the scene, and a per-pixel mixture
//! says little about them. This guide learns incident light per region of space instead,
//! in the manner of "practical path guiding" (Müller et al. 2017) with a fixed structure:
//!
//! * space: the scene's bounding box cut into a regular grid of cells
//!   ([`CELLS_LONGEST`] along its longest side);
//! * directions: per cell, a piecewise-constant density over the sphere on an equal-area map
//!   (`cos θ` about the world `y` axis and `φ`, [`THETA_BINS`] × [`PHI_BINS`] bins of equal
//!   solid angle).
//!
//! It is trained on records of path-traced samples: at every non-delta vertex, the
//! cosine-weighted incident radiance along the sampled direction (and along the light sample's
//! direction, with its multiple-importance weight) over that direction's density. The sum of
//! a bin's records is proportional to an estimate of `∫_bin L_i |cos| dω`; the bin's
//! probability is that, normalised over the cell, with [`UNIFORM_SHARE`] of the sphere's uniform density mixed in. Cells
//! without a record carrying light are untrained: path tracing samples the BSDF there.
//!
//! A guided vertex draws its direction from `GUIDE_SHARE · p_guide + (1 − GUIDE_SHARE) ·
//! p_bsdf` and multiple importance sampling weighs next-event estimation against that
//! density, so the estimator stays unbiased whatever was learned.

use crate::accel::TriangleMesh;
use glam::Vec3;
use std::f64::consts::PI;

/// Bins of `cos θ` (about the world `y` axis) and of `φ`: 512 bins of 0.025 sr, about 9°
/// across. fig1, 64 spp, seed 7, `pg` relMSE (`pt`: 0.053): 0.036 with 8 × 16 bins and 16
/// training passes, 0.032 with 16 × 16 and 8 passes, 0.031 with 16 × 32 and 8 passes.
pub const THETA_BINS: usize = 16;
pub const PHI_BINS: usize = 32;
pub const BINS: usize = THETA_BINS * PHI_BINS;
/// Cells along the longest side of the scene's bounding box. fig1, equal time, 2 / 8 s,
/// `pg` with 4 passes over `pt`: 0.70 / 0.67 with 8 cells, 0.92 / 0.85 with 12 (too few
/// records per cell), and with 4 cells and 32 passes the per-sample relMSE is 0.049
/// against 0.036 with 8.
pub const CELLS_LONGEST: usize = 8;
/// Share of the uniform sphere density in a trained cell's density: directions the training
/// records missed keep some probability.
pub const UNIFORM_SHARE: f64 = 0.1;
/// Share of guided direction sampling at a trained vertex; the rest samples the BSDF.
/// (fig1, 64 spp, 8 × 16 bins: relMSE 0.038 / 0.039 / 0.050 / 0.128 at shares 0.3 / 0.5 /
/// 0.7 / 0.9; with 32 training passes 0.5 still beats 0.7, 0.036 against 0.042: a regular
/// grid's cells average incident light over too much space to be trusted further.)
pub const GUIDE_SHARE: f64 = 0.5;

/// The regular grid of cells over a bounding box.
#[derive(Clone, Debug)]
pub struct Grid {
    lo: Vec3,
    /// Cells per unit length (the same along every axis).
    scale: f32,
    res: [usize; 3],
}

impl Grid {
    /// A grid over the box `[lo, hi]` with [`CELLS_LONGEST`] cells along its longest side
    /// (at least one along every side).
    pub fn new(lo: Vec3, hi: Vec3) -> Self {
        let size = (hi - lo).max(Vec3::splat(1e-6));
        let scale = CELLS_LONGEST as f32 / size.max_element();
        let res = size
            .to_array()
            .map(|s| ((s * scale).ceil() as usize).clamp(1, CELLS_LONGEST));
        Self { lo, scale, res }
    }

    /// The grid over the bounding box of `mesh`.
    pub fn around(mesh: &TriangleMesh) -> Self {
        let (lo, hi) = mesh.bounds();
        if lo.cmple(hi).all() {
            Self::new(lo, hi)
        } else {
            Self::new(Vec3::ZERO, Vec3::ONE)
        }
    }

    pub fn cells(&self) -> usize {
        self.res.iter().product()
    }

    /// The cell containing `p` (points outside the box go to the nearest cell).
    pub fn cell(&self, p: Vec3) -> usize {
        let t = ((p - self.lo) * self.scale).to_array();
        // `as usize` maps NaN and negatives to 0.
        let i: [usize; 3] = std::array::from_fn(|a| (t[a] as usize).min(self.res[a] - 1));
        (i[2] * self.res[1] + i[1]) * self.res[0] + i[0]
    }
}

/// The bin of unit direction `d`: `cos θ = d.y` in [`THETA_BINS`] equal steps, and `φ + π`
/// (the angle of `(−d.x, −d.z)`) in [`PHI_BINS`] equal sectors, found by comparisons with
/// the sector boundaries' tangents rather than by `atan2` (every guided vertex computes two
/// or three bins).
pub fn bin(d: Vec3) -> usize {
    let t = (((d.y + 1.0) * 0.5 * THETA_BINS as f32) as usize).min(THETA_BINS - 1);
    let (a, b) = (-d.x, -d.z);
    // Quadrant of (a, b), and (a, b) rotated into the first one: (p > 0, r ≥ 0).
    let (quadrant, p, r) = match (a >= 0.0, b >= 0.0) {
        (true, true) => (0, a, b),
        (false, true) => (1, b, -a),
        (false, false) => (2, -a, -b),
        (true, false) => (3, -b, a),
    };
    let sector = SECTOR_TANGENTS.iter().filter(|&&tan| r >= p * tan).count();
    t * PHI_BINS + SECTORS * quadrant + sector
}

/// Sectors of `φ` per quadrant, and the tangents of their inner boundaries `k π / (2 ·
/// SECTORS)`, `k = 1 … SECTORS − 1`.
const SECTORS: usize = PHI_BINS / 4;
const SECTOR_TANGENTS: [f32; SECTORS - 1] = [
    0.198_912_37,
    0.414_213_57,
    0.668_178_6,
    1.0,
    1.496_605_8,
    2.414_213_6,
    5.027_339_5,
];

/// The direction at position `(r1, r2) ∈ [0, 1)²` inside `bin`, uniform in solid angle.
fn direction(bin: usize, r1: f64, r2: f64) -> Vec3 {
    let (t, p) = (bin / PHI_BINS, bin % PHI_BINS);
    let y = (-1.0 + 2.0 * (t as f64 + r1) / THETA_BINS as f64).clamp(-1.0, 1.0);
    let phi = 2.0 * PI * ((p as f64 + r2) / PHI_BINS as f64 - 0.5);
    let s = (1.0 - y * y).max(0.0).sqrt();
    Vec3::new((s * phi.cos()) as f32, y as f32, (s * phi.sin()) as f32).normalize()
}

/// One training record: a cell, a direction bin and the cosine-weighted radiance over the
/// direction's density (luminance).
#[derive(Clone, Copy, Debug)]
pub struct Record {
    pub cell: u32,
    pub bin: u16,
    pub value: f32,
}

/// Records collected along one path: the sampled directions' records wait for the radiance
/// the rest of the path brings back.
#[derive(Debug)]
pub struct PathRecorder {
    pub grid: Grid,
    pending: Vec<Pending>,
    pub records: Vec<Record>,
}

#[derive(Debug)]
struct Pending {
    cell: u32,
    bin: u16,
    /// `|cos| / pdf` of the sampled direction.
    cos_over_pdf: f32,
    /// The path throughput right after this vertex's sample, and the radiance collected
    /// before the sampled ray was traced.
    beta: Vec3,
    before: Vec3,
}

fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

impl PathRecorder {
    pub fn new(grid: Grid) -> Self {
        Self {
            grid,
            pending: Vec::new(),
            records: Vec::new(),
        }
    }

    /// A light sample's record at `x`: `value` is its MIS-weighted `L_e |cos| / pdf`
    /// (throughput excluded).
    pub fn light(&mut self, x: Vec3, wi: Vec3, value: Vec3) {
        let value = luminance(value);
        if value > 0.0 && value.is_finite() {
            self.records.push(Record {
                cell: self.grid.cell(x) as u32,
                bin: bin(wi) as u16,
                value,
            });
        }
    }

    /// The direction sampled at vertex `x`, with `|cos| / pdf`, the throughput after the
    /// sample and the radiance collected so far.
    pub fn sampled(&mut self, x: Vec3, wi: Vec3, cos_over_pdf: f32, beta: Vec3, before: Vec3) {
        self.pending.push(Pending {
            cell: self.grid.cell(x) as u32,
            bin: bin(wi) as u16,
            cos_over_pdf,
            beta,
            before,
        });
    }

    /// Ends the path whose estimate is `radiance`: each sampled direction's record gets the
    /// radiance collected after it, divided by the throughput that carried it.
    pub fn finish(&mut self, radiance: Vec3) {
        for p in self.pending.drain(..) {
            let after = radiance - p.before;
            let li = Vec3::select(p.beta.cmpgt(Vec3::ZERO), after / p.beta, Vec3::ZERO);
            let value = luminance(li) * p.cos_over_pdf;
            if value > 0.0 && value.is_finite() {
                self.records.push(Record {
                    cell: p.cell,
                    bin: p.bin,
                    value,
                });
            }
        }
    }
}

/// Per cell and bin, the summed values of the training records so far: each training pass
/// adds its records, and the guide of all of them is rebuilt from the sums.
#[derive(Clone, Debug)]
pub struct RecordSums {
    grid: Grid,
    sums: Vec<f64>,
    records: usize,
}

impl RecordSums {
    pub fn new(grid: Grid) -> Self {
        let sums = vec![0.0; grid.cells() * BINS];
        Self {
            grid,
            sums,
            records: 0,
        }
    }

    pub fn add(&mut self, records: impl IntoIterator<Item = Record>) {
        for r in records {
            self.records += 1;
            let i = r.cell as usize * BINS + r.bin as usize;
            if let Some(s) = self.sums.get_mut(i) {
                *s += f64::from(r.value);
            }
        }
    }

    /// The guide of the records added so far (see the module documentation).
    pub fn guide(&self) -> SpatialGuide {
        let cells = self.grid.cells();
        let mut trained = vec![false; cells];
        let mut density = vec![0.0f32; cells * BINS];
        let mut cdf = vec![0.0f32; cells * BINS];
        let bin_solid_angle = 4.0 * PI / BINS as f64;
        for c in 0..cells {
            let s = &self.sums[c * BINS..(c + 1) * BINS];
            let total: f64 = s.iter().sum();
            if !(total > 0.0 && total.is_finite()) {
                continue;
            }
            trained[c] = true;
            let mut acc = 0.0;
            for b in 0..BINS {
                let p = (1.0 - UNIFORM_SHARE) * s[b] / total + UNIFORM_SHARE / BINS as f64;
                density[c * BINS + b] = (p / bin_solid_angle) as f32;
                acc += p;
                cdf[c * BINS + b] = acc as f32;
            }
            cdf[c * BINS + BINS - 1] = 1.0;
        }
        let stats = SpatialStats {
            records: self.records,
            cells,
            trained_cells: trained.iter().filter(|&&t| t).count(),
            ..SpatialStats::default()
        };
        SpatialGuide {
            grid: self.grid.clone(),
            stats,
            trained,
            density,
            cdf,
        }
    }
}

/// What training a spatial guide did.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct SpatialStats {
    /// Training passes (one path-traced sample per pixel each).
    pub passes: u32,
    /// Records carrying light, over all passes.
    pub records: usize,
    pub cells: usize,
    pub trained_cells: usize,
    /// Wall-clock seconds of the training passes.
    pub seconds: f64,
}

/// The trained guide: per cell, bin probabilities and their cumulative sums.
#[derive(Clone, Debug)]
pub struct SpatialGuide {
    pub grid: Grid,
    pub stats: SpatialStats,
    /// Per cell: whether any record carried light.
    trained: Vec<bool>,
    /// Per cell and bin: solid-angle density, and cumulative probability up to the bin's end.
    density: Vec<f32>,
    cdf: Vec<f32>,
}

impl SpatialGuide {
    /// The guide trained on `records` (per cell and bin, their mean value: cells with no
    /// light stay untrained).
    pub fn train(grid: Grid, records: impl IntoIterator<Item = Record>) -> Self {
        let mut sums = RecordSums::new(grid);
        sums.add(records);
        sums.guide()
    }

    /// The trained cell at `p`, if any.
    pub fn cell(&self, p: Vec3) -> Option<usize> {
        let c = self.grid.cell(p);
        self.trained[c].then_some(c)
    }

    /// The solid-angle density of `cell`'s guide for unit `wi`.
    pub fn pdf(&self, cell: usize, wi: Vec3) -> f64 {
        f64::from(self.density[cell * BINS + bin(wi)])
    }

    /// A direction from `cell`'s density, from three uniform numbers.
    pub fn sample(&self, cell: usize, u: [f64; 3]) -> Vec3 {
        let cdf = &self.cdf[cell * BINS..(cell + 1) * BINS];
        let b = cdf.partition_point(|&c| f64::from(c) <= u[0]).min(BINS - 1);
        direction(b, u[1], u[2])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `bin` against the `atan2` it replaces, on random directions.
    #[test]
    fn bins_agree_with_atan2() {
        let mut rng = crate::sampling::sample_rng(9, 0, 0);
        for _ in 0..100_000 {
            let u = [0; 3].map(|_| crate::sampling::uniform(&mut rng) as f64);
            let d = direction((u[0] * BINS as f64) as usize, u[1], u[2]);
            let phi = (d.z as f64).atan2(d.x as f64);
            let p = (((phi / (2.0 * PI) + 0.5) * PHI_BINS as f64) as usize).min(PHI_BINS - 1);
            assert_eq!(bin(d) % PHI_BINS, p, "{d}");
        }
    }

    #[test]
    fn bins_are_equal_area_and_round_trip() {
        for b in 0..BINS {
            for (r1, r2) in [(0.1, 0.2), (0.5, 0.5), (0.9, 0.95)] {
                assert_eq!(bin(direction(b, r1, r2)), b, "bin {b} at ({r1}, {r2})");
            }
        }
    }

    #[test]
    fn density_integrates_to_one_and_matches_samples() {
        let grid = Grid::new(Vec3::ZERO, Vec3::ONE);
        let records = (0..200).map(|i| Record {
            cell: 0,
            bin: (i % 7) as u16,
            value: 1.0 + i as f32,
        });
        let guide = SpatialGuide::train(grid, records);
        assert!(guide.cell(Vec3::splat(0.01)).is_some());
        // ∫ p dω over the sphere by the bins' equal solid angles.
        let total: f64 = (0..BINS)
            .map(|b| guide.pdf(0, direction(b, 0.5, 0.5)) * 4.0 * PI / BINS as f64)
            .sum();
        assert!((total - 1.0).abs() < 1e-5, "{total}");
        // Sampled bin frequencies against the densities.
        let n = 200_000;
        let mut hits = vec![0u32; BINS];
        let mut rng = crate::sampling::sample_rng(3, 0, 0);
        for _ in 0..n {
            let u = [0; 3].map(|_| f64::from(crate::sampling::uniform(&mut rng)));
            hits[bin(guide.sample(0, u))] += 1;
        }
        // Largest |z| of the bins' counts against `scale` × their probabilities.
        let worst = |scale: f64| {
            (0..BINS)
                .map(|b| {
                    let p = scale * guide.pdf(0, direction(b, 0.5, 0.5)) * 4.0 * PI / BINS as f64;
                    let expected = p * n as f64;
                    (hits[b] as f64 - expected).abs() / expected.sqrt().max(1.0)
                })
                .fold(0.0, f64::max)
        };
        assert!(worst(1.0) < 5.0, "max |z| {}", worst(1.0));
        // The same check rejects probabilities off by 5 %.
        assert!(worst(1.05) > 5.0, "max |z| {} off by 5 %", worst(1.05));
    }
}
