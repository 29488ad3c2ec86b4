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

use super::generator::DirectionSampler;
use super::mixture::Mixture;
use super::spatial::{SpatialGuide, GUIDE_SHARE};
use crate::sampling::anchor::{AnchorSampler, ConeTest};
use crate::sampling::brdf;
use crate::sampling::patch::{PatchSampler, PatchShape};
use crate::scene::Material;
use glam::{DVec3, Vec3};
use std::sync::Arc;

/// One weighted anchor cone of a level, with what its density and its sampling need
/// precomputed: the guide evaluates every cone of a level twice per vertex (light sample and
/// guided sample).
#[derive(Clone, Copy, Debug)]
struct GuideAnchor {
    weight: f64,
    sampler: AnchorSampler,
    /// [`AnchorSampler::extents`], computed once.
    extents: (f64, f64),
    /// `weight · p1`, `weight · p2` and the sampler's cone test.
    inside: f64,
    outside: f64,
    test: ConeTest,
}

impl GuideAnchor {
    fn new(weight: f64, sampler: AnchorSampler) -> Self {
        // One sin_cos for all three: the guide makes these per pixel.
        let extents = sampler.extents();
        let (p1, p2) = sampler.densities_with_extents(extents);
        Self {
            weight,
            sampler,
            extents,
            inside: weight * p1,
            outside: weight * p2,
            // tan²(θc/2) = h_c / g_c, as `AnchorSampler::tan2_half`.
            test: ConeTest::new(extents.0 / extents.1),
        }
    }

    /// `weight · pdf(wi)` from `x`: [`AnchorSampler::pdf`] without recomputing constants.
    #[inline]
    fn weighted_pdf(&self, x: DVec3, wi: DVec3) -> f64 {
        if self.test.inside(self.sampler.anchor - x, wi) {
            self.inside
        } else {
            self.outside
        }
    }
}

/// One weighted patch of a level, with its constants.
#[derive(Clone, Copy, Debug)]
struct GuidePatch {
    weight: f64,
    shape: PatchShape,
}

/// The samplers of one vertex index.
#[derive(Clone, Debug, Default)]
struct Level {
    /// Summed weight of BRDF sampling.
    brdf: f64,
    /// Anchor cones and their weights.
    anchors: Vec<GuideAnchor>,
    /// Patches and their weights.
    patches: Vec<GuidePatch>,
}

impl Level {
    fn set(&mut self, cones: &[(f64, AnchorSampler)], patches: &[(f64, PatchSampler)]) {
        self.anchors.clear();
        self.anchors
            .extend(cones.iter().map(|&(w, a)| GuideAnchor::new(w, a)));
        self.patches.clear();
        self.patches
            .extend(patches.iter().map(|(weight, sampler)| GuidePatch {
                weight: *weight,
                shape: PatchShape::new(sampler),
            }));
    }

    /// Whether the level samples anything but the BRDF.
    fn guides(&self) -> bool {
        !(self.anchors.is_empty() && self.patches.is_empty())
    }

    /// A direction out of `x` from the cone or patch that `target` (a uniform number less
    /// the BRDF's weight) picks, driven by `rest`.
    fn sample(&self, x: DVec3, mut target: f64, rest: [f64; 3]) -> Vec3 {
        // Sampler `i`: the cones, then the patches; rounding past the end takes the last
        // one.
        let cones = self.anchors.len();
        let weight = |i: usize| match i < cones {
            true => self.anchors[i].weight,
            false => self.patches[i - cones].weight,
        };
        let mut i = 0;
        while i + 1 < cones + self.patches.len() && target >= weight(i) {
            target -= weight(i);
            i += 1;
        }
        let dir = match self.anchors.get(i) {
            Some(a) => a.sampler.sample_with_extents(x, rest, a.extents),
            None => self.patches[i - cones].shape.sampler.sample(x, rest),
        };
        dir.as_vec3().normalize()
    }
}

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
    spatial: Option<Arc<SpatialGuide>>,
}

/// A direction drawn from a guide.
pub struct GuideSample {
    pub wi: Vec3,
    /// `p_k(wi)`, solid angle.
    pub pdf: f64,
    /// BRDF × cos / pdf.
    pub weight: Vec3,
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

    /// This guide with every cone and patch density scaled by `factor` when evaluated (not when
    /// sampled): a wrong input that unbiasedness tests must reject.
    pub fn with_pdf_error(mut self, factor: f64) -> Self {
        self.pdf_error = Some(factor);
        self
    }

    /// This guide with `spatial` guiding the vertices beyond its levels.
    pub fn with_spatial(mut self, spatial: Option<Arc<SpatialGuide>>) -> Self {
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
    /// there instead of replacing it (glossy, 2 s, seeds 404 and 405: where they replaced
    /// it, relMSE was 5× `pg`'s). At the path's `last` vertex it does not guide the
    /// direction: that direction can only find emission, which next-event estimation finds
    /// better, and the quadtree's descents would cost for nothing.
    pub fn at(&self, k: usize, x: Vec3, n: Vec3, last: bool) -> Vertex<'_> {
        let (spatial, light_share) = match self.spatial.as_deref() {
            Some(s) => {
                let (cell, light_share) = s.at(x, n);
                (cell.filter(|_| !last).map(|cell| (s, cell)), light_share)
            }
            None => (None, 1.0),
        };
        let by = match (self.level(k), spatial) {
            (Some(level), spatial) => By::Level(level, spatial),
            (None, Some((s, cell))) => By::Spatial(s, cell),
            (None, None) => By::Brdf,
        };
        Vertex {
            by,
            light_share,
            scale: self.pdf_error.unwrap_or(1.0),
            x: x.as_dvec3(),
            n,
        }
    }

    /// `p_k(wi)` at the surface point `x` of `material` (normal `n` facing `wo`).
    pub fn pdf(&self, k: usize, material: &Material, x: Vec3, n: Vec3, wo: Vec3, wi: Vec3) -> f64 {
        self.at(k, x, n, false).pdf(material, wo, wi)
    }

    /// A direction out of the `k`-th non-delta vertex `x`, from four uniform numbers (see
    /// [`Vertex::sample`]).
    pub fn sample(
        &self,
        k: usize,
        material: &Material,
        x: Vec3,
        n: Vec3,
        wo: Vec3,
        u: [f64; 4],
    ) -> Option<GuideSample> {
        self.at(k, x, n, false).sample(material, wo, u)
    }
}

/// What guides one vertex (see [`Guide::at`]): a level samples its BRDF share from the
/// spatial guide's region where there is one.
#[derive(Clone, Copy)]
enum By<'a> {
    Level(&'a Level, Option<(&'a SpatialGuide, usize)>),
    Spatial(&'a SpatialGuide, usize),
    Brdf,
}

/// The guide of one vertex: the point `x`, its normal `n` (facing the path's `wo`) and
/// what samples directions there.
#[derive(Clone, Copy)]
pub struct Vertex<'a> {
    by: By<'a>,
    /// The probability of next-event estimation here.
    light_share: f64,
    /// The guide's fault injection (1 without).
    scale: f64,
    x: DVec3,
    n: Vec3,
}

impl Vertex<'_> {
    /// The probability of next-event estimation here: 1, or less in a cell of the spatial
    /// guide where training never saw a light sample reach a light. Multiple importance
    /// sampling weighs the light sample's density times this.
    pub fn light_share(&self) -> f64 {
        self.light_share
    }

    /// Whether this vertex samples anything but the BRDF.
    pub fn guides(&self) -> bool {
        !matches!(self.by, By::Brdf)
    }

    /// Cones, patches or spatial regions: the densities one evaluation of `pdf` costs.
    pub fn samplers(&self) -> usize {
        match self.by {
            By::Level(l, spatial) => {
                l.anchors.len() + l.patches.len() + usize::from(spatial.is_some())
            }
            By::Spatial(..) => 1,
            By::Brdf => 0,
        }
    }

    /// The density of a spatially guided vertex from the guide's and the BRDF's.
    fn spatial_mix(&self, guide_pdf: f64, brdf_pdf: f64) -> f64 {
        GUIDE_SHARE * self.scale * guide_pdf + (1.0 - GUIDE_SHARE) * brdf_pdf
    }

    /// `p(wi)` for the material's BRDF pdf `brdf_pdf` here.
    fn pdf_with(&self, wi: DVec3, brdf_pdf: f64) -> f64 {
        match self.by {
            By::Brdf => brdf_pdf,
            By::Spatial(s, cell) => self.spatial_mix(s.pdf(cell, wi.as_vec3()), brdf_pdf),
            By::Level(level, spatial) => {
                let brdf_pdf = match spatial {
                    Some((s, cell)) => self.spatial_mix(s.pdf(cell, wi.as_vec3()), brdf_pdf),
                    None => brdf_pdf,
                };
                let x = self.x;
                let anchors: f64 = level.anchors.iter().map(|a| a.weighted_pdf(x, wi)).sum();
                let patches: f64 = level
                    .patches
                    .iter()
                    .map(|p| p.weight * p.shape.pdf(x, wi))
                    .sum();
                level.brdf * brdf_pdf + self.scale * (anchors + patches)
            }
        }
    }

    /// `p(wi)` for `material` seen from `wo`.
    pub fn pdf(&self, material: &Material, wo: Vec3, wi: Vec3) -> f64 {
        let brdf_pdf = brdf::pdf(material, self.n, wo, wi);
        self.pdf_with(wi.as_dvec3(), brdf_pdf)
    }

    /// A direction out of this vertex of `material` seen from `wo`, from four uniform
    /// numbers: `u[0]` picks the sampler, the rest drive it. `None` where the direction
    /// carries nothing.
    pub fn sample(&self, material: &Material, wo: Vec3, u: [f64; 4]) -> Option<GuideSample> {
        let rest = [u[1], u[2], u[3]];
        let n = self.n;
        let wi = match self.by {
            By::Brdf => {
                let s = brdf::sample(material, n, wo, rest)?;
                return Some(GuideSample {
                    wi: s.wi,
                    pdf: s.pdf,
                    weight: s.weight,
                });
            }
            By::Spatial(s, cell) => {
                // The guide's own sample brings its density from the descent that drew it.
                let (wi, guided) = if u[0] < GUIDE_SHARE {
                    let (wi, pdf) = s.sample(cell, rest);
                    (wi, Some(pdf))
                } else {
                    (brdf::sample_direction(material, n, wo, rest)?, None)
                };
                return self.finish_sample(material, wo, wi, |brdf_pdf| {
                    self.spatial_mix(guided.unwrap_or_else(|| s.pdf(cell, wi)), brdf_pdf)
                });
            }
            By::Level(level, spatial) => {
                let target = u[0] - level.brdf;
                match spatial {
                    _ if target >= 0.0 => level.sample(self.x, target, rest),
                    // The BRDF share as the spatial guide samples: `u[0] / brdf` picks.
                    Some((s, cell)) if u[0] < GUIDE_SHARE * level.brdf => s.sample(cell, rest).0,
                    _ => brdf::sample_direction(material, n, wo, rest)?,
                }
            }
        };
        self.finish_sample(material, wo, wi, |brdf_pdf| {
            self.pdf_with(wi.as_dvec3(), brdf_pdf)
        })
    }

    /// The guide sample of direction `wi`: its density (`pdf` of the BRDF's density, asked
    /// only where the direction carries something) and weight.
    fn finish_sample(
        &self,
        material: &Material,
        wo: Vec3,
        wi: Vec3,
        pdf: impl FnOnce(f64) -> f64,
    ) -> Option<GuideSample> {
        let n = self.n;
        let cos = n.dot(wi);
        let f = brdf::eval(material, n, wo, wi);
        if cos <= 0.0 || f.max_element() <= 0.0 {
            return None;
        }
        let pdf = pdf(brdf::pdf(material, n, wo, wi));
        if !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        Some(GuideSample {
            wi,
            pdf,
            weight: f * (cos as f64 / pdf) as f32,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::path::generator::{PathGenerator, Step};
    use crate::sampling::light_point::LightPointSampler;
    use crate::sampling::{sample_rng, uniform};

    fn mixture() -> Mixture {
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
    const PATCH: PatchSampler = PatchSampler {
        center: DVec3::new(-1.0, 1.5, 0.5),
        half_u: DVec3::new(0.5, 0.0, 0.0),
        half_v: DVec3::new(0.0, 0.0, 0.4),
        alpha: 0.9,
    };

    /// Monte Carlo ∫ p_0(ω) dω over the sphere, uniform directions: 1 for a density.
    fn integral(guide: &Guide, material: &Material) -> f64 {
        integral_at(guide, material, 0)
    }

    /// ∫ p_k(ω) dω at the origin.
    fn integral_at(guide: &Guide, material: &Material, k: usize) -> f64 {
        let n = Vec3::Y;
        let wo = Vec3::new(0.3, 1.0, 0.1).normalize();
        let mut rng = sample_rng(5, 0, 0);
        // The cone and the patch hold 0.58 of the mass in 0.3 sr: the estimate's standard
        // deviation is about 0.002.
        let count = 4_000_000;
        let mut sum = 0.0;
        for _ in 0..count {
            let z = 1.0 - 2.0 * uniform(&mut rng);
            let phi = std::f32::consts::TAU * uniform(&mut rng);
            let r = (1.0 - z * z).max(0.0).sqrt();
            let wi = Vec3::new(r * phi.cos(), z, r * phi.sin());
            sum += guide.pdf(k, material, Vec3::ZERO, n, wo, wi);
        }
        sum / count as f64 * 4.0 * std::f64::consts::PI
    }

    fn white() -> Material {
        Material {
            name: "white".into(),
            kd: Vec3::splat(0.5),
            ks: Vec3::ZERO,
            ns: 0.0,
            mirror: false,
            ke: Vec3::ZERO,
        }
    }

    /// Past the mixture's two levels, a spatial guide trained on records around one
    /// direction: a density (and the check rejects its density off by 10 %), whose samples
    /// carry the density `pdf` reports and go where the records did.
    #[test]
    fn spatial_guide_past_the_levels_is_a_density() {
        use crate::path::spatial::{to_square, Record};
        let material = white();
        let target = Vec3::new(0.6, 0.7, -0.3).normalize();
        let [tu, tv] = to_square(target);
        // Records spread over a square of side 1/16 of the square map at `target`, all
        // at the origin, on a floor (facing +y).
        let mut rng = sample_rng(8, 0, 0);
        let records: Vec<Record> = (0..4100)
            .map(|i| Record {
                p: Vec3::ZERO,
                facing: 2,
                dir: [tu + uniform(&mut rng) / 16.0, tv + uniform(&mut rng) / 16.0],
                value: 1.0 + (i % 3) as f32,
            })
            .collect();
        let spatial = Arc::new(SpatialGuide::train(Vec3::splat(-1.0), Vec3::ONE, records));
        // Near: within the records' square widened by the finest leaf (1/32 of the square),
        // the resolution of the guide.
        let near = |d: Vec3| {
            let [u, v] = to_square(d);
            let around = -1.0 / 32.0..3.0 / 32.0;
            around.contains(&(u - tu)) && around.contains(&(v - tv))
        };
        let guide = Guide::new(&mixture()).with_spatial(Some(spatial));
        assert!(guide.guides(2) && guide.at(2, Vec3::ZERO, Vec3::Y, false).samplers() == 1);
        let total = integral_at(&guide, &material, 2);
        assert!((total - 1.0).abs() < 0.01, "∫ p = {total}");
        // Half the density is the spatial guide's: ×1.1 there makes ∫ p ≈ 1.05.
        let wrong = integral_at(&guide.clone().with_pdf_error(1.1), &material, 2);
        assert!(
            (wrong - 1.0).abs() > 0.03,
            "∫ p = {wrong} with a wrong density"
        );
        let (n, wo) = (Vec3::Y, Vec3::new(0.3, 1.0, 0.1).normalize());
        let mut rng = sample_rng(7, 0, 0);
        // Of 10 000 samples at level `k`, each carrying the density `pdf` reports: how
        // many are near the records.
        let mut samples_near = |k: usize| {
            let mut count = 0;
            for _ in 0..10_000 {
                let u = std::array::from_fn(|_| uniform(&mut rng) as f64);
                if let Some(s) = guide.sample(k, &material, Vec3::ZERO, n, wo, u) {
                    let p = guide.pdf(k, &material, Vec3::ZERO, n, wo, s.wi);
                    assert!((s.pdf - p).abs() <= 1e-9 * p, "{} vs {p}", s.pdf);
                    count += usize::from(near(s.wi));
                }
            }
            count
        };
        // 0.5 · 0.9 of the samples near the records (1/64 of the square with the margin).
        let towards = samples_near(2);
        assert!(towards > 4_000, "{towards} samples near the records");
        // At the levels, the BRDF share samples as the spatial guide does: still a density,
        // whose samples carry the density `pdf` reports, and the check rejects it off by
        // 10 % (the cone, the patch and the spatial guide hold 0.85 of level 0: ∫ ≈ 1.085).
        let by_spatial = samples_near(0);
        assert!(
            by_spatial > 500,
            "{by_spatial} samples near the records at level 0"
        );
        for k in 0..2 {
            assert_eq!(guide.at(k, Vec3::ZERO, Vec3::Y, false).samplers(), 3 - k);
            let total = integral_at(&guide, &material, k);
            assert!((total - 1.0).abs() < 0.01, "level {k}: ∫ p = {total}");
        }
        let wrong = integral_at(&guide.clone().with_pdf_error(1.1), &material, 0);
        assert!(
            (wrong - 1.0).abs() > 0.02,
            "∫ p = {wrong} with a wrong density"
        );
        // On a surface facing another way, where nothing was recorded: BRDF sampling alone.
        let (n, wo) = (Vec3::X, Vec3::new(1.0, 0.3, 0.1).normalize());
        let wi = Vec3::new(0.5, 0.5, 0.0).normalize();
        let brdf_pdf = brdf::pdf(&material, n, wo, wi);
        assert_eq!(guide.pdf(2, &material, Vec3::ZERO, n, wo, wi), brdf_pdf);
    }

    #[test]
    fn guide_is_a_density_and_sampling_agrees_with_pdf() {
        let material = white();
        let guide = Guide::new(&mixture());
        assert!(guide.guides(0) && guide.guides(1) && !guide.guides(2));
        let total = integral(&guide, &material);
        assert!((total - 1.0).abs() < 0.01, "∫ p = {total}");
        // The same check rejects cone and patch densities off by 10 % (weight 0.7: ∫ p ≈
        // 1.07).
        let wrong = integral(&guide.clone().with_pdf_error(1.1), &material);
        assert!(
            (wrong - 1.0).abs() > 0.03,
            "∫ p = {wrong} with a wrong density"
        );
        // Every sample carries the density `pdf` reports for its direction.
        let (n, wo) = (Vec3::Y, Vec3::new(0.3, 1.0, 0.1).normalize());
        let mut rng = sample_rng(6, 0, 0);
        let (mut anchored, mut patched) = (0, 0);
        let shape = PatchShape::new(&PATCH);
        for _ in 0..10_000 {
            let u = std::array::from_fn(|_| uniform(&mut rng) as f64);
            if let Some(s) = guide.sample(0, &material, Vec3::ZERO, n, wo, u) {
                let p = guide.pdf(0, &material, Vec3::ZERO, n, wo, s.wi);
                assert!((s.pdf - p).abs() <= 1e-9 * p, "{} vs {p}", s.pdf);
                let expected = brdf::eval(&material, n, wo, s.wi) * (n.dot(s.wi) / p as f32);
                assert!((s.weight - expected).length() <= 1e-5 * expected.length());
                anchored += usize::from(s.wi.dot(Vec3::new(1.0, 2.0, 0.0).normalize()) > 0.98);
                patched += usize::from(shape.patch_density(DVec3::ZERO, s.wi.as_dvec3()) > 0.0);
            }
        }
        // About 0.5 · 0.8 of the samples go into the 0.2-rad cone, 0.2 · 0.9 to the patch.
        assert!(anchored > 3_500, "{anchored} samples in the anchor cone");
        assert!(patched > 1_600, "{patched} samples towards the patch");
    }

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
                a.at(0, x.as_vec3(), Vec3::Y, false).pdf_with(wi, 0.3),
                b.at(0, x.as_vec3(), Vec3::Y, false).pdf_with(wi, 0.3),
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
        let samplers = |g: &Guide| g.at(0, Vec3::ZERO, Vec3::Y, false).samplers();
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
