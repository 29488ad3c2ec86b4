//! The share of guided sampling per region (`--guide-selection learned`): the probability
//! `α` with which a spatially guided vertex draws its direction from the region's guide
//! rather than from the BSDF, learned per region of the [`SpatialField`] from the training
//! records of the pass that built it, instead of the fixed [`GUIDE_SHARE`].
//!
//! A vertex samples `p_α = α p_guide + (1 − α) p_bsdf`. The share of a region minimises the
//! Kullback–Leibler divergence from the light the region's vertices reflect,
//! `F(ω) = f(ω) L_i(ω) |cos ω|` (normalised), to `p_α`: as the improvements to "Practical
//! Path Guiding" (Müller 2019, "Practical Path Guiding in Production") do per spatial leaf,
//! there by stochastic gradient descent while rendering. The loss
//! `−Σ F_j / q_j · log p_α(ω_j)` over the records `ω_j` (drawn with the density `q_j` of
//! their pass) is convex in `α`, its derivative `Σ F_j / q_j · (p_bsdf − p_guide) / p_α`
//! rises with `α`, so the share is found by bisection over the records in a fixed order:
//! the same share for any thread count, from the same records a plan file's guide was
//! built from. The divergence rather than the second moment of the one-sample estimate
//! `F / p_α`: the second moment weighs each record by `F² / q`, so that a few bright
//! records decide a region's share, and a share fitted that way per region was measured to
//! lose (see [`GUIDE_SHARE`]); the divergence weighs them by `F / q`.
//!
//! `p_guide` is the density of the guide that drew the records (the previous pass's), as in
//! Müller's online fit, whose records were drawn by the guide being fitted against: the new
//! guide, built from the same records, would look better on them than it is. A region's
//! records are those of the sampled directions whose vertex it holds in the new field and
//! whose vertex the previous guide sampled (a region of it, beside a BSDF that takes a
//! guide), with light `F > 0`. With fewer than [`MIN_FIT_RECORDS`] of them, the region
//! keeps [`GUIDE_SHARE`].
//!
//! The share is clamped to [`MIN_SHARE`]`..=`[`MAX_SHARE`], 0.1 to 1/2: a region may learn
//! to leave its directions to the BSDF (where the guide, which knows nothing of the BSDF,
//! sends them where a glossy lobe reflects little), never to sample its guide more than the
//! fixed share does. The fixed share bounds a BSDF-sampled direction's weight
//! `f |cos| / p_α` to twice the BSDF's own, wherever the guide has no density; a guide
//! learned from one pass's records misses rare paths that carry much light, which the
//! records, and so the fit, seldom hold. Fitted up to 0.9, the shares rose to the bound
//! nearly everywhere on diffuse surfaces (fig5 at 64², 1024 spp: 274 of 328 regions), and
//! `pg`'s error at equal time rose 1.40 × on fig5, 1.15 × on gap and 1.09 × on shelf
//! (reports/pg-selection.md). The guide keeps a tenth at least, so that the next pass still
//! draws records from it.
//!
//! Unbiasedness does not depend on the share: sampling and every density (the sampled
//! direction's, the one multiple importance sampling weighs next-event estimation against,
//! and that of a direction which finds a light) use the same `α` of the vertex's region
//! ([`super::Vertex`]), looked up once per vertex.

use super::field::{SpatialField, DARK, GUIDE_SHARE};
use super::stats::SelectionStats;
use glam::Vec3;
use rayon::prelude::*;

/// The least and the largest share of guided sampling a region may learn (see the module
/// documentation).
pub const MIN_SHARE: f64 = 0.1;
pub const MAX_SHARE: f64 = GUIDE_SHARE;
/// A region learns its share from at least this many records (below, [`GUIDE_SHARE`]).
pub const MIN_FIT_RECORDS: usize = 32;
/// Bisection steps of the fit: the share to `0.8 / 2^20`.
const BISECTIONS: u32 = 20;

/// How the share of guided sampling is set per region (`--guide-selection`).
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    serde::Serialize,
    serde::Deserialize,
    clap::ValueEnum,
)]
#[serde(rename_all = "lowercase")]
pub enum Selection {
    /// [`GUIDE_SHARE`] everywhere.
    #[default]
    Fixed,
    /// Learned per region from the training records.
    Learned,
}

/// What a region's share is learned from: one sampled direction of a training path at a
/// vertex the guide sampled (at `p`, facing `facing`), with `product`, its
/// `f L_i |cos| / q` (luminance), and the guide's and the BSDF's densities along it.
#[derive(Clone, Copy, Debug)]
pub struct SelectionRecord {
    pub p: Vec3,
    pub facing: u8,
    pub product: f32,
    pub guide_pdf: f32,
    pub bsdf_pdf: f32,
}

/// The share of least Kullback–Leibler divergence (see the module documentation) for
/// records of `(F / q, p_guide, p_bsdf)`, in [`MIN_SHARE`]`..=`[`MAX_SHARE`]; `None` with
/// fewer than [`MIN_FIT_RECORDS`] records.
pub fn fit_share(records: &[(f64, f64, f64)]) -> Option<f64> {
    if records.len() < MIN_FIT_RECORDS {
        return None;
    }
    // The loss's derivative in `α`, rising with it.
    let slope = |a: f64| -> f64 {
        records
            .iter()
            .map(|&(w, g, b)| w * (b - g) / (a * g + (1.0 - a) * b))
            .sum()
    };
    let (mut lo, mut hi) = (MIN_SHARE, MAX_SHARE);
    if slope(lo) >= 0.0 {
        return Some(lo);
    }
    if slope(hi) <= 0.0 {
        return Some(hi);
    }
    for _ in 0..BISECTIONS {
        let mid = 0.5 * (lo + hi);
        if slope(mid) > 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    Some(0.5 * (lo + hi))
}

impl SpatialField {
    /// Learns each region's share of guided sampling from `records` (see the module
    /// documentation): the regions are this field's, the densities the previous guide's.
    pub(super) fn learn_shares(&mut self, records: &[SelectionRecord]) {
        // (region, record) for every usable record, in a total order: the fit does not
        // depend on the order records came in.
        let mut keyed: Vec<(u32, u32)> = records
            .iter()
            .enumerate()
            .filter(|(_, r)| {
                let ok = |x: f32| x.is_finite() && x >= 0.0;
                ok(r.product) && ok(r.guide_pdf) && ok(r.bsdf_pdf) && r.guide_pdf + r.bsdf_pdf > 0.0
            })
            .filter_map(|(i, r)| {
                let cell = self.lattice.index_in(r.p, usize::from(r.facing));
                let root = self.regions[cell] & !DARK;
                (root != 0).then_some((root, i as u32))
            })
            .collect();
        keyed.sort_unstable();
        let groups: Vec<&[(u32, u32)]> = keyed.chunk_by(|a, b| a.0 == b.0).collect();
        let fitted: Vec<(u32, Option<f64>, usize)> = groups
            .par_iter()
            .map(|group| {
                let triples: Vec<(f64, f64, f64)> = group
                    .iter()
                    .map(|&(_, i)| {
                        let r = &records[i as usize];
                        (
                            f64::from(r.product),
                            f64::from(r.guide_pdf),
                            f64::from(r.bsdf_pdf),
                        )
                    })
                    .collect();
                (group[0].0, fit_share(&triples), group.len())
            })
            .collect();
        let share_of = |root: u32| {
            fitted
                .binary_search_by_key(&root, |f| f.0)
                .ok()
                .and_then(|i| fitted[i].1)
                .unwrap_or(GUIDE_SHARE)
        };
        self.shares = (self.regions.iter())
            .map(|&r| share_of(r & !DARK) as f32)
            .collect();
        self.stats.selection = Some(selection_stats(&fitted, self.stats.trained_cells));
    }
}

/// The statistics of the shares `fitted` per region (with their records' counts) of a
/// field of `regions` trained regions.
fn selection_stats(fitted: &[(u32, Option<f64>, usize)], regions: usize) -> SelectionStats {
    let mut stats = SelectionStats {
        regions,
        ..SelectionStats::default()
    };
    let (mut sum, mut sum_records, mut records) = (0.0, 0.0, 0usize);
    for &(_, share, n) in fitted {
        let Some(s) = share else { continue };
        stats.fitted += 1;
        stats.at_min += usize::from(s <= MIN_SHARE);
        stats.at_max += usize::from(s >= MAX_SHARE);
        sum += s;
        sum_records += s * n as f64;
        records += n;
        let bin = ((s - MIN_SHARE) / (MAX_SHARE - MIN_SHARE) * 8.0) as usize;
        stats.histogram[bin.min(7)] += 1;
        stats.histogram_records[bin.min(7)] += n;
    }
    if stats.fitted > 0 {
        stats.mean = sum / stats.fitted as f64;
        stats.mean_per_record = sum_records / records as f64;
    }
    stats
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{sample_rng, uniform};

    /// Records of a region whose light arrives from two small caps of the sphere, `a` of it
    /// from cap A and the rest from cap B, where the guide's density is sharp on A (it found
    /// A) and the BSDF's on B; directions drawn half from each, as the fixed share draws
    /// them.
    fn records(a: f64) -> Vec<(f64, f64, f64)> {
        let sphere = 4.0 * std::f64::consts::PI;
        let cap = 0.05;
        // A sharp density: 0.95 of its mass uniform on its cap, the rest on the sphere.
        let sharp = |on_cap: bool| 0.05 / sphere + if on_cap { 0.95 / cap } else { 0.0 };
        let mut rng = sample_rng(12, 0, 0);
        (0..4000)
            .filter_map(|_| {
                let by_guide = uniform(&mut rng) < 0.5;
                // The cap the direction lands on (0: A, 1: B, 2: neither).
                let landed = if uniform(&mut rng) < 0.95 {
                    usize::from(!by_guide)
                } else {
                    match f64::from(uniform(&mut rng)) * sphere {
                        u if u < cap => 0,
                        u if u < 2.0 * cap => 1,
                        _ => 2,
                    }
                };
                let (g, b) = (sharp(landed == 0), sharp(landed == 1));
                let light = [a / cap, (1.0 - a) / cap, 0.0][landed];
                (light > 0.0).then(|| (light / (0.5 * g + 0.5 * b), g, b))
            })
            .collect()
    }

    /// Where the guide found all the light, or most of it, the share goes to its upper
    /// bound; where the BSDF's density is the light's, to its lower bound; in between, it
    /// follows the share of the light the guide found.
    #[test]
    fn shares_move_towards_the_better_technique() {
        let share = |a: f64| fit_share(&records(a)).unwrap();
        let fitted = [1.0, 0.7, 0.0, 0.4, 0.25].map(share);
        eprintln!("{fitted:?}");
        assert_eq!(fitted[0], MAX_SHARE);
        assert_eq!(fitted[1], MAX_SHARE);
        assert_eq!(fitted[2], MIN_SHARE);
        assert!((fitted[3] - 0.4).abs() < 0.05, "{}", fitted[3]);
        assert!((fitted[4] - 0.25).abs() < 0.05, "{}", fitted[4]);
        // Too few records: no share.
        assert_eq!(fit_share(&records(1.0)[..MIN_FIT_RECORDS - 1]), None);
    }
}
