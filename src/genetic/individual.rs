//! Individuals of the genetic algorithm (paper §5.3): weighted sets of path generators, and
//! the random draws that create and mutate their parts.
//!
//! Component 0 of every individual is the defensive `srt` generator, never mutated, with
//! weight ≥ `GaConfig::defensive_weight`: whatever the evolved components do, the mixture
//! covers every light-carrying path, so the final estimator stays unbiased.

use super::test_paths::TestPaths;
use super::GaConfig;
use crate::path::generator::{
    DirectionSampler, PathGenerator, SrtAbsorption, Step, ABSORPTION_MAX, ABSORPTION_MIN,
};
use crate::path::mixture::Mixture;
use crate::path::mixture_file;
use crate::sampling::anchor::AnchorSampler;
use crate::sampling::light_point::{LightPointSampler, LightRegion};
use crate::sampling::patch::PatchSampler;
use crate::scene::Scene;
use glam::DVec3;
use rand::Rng as _;
use std::f64::consts::PI;

/// Light regions are drawn up to this subdivision level (16 cells per emitter triangle).
pub const MAX_LIGHT_LEVEL: u8 = 2;
/// Random cone half-angles are log-uniform in this range (radians).
pub const THETA_C_RANGE: (f64, f64) = (0.02, 1.5);
/// Cones of generators that follow a test path: half-angles log-uniform, probabilities
/// uniform in these ranges.
pub const FOLLOW_THETA_C: (f64, f64) = (0.05, 0.5);
pub const FOLLOW_ALPHA: (f64, f64) = (0.5, 0.95);
/// Random cone probabilities `α` are uniform in this range.
pub const ALPHA_RANGE: (f64, f64) = (0.05, 0.95);
/// Random light-region probabilities `β` are uniform in `[0, BETA_MAX)`.
pub const BETA_MAX: f64 = 0.95;
/// A data-driven patch spans the light-carrying test paths' arrival points on its plane
/// between these weighted quantiles along each of its axes: the full range lets stray
/// points stretch the patch, and a narrower range did no better (reports/README.md,
/// "Measurements formerly in code comments (2026-12-07)").
const PATCH_QUANTILES: (f64, f64) = (0.02, 0.98);
/// Share of data-driven patches fitted to the arrivals near a point rather than to all of
/// them on its plane. More local patches raised the error (same section); a few stay for
/// planes that hold several lit regions.
const PATCH_LOCAL_SHARE: f64 = 0.25;
/// Probabilities `α` of data-driven patches are uniform in this range: a patch fitted to
/// where light arrived needs little of the uniform part, half of which is below the surface
/// (this range did better than `FOLLOW_ALPHA`: same section).
pub const PATCH_ALPHA: (f64, f64) = (0.8, 0.99);
/// Half-edges of patches stay between these fractions of the scene's size.
pub const PATCH_HALF_RANGE: (f64, f64) = (0.005, 2.0);
/// Radius of the points a local patch is fitted to, relative to the scene's size:
/// log-uniform in this range.
const PATCH_LOCAL_RADIUS: (f64, f64) = (0.05, 0.5);

/// Where a light-carrying test path's `k`-th direction arrived, on a plane.
#[derive(Clone, Copy, Debug)]
struct Arrival {
    point: DVec3,
    /// Unit geometric normal of the triangle there.
    normal: DVec3,
    /// `sqrt(F²/q)` of the path: how much its arrival point counts in a patch's extent.
    weight: f64,
}

/// A generator with an identity: copies (crossover, elitism) keep the id, any change gets a
/// new one, so the fitness cache evaluates each distinct generator once.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Gene {
    pub id: u64,
    pub generator: PathGenerator,
    /// Per step: the triangle its anchor lies on (`None` for a BRDF sampler).
    pub anchor_prims: Vec<Option<u32>>,
}

/// A weighted set of generators; `genes[0]` is the defensive `srt` generator (id 0).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Individual {
    pub genes: Vec<Gene>,
    /// Sum to 1; `weights[0] ≥ GaConfig::defensive_weight`.
    pub weights: Vec<f64>,
}

impl Individual {
    /// The mixture of eq. 7 this individual stands for.
    pub fn to_mixture(&self) -> Mixture {
        Mixture::new(
            self.genes.iter().map(|g| g.generator.clone()).collect(),
            self.weights.clone(),
        )
    }

    /// Normalises the weights to sum 1 with the defensive one at least `defensive`.
    pub fn normalise_weights(&mut self, defensive: f64) {
        normalise_weights(&mut self.weights, defensive);
    }
}

/// Normalises non-negative `weights` to sum 1 with `weights[0]` (the defensive component) at
/// least `defensive`.
pub fn normalise_weights(weights: &mut [f64], defensive: f64) {
    let others: f64 = weights[1..].iter().sum();
    let total = weights[0] + others;
    let w0 = if total > 0.0 { weights[0] / total } else { 1.0 };
    if others <= 0.0 || w0 >= 1.0 {
        weights.iter_mut().for_each(|w| *w = 0.0);
        weights[0] = 1.0;
        return;
    }
    let w0 = w0.max(defensive);
    let scale = (1.0 - w0) / others;
    for w in &mut weights[1..] {
        *w *= scale;
    }
    // The defensive weight takes the rounding error, so the sum is 1 to an ulp or two.
    weights[0] = 1.0 - weights[1..].iter().sum::<f64>();
}

/// What random draws need of the scene, and the source of fresh gene ids.
pub struct GenePool<'a> {
    pub scene: &'a Scene,
    pub max_bounces: u32,
    /// Steps of a random generator.
    steps: usize,
    srt: PathGenerator,
    /// Running sum of triangle areas, for anchors uniform by area on all surfaces.
    area_cdf: Vec<f64>,
    next_id: u64,
    /// Light-carrying test paths that anchors may be drawn from, with the running sum of
    /// their `F²/q` (or its root), and the share of anchors drawn from them (`GaConfig::data_anchors`).
    paths: Option<(&'a TestPaths, Vec<f64>)>,
    data_anchors: f64,
    /// Paths picked ∝ `sqrt(F²/q)` rather than `F²/q` (with held-out placement,
    /// `GaConfig::held_out`; see [`Self::pick_path`]).
    root_picks: bool,
    /// Per step, where the light-carrying test paths' directions arrived; and the share of
    /// data-driven samplers that are patches (`GaConfig::patches`).
    arrivals: Vec<Vec<Arrival>>,
    patches: f64,
    /// `GaConfig::directions_only`: the absorption of every step.
    fixed_absorption: Option<SrtAbsorption>,
}

/// A uniform number in `[lo, hi)`.
fn range(rng: &mut crate::sampling::Rng, (lo, hi): (f64, f64)) -> f64 {
    lo + (hi - lo) * rng.random::<f64>()
}

/// A log-uniform number in `[lo, hi)`.
fn log_uniform(rng: &mut crate::sampling::Rng, (lo, hi): (f64, f64)) -> f64 {
    (lo.ln() + (hi.ln() - lo.ln()) * rng.random::<f64>()).exp()
}

impl<'a> GenePool<'a> {
    pub fn new(scene: &'a Scene, max_bounces: u32, config: &GaConfig) -> Self {
        let mut total = 0.0;
        let area_cdf = (0..scene.mesh.prim_count() as u32)
            .map(|prim| {
                total += scene.mesh.area(prim);
                total
            })
            .collect();
        Self {
            scene,
            max_bounces,
            steps: config
                .max_steps
                .unwrap_or(usize::MAX)
                .min(max_bounces.saturating_sub(1).max(1) as usize),
            srt: PathGenerator::srt(
                max_bounces,
                config.srt_absorption,
                mixture_file::uniform_light(scene),
            ),
            area_cdf,
            next_id: 1,
            paths: None,
            data_anchors: config.data_anchors,
            root_picks: config.held_out == Some(true),
            arrivals: Vec::new(),
            patches: config.patches,
            fixed_absorption: config.directions_only.then_some(config.srt_absorption),
        }
    }

    /// This pool with `paths` as the source of data-driven anchors.
    pub fn with_test_paths(mut self, paths: &'a TestPaths) -> Self {
        let mut total = 0.0;
        let cdf = paths
            .f2_over_q
            .iter()
            .map(|&f| {
                total += if self.root_picks { f.sqrt() } else { f };
                total
            })
            .collect();
        self.paths = Some((paths, cdf));
        self.arrivals = (0..self.steps)
            .map(|k| {
                (0..paths.len())
                    .filter_map(|i| {
                        let (point, prim) = paths.step_target(i, k)?;
                        let normal = self.normal(prim, point)?;
                        let weight = paths.f2_over_q[i].sqrt();
                        (weight > 0.0 && weight.is_finite()).then_some(Arrival {
                            point,
                            normal,
                            weight,
                        })
                    })
                    .collect()
            })
            .collect();
        self
    }

    /// A patch over where light-carrying test paths' `k`-th directions arrived on the plane
    /// of `point` (normal `normal`): all of them there, or with probability
    /// `PATCH_LOCAL_SHARE` those within a random radius of `point`. Its axes are the
    /// principal axes of those points (weights `sqrt(F²/q)`), its extent their weighted
    /// `PATCH_QUANTILES` along each axis. `None` without test paths there.
    pub fn data_patch(
        &self,
        k: usize,
        (point, normal): (DVec3, DVec3),
        rng: &mut crate::sampling::Rng,
    ) -> Option<PatchSampler> {
        let arrivals = self.arrivals.get(k)?;
        let extent = f64::from(self.scene.extent);
        let radius = match rng.random::<f64>() < PATCH_LOCAL_SHARE {
            true => log_uniform(rng, PATCH_LOCAL_RADIUS) * extent,
            false => f64::INFINITY,
        };
        let (e1, e2) = crate::math::basis(normal);
        // In-plane coordinates about `point` of the arrivals on the plane.
        let plane_tolerance = 1e-4 * extent;
        let near: Vec<(f64, f64, f64)> = arrivals
            .iter()
            .filter(|a| {
                let d = a.point - point;
                a.normal.dot(normal).abs() > 0.99
                    && normal.dot(d).abs() <= plane_tolerance
                    && d.length() <= radius
            })
            .map(|a| {
                let d = a.point - point;
                (d.dot(e1), d.dot(e2), a.weight)
            })
            .collect();
        if near.is_empty() {
            return None;
        }
        let total: f64 = near.iter().map(|p| p.2).sum();
        let (mx, my) = near
            .iter()
            .fold((0.0, 0.0), |(x, y), p| (x + p.0 * p.2, y + p.1 * p.2));
        // Arrivals have positive weights: `total > 0`.
        let (mx, my) = (mx / total, my / total);
        let (cxx, cxy, cyy) = near.iter().fold((0.0, 0.0, 0.0), |(a, b, c), p| {
            let (dx, dy) = (p.0 - mx, p.1 - my);
            (a + p.2 * dx * dx, b + p.2 * dx * dy, c + p.2 * dy * dy)
        });
        let angle = 0.5 * (2.0 * cxy).atan2(cxx - cyy);
        let (s, c) = angle.sin_cos();
        let axes = [e1 * c + e2 * s, e2 * c - e1 * s];
        let (lo, hi) = PATCH_HALF_RANGE;
        let mut center = point;
        let mut half = [DVec3::ZERO; 2];
        for (axis, half) in axes.iter().zip(&mut half) {
            let mut along: Vec<(f64, f64)> = near
                .iter()
                .map(|p| (p.0 * axis.dot(e1) + p.1 * axis.dot(e2), p.2))
                .collect();
            along.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
            let quantile = |q: f64| {
                let mut sum = 0.0;
                along
                    .iter()
                    .find(|p| {
                        sum += p.1;
                        sum >= q * total
                    })
                    .map_or(0.0, |p| p.0)
            };
            let (a, b) = (quantile(PATCH_QUANTILES.0), quantile(PATCH_QUANTILES.1));
            center += *axis * (0.5 * (a + b));
            *half = *axis * (0.5 * (b - a)).clamp(lo * extent, hi * extent);
        }
        PatchSampler::new(center, half[0], half[1], range(rng, PATCH_ALPHA)).ok()
    }

    /// A data-driven patch for step `k` about the arrival of a light-carrying test path
    /// picked ∝ its `F²/q` or its root ([`Self::pick_path`]); `None` without test paths.
    fn random_patch(&self, k: usize, rng: &mut crate::sampling::Rng) -> Option<PatchSampler> {
        let (paths, i) = self.pick_path(rng)?;
        let (point, prim) = paths.step_target(i, k)?;
        self.data_patch(k, (point, self.normal(prim, point)?), rng)
    }

    /// The unit geometric normal of triangle `prim` (`None` for a degenerate one); of an
    /// analytic shape, its normal at `point`.
    fn normal(&self, prim: u32, point: DVec3) -> Option<DVec3> {
        if let Some(shape) = self.scene.mesh.analytic(prim) {
            return shape.normal_at(point).try_normalize();
        }
        let [a, b, c] = self.scene.mesh.vertices(prim).map(|v| v.as_dvec3());
        (b - a).cross(c - a).try_normalize()
    }

    /// A light-carrying test path picked with probability ∝ its `F²/q`, or with held-out
    /// placement ∝ its root (`None` without paths). `F²/q` is heavy-tailed on glossy paths,
    /// and a few paths then take most of the picks, so held-out placement picks by the
    /// root, which lowered `ga`'s error on glossy (reports/README.md, "Measurements
    /// formerly in code comments (2026-12-07)"); `ga-pt`'s guides, which place from the
    /// paths they are measured on, keep `F²/q`, since the root let fig5's pilot fail
    /// (docs/methods/ga.md, "Held-out placement").
    fn pick_path(&self, rng: &mut crate::sampling::Rng) -> Option<(&'a TestPaths, usize)> {
        let (paths, cdf) = self.paths.as_ref()?;
        let total = cdf.last().copied().unwrap_or(0.0);
        if total.is_nan() || total <= 0.0 {
            return None;
        }
        let target = rng.random::<f64>() * total;
        Some((
            paths,
            cdf.partition_point(|&c| c <= target).min(cdf.len() - 1),
        ))
    }

    /// A generator that follows one light-carrying test path (picked as [`Self::pick_path`] does): each step
    /// aims a cone at the point the path's direction reached there (half-angle in
    /// `FOLLOW_THETA_C`, probability in `FOLLOW_ALPHA`), BRDF sampling past the path's end.
    /// `None` without test paths.
    pub fn path_gene(&mut self, rng: &mut crate::sampling::Rng) -> Option<Gene> {
        let (paths, i) = self.pick_path(rng)?;
        let mut gene = self.random_gene(rng);
        for k in 0..gene.generator.steps.len() {
            let target = paths.step_target(i, k);
            let patch = target
                .filter(|_| rng.random::<f64>() < self.patches)
                .and_then(|(p, prim)| self.data_patch(k, (p, self.normal(prim, p)?), rng));
            let (sampler, prim) = match (patch, target) {
                (Some(patch), _) => (DirectionSampler::Patch(patch), None),
                (None, Some((anchor, prim))) => {
                    let sampler = AnchorSampler {
                        anchor,
                        theta_c: log_uniform(rng, FOLLOW_THETA_C),
                        alpha: range(rng, FOLLOW_ALPHA),
                    };
                    (DirectionSampler::Anchor(sampler), Some(prim))
                }
                (None, None) => (DirectionSampler::Brdf, None),
            };
            gene.generator.steps[k].sampler = sampler;
            gene.anchor_prims[k] = prim;
        }
        Some(gene)
    }

    /// An anchor point for step `k` and its triangle. With probability `data_anchors` (and
    /// test paths), where a light-carrying test path's `k`-th direction arrived, the path
    /// picked as [`Self::pick_path`] does (beyond the paper: the light's actual routes);
    /// otherwise, or where that path has no `k`-th step, uniform by area on all surfaces.
    pub fn random_anchor(&self, k: usize, rng: &mut crate::sampling::Rng) -> (DVec3, u32) {
        if self.paths.is_some() && rng.random::<f64>() < self.data_anchors {
            if let Some(found) = self.pick_path(rng).and_then(|(p, i)| p.step_target(i, k)) {
                return found;
            }
        }
        self.random_surface_point(rng)
    }

    /// The defensive component every individual carries.
    pub fn srt(&self) -> Gene {
        Gene {
            id: 0,
            generator: self.srt.clone(),
            anchor_prims: vec![None; self.srt.steps.len()],
        }
    }

    pub fn fresh_id(&mut self) -> u64 {
        self.next_id += 1;
        self.next_id
    }

    /// A point uniform by area on the scene's surfaces, and its triangle.
    pub fn random_surface_point(&self, rng: &mut crate::sampling::Rng) -> (DVec3, u32) {
        let total = self.area_cdf.last().copied().unwrap_or(0.0);
        let target = rng.random::<f64>() * total;
        let prim = self
            .area_cdf
            .partition_point(|&c| c <= target)
            .min(self.area_cdf.len() - 1) as u32;
        if let Some(shape) = self.scene.mesh.analytic(prim) {
            let u1 = rng.random::<f64>();
            return (shape.sample_area(u1, rng.random::<f64>()), prim);
        }
        let [a, b, c] = self.scene.mesh.vertices(prim).map(|v| v.as_dvec3());
        let su = rng.random::<f64>().sqrt();
        let u2 = rng.random::<f64>();
        (a * (1.0 - su) + b * (su * (1.0 - u2)) + c * (su * u2), prim)
    }

    pub fn random_theta_c(rng: &mut crate::sampling::Rng) -> f64 {
        log_uniform(rng, THETA_C_RANGE)
    }

    pub fn random_alpha(rng: &mut crate::sampling::Rng) -> f64 {
        range(rng, ALPHA_RANGE)
    }

    pub fn random_absorption(rng: &mut crate::sampling::Rng) -> f64 {
        range(rng, (ABSORPTION_MIN, ABSORPTION_MAX))
    }

    /// A directional sampler of either type for step `k` and, for an anchor, its triangle.
    pub fn random_sampler(
        &self,
        k: usize,
        rng: &mut crate::sampling::Rng,
    ) -> (DirectionSampler, Option<u32>) {
        if rng.random::<f64>() < 0.5 {
            return (DirectionSampler::Brdf, None);
        }
        if self.paths.is_some() && rng.random::<f64>() < self.data_anchors * self.patches {
            if let Some(patch) = self.random_patch(k, rng) {
                return (DirectionSampler::Patch(patch), None);
            }
        }
        let (anchor, prim) = self.random_anchor(k, rng);
        let sampler = AnchorSampler {
            anchor,
            theta_c: Self::random_theta_c(rng),
            alpha: Self::random_alpha(rng),
        };
        (DirectionSampler::Anchor(sampler), Some(prim))
    }

    /// A light region on an emitter picked by area, at a random level, and a random `β`
    /// (uniform light sampling, never used, in a scene without area emitters).
    pub fn random_light(&self, rng: &mut crate::sampling::Rng) -> LightPointSampler {
        let emitters = &self.scene.emitters;
        if emitters.prims.is_empty() {
            // Lit by its environment alone: no light point is ever sampled.
            return LightPointSampler::uniform(0);
        }
        let prim = emitters.pick(rng.random::<f64>());
        let level = rng.random_range(0..=MAX_LIGHT_LEVEL);
        let cell = rng.random_range(0..1u32 << (2 * u32::from(level)));
        // An analytic emitter is one region (see `light_point`).
        let (level, cell) = match self.scene.mesh.analytic(prim) {
            Some(_) => (0, 0),
            None => (level, cell),
        };
        LightPointSampler {
            region: LightRegion { prim, level, cell },
            beta: range(rng, (0.0, BETA_MAX)),
        }
    }

    /// A random generator: one step per vertex that can scatter before `max_bounces` (the
    /// absorption there is 1 anyway), or `GaConfig::max_steps` of them, each of a random
    /// type and absorption (`srt`'s absorption and light sampler with
    /// `GaConfig::directions_only`).
    pub fn random_gene(&mut self, rng: &mut crate::sampling::Rng) -> Gene {
        let n = self.steps;
        let mut steps = Vec::with_capacity(n);
        let mut anchor_prims = Vec::with_capacity(n);
        for k in 0..n {
            let (sampler, prim) = self.random_sampler(k, rng);
            let absorption = match self.fixed_absorption {
                Some(a) => a.at(k),
                None => Self::random_absorption(rng),
            };
            steps.push(Step {
                sampler,
                absorption,
            });
            anchor_prims.push(prim);
        }
        let light = match self.fixed_absorption {
            Some(_) => self.srt.light,
            None => self.random_light(rng),
        };
        Gene {
            id: self.fresh_id(),
            generator: PathGenerator { steps, light },
            anchor_prims,
        }
    }

    /// `ind`, evolved with another pool, as a member of this one: fresh gene ids (ids are
    /// per pool), the defensive component this pool's, and every generator cut or padded
    /// (with BRDF steps) to this pool's number of steps.
    pub fn adopt(&mut self, ind: &Individual, config: &GaConfig) -> Individual {
        let mut genes = vec![self.srt()];
        for gene in &ind.genes[1..] {
            let mut gene = gene.clone();
            let from = gene.generator.steps.len();
            gene.generator
                .steps
                .extend((from..self.steps).map(|k| Step {
                    sampler: DirectionSampler::Brdf,
                    absorption: self.fixed_absorption.map_or(0.5, |a| a.at(k)),
                }));
            gene.generator.steps.truncate(self.steps);
            gene.anchor_prims.resize(self.steps, None);
            gene.id = self.fresh_id();
            genes.push(gene);
        }
        let mut adopted = Individual {
            genes,
            weights: ind.weights.clone(),
        };
        adopted.normalise_weights(config.defensive_weight);
        adopted
    }

    /// A random individual: the defensive component and `config.generators` random ones,
    /// with random weights.
    pub fn random_individual(
        &mut self,
        config: &GaConfig,
        rng: &mut crate::sampling::Rng,
    ) -> Individual {
        let mut genes = vec![self.srt()];
        let mut weights = vec![range(rng, (0.0, 1.0))];
        // With data anchors, that share of individuals follows light-carrying test paths.
        let follow = self.paths.is_some() && rng.random::<f64>() < self.data_anchors;
        for _ in 0..config.generators {
            let gene = match follow {
                true => self.path_gene(rng),
                false => None,
            };
            genes.push(gene.unwrap_or_else(|| self.random_gene(rng)));
            weights.push(range(rng, (0.1, 1.0)));
        }
        let mut ind = Individual { genes, weights };
        ind.normalise_weights(config.defensive_weight);
        ind
    }
}

/// Cone half-angles are kept inside (0, π) with a margin: `THETA_C_RANGE` widened.
pub fn clamp_theta_c(theta: f64) -> f64 {
    theta.clamp(1e-3, PI - 1e-3)
}
