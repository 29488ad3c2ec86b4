//! The directional part of an evolved mixture as a guide for path tracing (`--method ga-pt`,
//! beyond the paper).
//!
//! The paper's estimator (eq. 8) samples whole paths and connects to a light only at the
//! path's end. Path tracing connects at every vertex and weights light sampling against
//! direction sampling by multiple importance sampling; what the genetic algorithm learned —
//! where light arrives from, as anchor cones per vertex — can replace its BSDF sampling.
//! At the `k`-th non-delta vertex the guide samples a direction from
//!
//! ```text
//! p_k(ω) = w_brdf,k · p_brdf(ω) + Σ_j w_j,k · p_j(ω)
//! ```
//!
//! the `k`-th directional samplers of the mixture's generators (anchor cones and patches),
//! each with its generator's weight (a generator without a `k`-th step, and the defensive
//! `srt` one, count as BRDF sampling). The weights sum to 1 and every cone and patch sampler
//! covers the whole sphere, so `p_k` is a density wherever the BSDF is non-zero: the
//! estimator stays unbiased. With `pg`'s spatial guide (`ga-pt`'s default), `p_brdf` is
//! replaced where the guide has learned something by what `pg` samples there, `GUIDE_SHARE
//! · p_spatial + (1 − GUIDE_SHARE) · p_brdf`, itself a density, and the vertices past the
//! levels sample that alone. Absorptions and light samplers of the generators are not
//! used: path length is path tracing's (Russian roulette), light points are sampled by
//! area.

use super::field::{SpatialField, GUIDE_SHARE};
use super::level::Level;
use super::vertex::{GuideSample, Vertex, VertexSampler};
use crate::path::generator::DirectionSampler;
use crate::path::mixture::Mixture;
use crate::sampling::anchor::AnchorSampler;
use crate::sampling::patch::PatchSampler;
use crate::scene::material::bsdf::Frame;
use crate::scene::MaterialAt;
use glam::Vec3;
use std::sync::Arc;

/// Adds `weight` to `sampler`'s entry of `list`, or appends it: a sampler that several
/// generators share is evaluated once.
fn merge<T: PartialEq + Copy>(list: &mut Vec<(f64, T)>, weight: f64, sampler: &T) {
    match list.iter_mut().find(|(_, s)| s == sampler) {
        Some((w, _)) => *w += weight,
        None => list.push((weight, *sampler)),
    }
}

/// Per vertex index, the weighted directional samplers of a mixture.
#[derive(Clone, Debug, Default)]
pub struct Guide {
    levels: Vec<Level>,
    /// Levels in use; `levels` may keep the storage of an earlier, deeper guide.
    depth: usize,
    /// Scratch of [`Self::rebuild`]: one level's cones and patches and their summed weights.
    cones: Vec<(f64, AnchorSampler)>,
    patches: Vec<(f64, PatchSampler)>,
    /// Fault injection for statistical tests: scales the cones' and patches' densities when
    /// evaluated.
    pdf_error: Option<f64>,
    /// Beyond the levels: the spatial guide, where it has learned something.
    spatial: Option<Arc<SpatialField>>,
}

impl Guide {
    /// The guide of `mixture`, whose weights are taken as they are. A cone or patch that
    /// several generators share at one level (neighbours that adopted one another's individuals,
    /// generators that differ only later) becomes one sampler with the summed weight: the
    /// same density, evaluated once.
    pub fn new(mixture: &Mixture) -> Self {
        let mut guide = Self::default();
        guide.rebuild(&[(1.0, mixture)]);
        guide
    }

    /// This guide remade as the guide of the union of `parts`, mixture `m` scaled by `w`
    /// ([`Mixture::union`] without building it), reusing its storage: the renderer makes
    /// one guide per pixel from its neighbours' mixtures.
    pub fn rebuild(&mut self, parts: &[(f64, &Mixture)]) {
        let generators = || {
            parts.iter().flat_map(|&(w, m)| {
                m.generators
                    .iter()
                    .zip(&m.weights)
                    .map(move |(g, &wg)| (g, w * wg))
            })
        };
        let depth = generators().map(|(g, _)| g.steps.len()).max().unwrap_or(0);
        if self.levels.len() < depth {
            self.levels.resize_with(depth, Level::default);
        }
        // Levels where everything samples the BRDF are left out at the end: beyond
        // `depth`, the guide is BRDF sampling.
        self.depth = 0;
        for k in 0..depth {
            self.cones.clear();
            self.patches.clear();
            let mut brdf = 0.0;
            for (g, w) in generators() {
                match g.steps.get(k).map(|s| &s.sampler) {
                    Some(DirectionSampler::Anchor(a)) => merge(&mut self.cones, w, a),
                    Some(DirectionSampler::Patch(p)) => merge(&mut self.patches, w, p),
                    Some(DirectionSampler::Brdf) | None => brdf += w,
                }
            }
            let level = &mut self.levels[k];
            level.brdf = brdf;
            level.set(&self.cones, &self.patches);
            if level.guides() {
                self.depth = k + 1;
            }
        }
    }

    /// The samplers of vertex `k`, where the guide has more than BRDF sampling.
    fn level(&self, k: usize) -> Option<&Level> {
        self.levels[..self.depth].get(k)
    }

    #[cfg(any(test, feature = "testing"))]
    /// This guide with every cone and patch density scaled by `factor` when evaluated (not when
    /// sampled): a wrong input that unbiasedness tests must reject.
    pub fn with_pdf_error(mut self, factor: f64) -> Self {
        self.pdf_error = Some(factor);
        self
    }

    /// This guide with `spatial` guiding the vertices beyond its levels.
    pub fn with_spatial(mut self, spatial: Option<Arc<SpatialField>>) -> Self {
        self.spatial = spatial;
        self
    }

    /// Whether vertex `k` may sample anything but the BRDF.
    pub fn guides(&self, k: usize) -> bool {
        k < self.depth || self.spatial.is_some()
    }

    /// What guides the `k`-th non-delta vertex at `x` (normal `n`): its level, the spatial
    /// guide's region there, or the BRDF alone. Looked up once per vertex, used for every
    /// density and sample there. The spatial guide says how often next-event estimation
    /// runs there, at every vertex, and at a level's vertex it samples the level's BRDF
    /// share as past the levels: the GA's cones and patches add to what `pg` would sample
    /// there instead of replacing it, since replacing it left glossy far noisier than `pg`
    /// (reports/README.md, "What changed between ebcb7fc and c0f2981"). At the path's
    /// `last` vertex it does not guide the direction: that direction can only find
    /// emission, which next-event estimation finds better, and the quadtree's descents
    /// would cost for nothing.
    pub fn at(&self, k: usize, x: Vec3, frame: Frame, last: bool) -> Vertex<'_> {
        let (spatial, found) = match self.spatial.as_deref() {
            Some(s) => {
                let found = s.lookup(x, frame.n);
                (
                    found.region.filter(|_| !last).map(|cell| (s, cell)),
                    Some(found),
                )
            }
            None => (None, None),
        };
        let light_share = found.map_or(1.0, |f| f.light_share);
        let share = found.map_or(GUIDE_SHARE, |f| f.share);
        let density_share = found.map_or(GUIDE_SHARE, |f| f.density_share);
        let sampler = match (self.level(k), spatial) {
            (Some(level), spatial) => VertexSampler::Level(level, spatial),
            (None, Some((s, cell))) => VertexSampler::Spatial(s, cell),
            (None, None) => VertexSampler::Brdf,
        };
        Vertex {
            sampler,
            light_share,
            scale: self.pdf_error.unwrap_or(1.0),
            share,
            density_share,
            x: x.as_dvec3(),
            frame,
        }
    }

    /// `p_k(wi)` at the surface point `x` of `material` (shading frame facing `wo`).
    pub fn pdf<'m>(
        &self,
        k: usize,
        material: impl Into<MaterialAt<'m>>,
        x: Vec3,
        frame: Frame,
        wo: Vec3,
        wi: Vec3,
    ) -> f64 {
        self.at(k, x, frame, false).pdf(material, wo, wi)
    }

    /// A direction out of the `k`-th non-delta vertex `x`, from four uniform numbers (see
    /// [`Vertex::sample`]).
    pub fn sample<'m>(
        &self,
        k: usize,
        material: impl Into<MaterialAt<'m>>,
        x: Vec3,
        frame: Frame,
        wo: Vec3,
        u: [f64; 4],
    ) -> Option<GuideSample> {
        self.at(k, x, frame, false).sample(material, wo, u)
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::guiding::field::GUIDE_SHARE;
    use crate::path::generator::{PathGenerator, Step};
    use crate::sampling::light_point::LightPointSampler;
    use crate::sampling::{sample_rng, uniform};
    use glam::DVec3;

    pub(in crate::guiding) fn mixture() -> Mixture {
        let light = LightPointSampler::uniform(0);
        let anchor = |p: DVec3, theta_c| Step {
            sampler: DirectionSampler::Anchor(AnchorSampler::new(p, theta_c, 0.8).unwrap()),
            absorption: 0.5,
        };
        let guided = PathGenerator {
            steps: vec![
                anchor(DVec3::new(1.0, 2.0, 0.0), 0.2),
                anchor(DVec3::Y, 0.5),
            ],
            light,
        };
        let patched = PathGenerator {
            steps: vec![Step {
                sampler: DirectionSampler::Patch(PATCH),
                absorption: 0.5,
            }],
            light,
        };
        Mixture::new(
            vec![PathGenerator::srt(3, 0.5, light), guided, patched],
            vec![0.3, 0.5, 0.2],
        )
    }

    /// The patch of [`mixture`]: above the origin, seen from there about 35° off its normal.
    pub(in crate::guiding) const PATCH: PatchSampler = PatchSampler {
        center: DVec3::new(-1.0, 1.5, 0.5),
        half_u: DVec3::new(0.5, 0.0, 0.0),
        half_v: DVec3::new(0.0, 0.0, 0.4),
        alpha: 0.9,
    };

    /// A mixture of `count` one-step generators with anchors on a ring of radius 2 around
    /// the origin, cone angles from 0.05 to 2.9 rad (narrow and wide cones), plus `srt`.
    fn ring(count: usize, seed: u64) -> Mixture {
        let light = LightPointSampler::uniform(0);
        let mut rng = sample_rng(seed, 0, 0);
        let mut generators = vec![PathGenerator::srt(3, 0.5, light)];
        for i in 0..count {
            let phi = i as f64 * 2.4;
            let anchor = DVec3::new(2.0 * phi.cos(), 1.0, 2.0 * phi.sin());
            let theta_c = 0.05 + 2.85 * uniform(&mut rng) as f64;
            generators.push(PathGenerator {
                steps: vec![Step {
                    sampler: DirectionSampler::Anchor(
                        AnchorSampler::new(anchor, theta_c, 0.7).unwrap(),
                    ),
                    absorption: 0.5,
                }],
                light,
            });
        }
        let weights = (0..=count).map(|i| 1.0 + i as f64).collect();
        Mixture::new(generators, weights)
    }

    /// The largest relative difference of `a`'s and `b`'s level-0 densities over random
    /// directions from points near the origin, one of them on an anchor (where the cone
    /// test takes its degenerate branch).
    fn max_difference(a: &Guide, b: &Guide) -> f64 {
        let mut rng = sample_rng(8, 0, 0);
        let mut worst: f64 = 0.0;
        let on_anchor = DVec3::new(2.0, 1.0, 0.0);
        for i in 0..20_000 {
            let x = if i % 10 == 0 {
                on_anchor
            } else {
                DVec3::new(uniform(&mut rng) as f64, 0.0, uniform(&mut rng) as f64)
            };
            let z = 1.0 - 2.0 * uniform(&mut rng) as f64;
            let phi = std::f64::consts::TAU * uniform(&mut rng) as f64;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let wi = DVec3::new(r * phi.cos(), z, r * phi.sin());
            let (pa, pb) = (
                a.at(0, x.as_vec3(), Frame::new(Vec3::Y, Vec3::ZERO), false)
                    .pdf_with(wi, 0.3, GUIDE_SHARE),
                b.at(0, x.as_vec3(), Frame::new(Vec3::Y, Vec3::ZERO), false)
                    .pdf_with(wi, 0.3, GUIDE_SHARE),
            );
            worst = worst.max((pa - pb).abs() / pa.max(pb));
        }
        worst
    }

    /// A guide rebuilt in the storage of a deeper one against a fresh guide of the union.
    #[test]
    fn rebuilt_guides_agree_with_a_fresh_guide_of_the_union() {
        let (m1, m2) = (ring(7, 1), ring(6, 2));
        // A guide rebuilt from parts, in storage that held a two-level guide.
        let mut rebuilt = Guide::new(&mixture());
        rebuilt.rebuild(&[(0.25, &m1), (0.75, &m2)]);
        let fresh = Guide::new(&Mixture::union(&[(0.25, &m1), (0.75, &m2)]));
        let samplers = |g: &Guide| {
            g.at(0, Vec3::ZERO, Frame::new(Vec3::Y, Vec3::ZERO), false)
                .samplers()
        };
        assert!(!rebuilt.guides(1) && samplers(&rebuilt) == samplers(&fresh));
        let same = max_difference(&rebuilt, &fresh);
        assert!(same < 1e-12, "rebuilt guide differs by {same}");
        // The comparison tells other weights apart.
        let mut other = Guide::default();
        other.rebuild(&[(0.5, &m1), (0.5, &m2)]);
        let different = max_difference(&other, &fresh);
        assert!(different > 0.05, "other weights differ by only {different}");
    }
}
