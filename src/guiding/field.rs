//! A spatial guide for the vertices a pixel's mixture does not reach (beyond the paper).
//!
//! The genetic algorithm learns, per pixel, where light arrives from at the first vertices of
//! that pixel's paths. Deeper vertices lie anywhere in the scene, and a per-pixel mixture
//! says little about them. This guide learns incident light per region of space instead,
//! after "practical path guiding" (Müller, Gross and Novák 2017): a spatial-directional tree.
//!
//! * space: per way a surface can face ([`facing`]: the two sides of a thin wall learn
//!   apart), a kd-tree over the scene's bounding box, a node cut in two at the middle of its
//!   longest side while it holds more than [`SPLIT_RECORDS`] training records, down to a
//!   lattice cell ([`LATTICE_LONGEST`] along the longest side): regions are small where
//!   light was recorded often (near what the camera sees) and large elsewhere, and a lookup
//!   is one read of a per-cell table;
//! * directions: per spatial leaf, a quadtree over a square map of the sphere ([`to_square`]:
//!   `u = (cos θ + 1) / 2` about the world `y` axis, `v` the azimuth's "diamond angle"), a quadrant
//!   subdivided while it carries more than [`SPLIT_ENERGY`] of the leaf's recorded light and
//!   holds at least [`MIN_NODE_RECORDS`] records: fine where light comes from a small
//!   solid angle (a slit, a lit band), coarse elsewhere.
//!
//! It is trained on records of path-traced samples: at every non-delta vertex, the
//! cosine-weighted incident radiance along the sampled direction (and along the light
//! sample's direction, with its multiple-importance weight) over that direction's density.
//! At a diffuse vertex, light arriving straight from an emitter is left out of the records
//! (the light sample's record, and the emission the sampled direction finds at once):
//! next-event estimation samples it well there, and a guide that learned it would spend its
//! samples on the light instead of on the indirect light only it can find; leaving it out
//! lowered `pg`'s error on fig1 and glossy, at a small cost on fig5 (reports/README.md,
//! "Measurements formerly in code comments (2026-12-07)"). An environment's light
//! (Mitsuba's `constant`, or `envmap`) stays in the sampled directions' records: a
//! `constant`'s light samples are uniform over the sphere, and a guide that leaves it to
//! them is worse than none (measured on `scenes/mitsuba/env.xml`, same section). The sum of
//! a quadrant's records is proportional to an estimate of `∫ L_i |cos| dω` over its solid
//! angle; a quadrant's probability given its parent is its share of the parent's sum, a
//! leaf's density is uniform over its part of the square (over the sphere, that divided by
//! [`square_jacobian`]), and [`UNIFORM_SHARE`] of the square's uniform density is mixed in. Leaves without a record
//! carrying light are untrained: path tracing samples the BSDF there.
//!
//! A guided vertex draws its direction from `s · p_guide + (1 − s) · p_bsdf`, `s` the
//! material's [`guide_share`] of its region's share (`GUIDE_SHARE`, or the share learned
//! for the region with `--guide-selection learned`, see [`super::selection`]; 0 on a rough
//! dielectric), and multiple importance sampling weighs next-event estimation against that
//! density, so the estimator stays unbiased whatever was learned.
//!
//! The training also learns where light sampling is wasted: per facing and lattice cell, a
//! cell is *dark* once [`DARK_AFTER_TRIES`] light samples in one pass reached no light
//! (fig1's lower room, which sees the light only through its walls). There next-event
//! estimation runs with probability [`DARK_LIGHT_SHARE`] only, and multiple importance
//! sampling weighs it at that share of its density (so emission found by the sampled
//! direction takes nearly all the weight): still unbiased, and the shadow rays that could
//! not arrive are not traced. A dark cell turns lit when one of its light samples reaches a
//! light. This saves time wherever a region sees the light only indirectly, at the same
//! error (reports/README.md, "What changed between de6d183 and ebcb7fc", and "Measurements
//! formerly in code comments (2026-12-07)").
//!
//! In Open PGL's terms this is the `Field`; the records it is trained on are the
//! [`SampleStorage`], filled by a [`PathSegmentStorage`] along each training path, and
//! `SpatialField::build` (in `field_build.rs`) is its update.
//!
//! [`facing`]: super::lattice::facing
//! [`LATTICE_LONGEST`]: super::lattice::LATTICE_LONGEST
//! [`SPLIT_RECORDS`]: super::field_build::SPLIT_RECORDS
//! [`SPLIT_ENERGY`]: super::field_build::SPLIT_ENERGY
//! [`MIN_NODE_RECORDS`]: super::field_build::MIN_NODE_RECORDS
//! [`DARK_AFTER_TRIES`]: super::storage::DARK_AFTER_TRIES
//! [`PathSegmentStorage`]: super::PathSegmentStorage
//! [`SampleStorage`]: super::SampleStorage

use super::lattice::Lattice;
use super::square::{from_square, quadrant, square_jacobian, to_square};
use super::stats::FieldStats;
use crate::scene::Material;
use glam::Vec3;

/// Share of the sphere's uniform density in a trained leaf's density: directions the training
/// records missed keep some probability.
pub const UNIFORM_SHARE: f64 = 0.1;
/// Share of guided direction sampling at a trained vertex; the rest samples the BSDF (on a
/// rough dielectric, none: see [`guide_share`]).
///
/// A share learned per region by the second moment did not pay; the one learned by the
/// Kullback–Leibler divergence (`--guide-selection learned`, [`super::selection`]) pays on
/// some scenes and not on others (reports/pg-selection.md). Each region chose, from a grid
/// over [0.1, 0.9],
/// the share of least estimated second moment of its one-sample direction estimate
/// (`Σ (f |cos| L_i / q)² q / (α p_guide + (1 − α) p_bsdf)` over its records, drawn with
/// density `q`), and `pg`'s error at equal time rose on every scene tried, with the
/// previous pass's guide as `p_guide` and more with the new one (reports/README.md,
/// "Measurements formerly in code comments (2026-12-07)"). The vertex's own second moment
/// leaves out what the share changes beyond it: the multiple-importance weights of the
/// light the direction finds, and the later vertices of the path.
pub const GUIDE_SHARE: f64 = 0.5;

/// The share of guided direction sampling at a spatially guided vertex of `m` in a region
/// whose share is `region` ([`GUIDE_SHARE`], or the region's learned share): `region` on
/// every non-delta lobe but a rough dielectric's, where it is 0 whatever its roughness
/// ([`takes_guide`]): the BSDF alone samples there (the guide still says how often next-event
/// estimation runs). A radiance-only guide does not know the rough dielectric's lobes (the
/// reflection, and `1 − F` of the time the refraction, as narrow as its roughness, on
/// either side of the surface), so its samples mostly land where the BSDF sends little: on
/// `scenes/mitsuba/roughglass.xml` `pg`'s error falls monotonically as the share does, to
/// about `pt`'s at 0, at every roughness tried (docs/methods/pg.md, "`pg`'s guide-vs-BSDF
/// fraction").
pub fn guide_share(m: &Material, region: f64) -> f64 {
    if takes_guide(m) {
        region
    } else {
        0.0
    }
}

/// Whether the spatial guide samples directions at a vertex of `m` at all: not on a rough
/// dielectric (see [`guide_share`]).
pub fn takes_guide(m: &Material) -> bool {
    !m.transmits()
}

/// What a lookup of the spatial field finds at a point ([`SpatialField::lookup`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lookup {
    /// The trained region there, if any (its directional quadtree's root).
    pub region: Option<usize>,
    /// The probability of next-event estimation there: 1, or [`DARK_LIGHT_SHARE`] in a
    /// dark cell.
    pub light_share: f64,
    /// The region's share of guided sampling (before the material's rule, [`guide_share`]):
    /// [`GUIDE_SHARE`], or the share learned for it.
    pub share: f64,
    /// The share the densities are computed with: `share`, but [`GUIDE_SHARE`] in a field
    /// with the fault [`SpatialField::with_fixed_share_density`] (a test's wrong input).
    pub density_share: f64,
}

/// Probability of next-event estimation in a dark lattice cell: one where the training's
/// light samples never reached a light (see `SpatialField::build`).
pub const DARK_LIGHT_SHARE: f64 = 0.1;
/// The bit of a [`SpatialField`]'s region that says its cell is dark.
pub(super) const DARK: u32 = 1 << 31;

/// A node of a directional quadtree: per quadrant of its square (see [`quadrant`]), the
/// quadrant's probability given the node, and its child node (0: the quadrant is a leaf,
/// uniform inside). 32 bytes, two to a cache line: a trained guide holds very many of them
/// (reports/README.md, "Measurements formerly in code comments (2026-12-07)"), and lookups
/// wander over all.
#[derive(Clone, Copy, Debug, Default, serde::Serialize, serde::Deserialize)]
pub(super) struct QuadNode {
    pub(super) prob: [f32; 4],
    pub(super) child: [u32; 4],
}

/// The trained guide: a spatial kd-tree whose leaves hold directional quadtrees (it
/// serialises exactly, for a plan file).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct SpatialField {
    pub stats: FieldStats,
    pub(super) lattice: Lattice,
    /// Per facing and lattice cell, the root of the directional quadtree of the kd-tree leaf
    /// holding the cell (0: none), with [`DARK`] set where the cell is dark (see
    /// [`SpatialField::build`]): a lookup is one read.
    pub(super) regions: Vec<u32>,
    /// Every leaf's quadtree nodes; node 0 is unused, so that child 0 can mean "none".
    pub(super) quads: Vec<QuadNode>,
    /// Per facing and lattice cell (as `regions`), the learned share of guided sampling of
    /// the region holding the cell ([`super::selection`]); empty: [`GUIDE_SHARE`] everywhere.
    pub(super) shares: Vec<f32>,
    /// The fault of [`SpatialField::with_fixed_share_density`]: densities with
    /// [`GUIDE_SHARE`] whatever the share that samples.
    #[serde(skip)]
    pub(super) fixed_share_density: bool,
}

/// Why a spatial guide (or its training's dark cells) read from a file cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum GuideStateError {
    #[error("a spatial guide of {regions} regions for {cells} lattice cells")]
    Regions { regions: usize, cells: usize },
    #[error("a spatial guide pointing past its {nodes} nodes")]
    Nodes { nodes: usize },
    #[error("{flags} dark-cell flags for a lattice of {cells} cells")]
    DarkFlags { flags: usize, cells: usize },
    #[error("{shares} learned guide shares for {cells} lattice cells, or one outside [0, 1]")]
    Shares { shares: usize, cells: usize },
}

impl SpatialField {
    /// Checks what a lookup relies on, for a guide read from a file: a region per lattice
    /// cell and facing, and every quadtree root and child a node.
    pub fn check(&self) -> Result<(), GuideStateError> {
        let cells = self.lattice.cells() * super::lattice::FACINGS;
        if self.regions.len() != cells || self.lattice.res.contains(&0) {
            return Err(GuideStateError::Regions {
                regions: self.regions.len(),
                cells,
            });
        }
        let nodes = self.quads.len();
        let roots = self.regions.iter().map(|r| (r & !DARK) as usize);
        let children = self.quads.iter().flat_map(|q| q.child.map(|c| c as usize));
        if roots.chain(children).any(|i| i >= nodes) {
            return Err(GuideStateError::Nodes { nodes });
        }
        let shares = self.shares.len();
        if !(shares == 0 || shares == cells) || !self.shares.iter().all(|s| (0.0..=1.0).contains(s))
        {
            return Err(GuideStateError::Shares { shares, cells });
        }
        Ok(())
    }

    #[cfg(any(test, feature = "testing"))]
    /// This guide with a deliberate fault: its regions sample with their learned shares, but
    /// every density is computed with [`GUIDE_SHARE`] (a test's wrong input, which must bias
    /// the estimate wherever a learned share is not 1/2).
    pub fn with_fixed_share_density(mut self) -> Self {
        self.fixed_share_density = true;
        self
    }

    /// Whether this guide has learned a share of guided sampling per region.
    pub fn learned_shares(&self) -> bool {
        !self.shares.is_empty()
    }

    #[cfg(any(test, feature = "testing"))]
    /// This guide with every cell dark: next-event estimation at [`DARK_LIGHT_SHARE`]
    /// everywhere, where light arrives too (the estimator must stay unbiased there: a test
    /// of its weights).
    pub fn with_every_cell_dark(mut self) -> Self {
        self.regions.iter_mut().for_each(|r| *r |= DARK);
        self
    }

    /// The trained region at `p` on a surface of normal `n`, if any (its directional
    /// quadtree's root), and the probability of next-event estimation there: 1, or
    /// [`DARK_LIGHT_SHARE`] in a dark cell.
    pub fn at(&self, p: Vec3, n: Vec3) -> (Option<usize>, f64) {
        let found = self.lookup(p, n);
        (found.region, found.light_share)
    }

    /// What the field holds at `p` on a surface of normal `n`: the trained region, the
    /// probability of next-event estimation and the region's share of guided sampling.
    pub fn lookup(&self, p: Vec3, n: Vec3) -> Lookup {
        let i = self.lattice.index_facing(p, n);
        let region = self.regions[i];
        let share = self.shares.get(i).map_or(GUIDE_SHARE, |&s| f64::from(s));
        Lookup {
            region: match region & !DARK {
                0 => None,
                root => Some(root as usize),
            },
            light_share: if region & DARK != 0 {
                DARK_LIGHT_SHARE
            } else {
                1.0
            },
            share,
            density_share: if self.fixed_share_density {
                GUIDE_SHARE
            } else {
                share
            },
        }
    }

    /// The solid-angle density of region `cell`'s guide for unit `wi`.
    pub fn pdf(&self, cell: usize, wi: Vec3) -> f64 {
        self.density(self.square_pdf(cell, to_square(wi)), wi)
    }

    /// The solid-angle density of unit `wi`, whose leaf has the square density `leaf`, with
    /// the uniform share mixed in.
    fn density(&self, leaf: f64, wi: Vec3) -> f64 {
        ((1.0 - UNIFORM_SHARE) * leaf + UNIFORM_SHARE) / square_jacobian(wi)
    }

    /// The density over the square of region `cell`'s quadtree at `(u, v)`.
    fn square_pdf(&self, cell: usize, [mut u, mut v]: [f32; 2]) -> f64 {
        let mut node = cell;
        let mut p = 1.0f64;
        loop {
            let n = &self.quads[node];
            let q;
            (q, u, v) = quadrant(u, v);
            p *= 4.0 * f64::from(n.prob[q]);
            match n.child[q] {
                0 => break,
                c => node = c as usize,
            }
        }
        p
    }

    /// A direction from region `cell`'s density, from three uniform numbers, and its
    /// solid-angle density (the leaf's, found on the way down).
    pub fn sample(&self, cell: usize, u: [f64; 3]) -> (Vec3, f64) {
        if u[0] < UNIFORM_SHARE {
            let wi = from_square(u[1], u[2]);
            return (wi, self.pdf(cell, wi));
        }
        let mut r = ((u[0] - UNIFORM_SHARE) / (1.0 - UNIFORM_SHARE)).clamp(0.0, 1.0);
        let (mut x, mut y, mut size) = (0.0f64, 0.0f64, 1.0f64);
        let mut leaf = 1.0f64;
        let mut node = cell;
        loop {
            let n = &self.quads[node];
            // The quadrant whose cumulative probability passes `r`, without branches
            // (rounding past the end takes the last quadrant with any probability).
            let p = n.prob.map(f64::from);
            let cdf = [0.0, p[0], p[0] + p[1], p[0] + p[1] + p[2]];
            let mut q = cdf[1..].iter().map(|&c| usize::from(r >= c)).sum::<usize>();
            while q > 0 && p[q] <= 0.0 {
                q -= 1;
            }
            r = ((r - cdf[q]) / p[q]).clamp(0.0, 1.0);
            leaf *= 4.0 * p[q];
            size *= 0.5;
            x += size * (q & 1) as f64;
            y += size * (q >> 1) as f64;
            match n.child[q] {
                0 => break,
                c => node = c as usize,
            }
        }
        let wi = from_square(x + size * u[1], y + size * u[2]);
        (wi, self.density(leaf, wi))
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::guiding::field_build::SPLIT_RECORDS;
    use crate::guiding::storage::Record;
    use crate::sampling::{sample_rng, uniform};
    use std::f64::consts::PI;

    /// A field trained on 4100 records at the origin, on a floor (facing +y), spread over a
    /// square of side 1/16 of the square map at `target`'s square-map point (returned too).
    pub(crate) fn trained_around(target: Vec3) -> (SpatialField, [f32; 2]) {
        let [tu, tv] = to_square(target);
        let mut rng = sample_rng(8, 0, 0);
        let records: Vec<Record> = (0..4100)
            .map(|i| Record {
                p: Vec3::ZERO,
                facing: 2,
                dir: [tu + uniform(&mut rng) / 16.0, tv + uniform(&mut rng) / 16.0],
                value: 1.0 + (i % 3) as f32,
            })
            .collect();
        let field = SpatialField::train(Vec3::splat(-1.0), Vec3::ONE, records);
        (field, [tu, tv])
    }

    fn uniforms(rng: &mut crate::sampling::Rng) -> [f64; 3] {
        [0; 3].map(|_| f64::from(uniform(rng)))
    }

    /// A guide trained on records bunched around two directions and spread over the rest,
    /// in one region of the box `[0, 1]³`.
    fn trained() -> SpatialField {
        let mut rng = sample_rng(4, 0, 0);
        let records = (0..SPLIT_RECORDS).map(|i| {
            let [a, b, c] = uniforms(&mut rng);
            let dir = match i % 4 {
                0 => [0.3 + 0.01 * a as f32, 0.7 + 0.003 * b as f32],
                1 => [0.8 + 0.05 * a as f32, 0.1 + 0.05 * b as f32],
                _ => [a as f32, b as f32],
            };
            Record {
                p: Vec3::splat(0.5),
                facing: 2,
                dir,
                value: 0.5 + c as f32,
            }
        });
        SpatialField::train(Vec3::ZERO, Vec3::ONE, records)
    }

    #[test]
    fn quadtree_refines_where_the_light_is() {
        let guide = trained();
        assert_eq!(guide.stats.trained_cells, 1);
        assert!(guide.at(Vec3::splat(0.5), -Vec3::Y).0.is_none());
        let cell = guide.at(Vec3::splat(0.5), Vec3::Y).0.unwrap();
        // A quarter of the light in 3e-5 of the square: the density there is that of the
        // finest leaf (4^-5 of the square), a quarter of 1024 times the mean, and the spread
        // records' quadrants stay coarse.
        let bright = guide.pdf(cell, from_square(0.305, 0.7015)) * 4.0 * PI;
        let dim = guide.pdf(cell, from_square(0.5, 0.3)) * 4.0 * PI;
        assert!(bright > 200.0, "density {bright} at the narrow bunch");
        assert!(
            (0.3..1.0).contains(&dim),
            "density {dim} among the spread records"
        );
        assert!(guide.stats.directional_nodes < 400, "{:?}", guide.stats);
    }

    #[test]
    fn density_integrates_to_one_and_matches_samples() {
        let guide = trained();
        let cell = guide.at(Vec3::splat(0.5), Vec3::Y).0.unwrap();
        // ∫ p dω by sampling directions from the guide itself: E[1 / p] over its samples is
        // the solid angle where p > 0, the whole sphere.
        let mut rng = sample_rng(3, 0, 0);
        let n = 200_000;
        let mut inverse = 0.0;
        // Frequencies of a coarse 16 × 16 histogram of the square against each of its cells'
        // probability, from the quadtree's leaves (and the uniform share).
        let mut hits = vec![0u32; 256];
        // Samples whose density from the descent that drew them differs from `pdf`'s (a
        // rounding at a leaf's edge may move a direction into the neighbouring leaf).
        let mut mismatched = 0;
        for _ in 0..n {
            let (d, pdf) = guide.sample(cell, uniforms(&mut rng));
            inverse += 1.0 / pdf;
            mismatched += usize::from((guide.pdf(cell, d) - pdf).abs() > 1e-6 * pdf);
            let [u, v] = to_square(d);
            hits[((u * 16.0) as usize).min(15) * 16 + ((v * 16.0) as usize).min(15)] += 1;
        }
        assert!(
            mismatched <= n / 1000,
            "{mismatched} densities differ from pdf's"
        );
        let sphere = inverse / n as f64;
        assert!(
            (sphere / (4.0 * PI) - 1.0).abs() < 0.01,
            "∫ 1 dω = {sphere}"
        );
        let mut expected = vec![UNIFORM_SHARE / 256.0; 256];
        for (x, y, size, p) in leaves(&guide, cell) {
            for (c, e) in expected.iter_mut().enumerate() {
                let (cu, cv) = ((c / 16) as f64 / 16.0, (c % 16) as f64 / 16.0);
                let overlap = |a: f64, b: f64| (a + size).min(b + 1.0 / 16.0) - a.max(b);
                let area = overlap(x, cu).max(0.0) * overlap(y, cv).max(0.0);
                *e += (1.0 - UNIFORM_SHARE) * p * area / (size * size);
            }
        }
        let total: f64 = expected.iter().sum();
        assert!((total - 1.0).abs() < 1e-3, "∫ p = {total}");
        let worst = |scale: f64| {
            (0..256)
                .map(|c| {
                    let e = scale * expected[c] * n as f64;
                    (hits[c] as f64 - e).abs() / e.sqrt().max(1.0)
                })
                .fold(0.0, f64::max)
        };
        assert!(worst(1.0) < 5.0, "max |z| {}", worst(1.0));
        // The same check rejects probabilities off by 5 %.
        assert!(worst(1.05) > 5.0, "max |z| {} off by 5 %", worst(1.05));
    }

    /// The leaves of region `cell`'s quadtree: their squares `(u, v, side)` and probabilities.
    fn leaves(guide: &SpatialField, cell: usize) -> Vec<(f64, f64, f64, f64)> {
        let mut out = Vec::new();
        let mut stack = vec![(cell, 0.0, 0.0, 1.0, 1.0)];
        while let Some((node, x, y, size, p)) = stack.pop() {
            let n = &guide.quads[node];
            for q in 0..4 {
                let h = size / 2.0;
                let (qx, qy) = (x + h * (q & 1) as f64, y + h * (q >> 1) as f64);
                let pq = p * f64::from(n.prob[q]);
                match n.child[q] {
                    0 => out.push((qx, qy, h, pq)),
                    c => stack.push((c as usize, qx, qy, h, pq)),
                }
            }
        }
        out
    }

    /// A cell turns dark after enough light tries of which none reached a light, stays
    /// dark while no try reaches one, and turns lit when one does; a cell with too few tries

    #[test]
    fn space_splits_where_records_are() {
        // Records at two points far apart, more than one leaf can hold: the regions split
        // and each learns its own direction.
        let records = (0..2 * SPLIT_RECORDS + 2).map(|i| {
            let left = i % 2 == 0;
            Record {
                p: if left {
                    Vec3::splat(0.1)
                } else {
                    Vec3::splat(0.9)
                },
                facing: 0,
                dir: if left { [0.2, 0.2] } else { [0.8, 0.8] },
                value: 1.0,
            }
        });
        let guide = SpatialField::train(Vec3::ZERO, Vec3::ONE, records);
        assert!(guide.stats.cells > 1, "{:?}", guide.stats);
        let (a, b) = (
            guide.at(Vec3::splat(0.1), Vec3::X).0.unwrap(),
            guide.at(Vec3::splat(0.9), Vec3::X).0.unwrap(),
        );
        // The same place facing another way has no records.
        assert!(guide.at(Vec3::splat(0.9), -Vec3::X).0.is_none());
        assert_ne!(a, b);
        let (da, db) = (from_square(0.2, 0.2), from_square(0.8, 0.8));
        assert!(guide.pdf(a, da) > 100.0 * guide.pdf(a, db));
        assert!(guide.pdf(b, db) > 100.0 * guide.pdf(b, da));
        // Nothing recorded: untrained.
        let empty = SpatialField::train(Vec3::ZERO, Vec3::ONE, []);
        assert!(empty.at(Vec3::splat(0.5), Vec3::Y).0.is_none());
    }
}
