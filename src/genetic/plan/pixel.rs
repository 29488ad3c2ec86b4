//! One GA pixel: its test paths, the genetic algorithm on them, the choice between the best
//! individual and `srt`, and the gate's trial ([`GaPixel`]).

use super::super::individual::Individual;
use super::super::population::{evolve_from, Evolution, GenerationStats};
use super::super::test_paths::TestPaths;
use super::super::{fitness, GaConfig};
use super::baseline::Origin;
use super::config::PlanConfig;
use super::gate::{gate_margins, run_trial, Trial};
use super::stages::LearnStore;
use super::PlanFor;
use crate::path::generator::Nee;
use crate::path::mixture::Mixture;
use crate::path::{RayCounts, SceneView};
use crate::sampling::{derived_seed, sample_rng, Stream};
use std::time::Instant;

/// With pruning, generators get the steps that carry all but this share of the test paths'
/// `Σ F²/q`: none, so steps are cut only past the deepest light-carrying test path. (Cutting
/// at 0.1 % made fig5 worse, 4.14 against 2.70 relMSE at 128², 64 spp: with M = 10 000 only
/// ~100 test paths carry light, too few to call a depth's share negligible.)
pub const PRUNE_SHARE: f64 = 0.0;

/// Steps of [`fitness::optimise_weights`] on the evolved mixture with
/// `GaConfig::convex_weights` (each costs two passes over the light-carrying test paths per
/// generator; it stops earlier once `V` stops falling).
pub const CONVEX_STEPS: fitness::Steps = fitness::Steps {
    iterations: 200,
    tolerance: 1e-9,
};

/// With pruning (`PlanConfig::prune`), the evolved mixture of `ga` keeps only the components
/// without which its `V` would rise by more than this share, in all
/// ([`fitness::prune_components`]). A component costs the render its densities at every
/// vertex of every path of every pixel whose mixture holds it: about 0.27 densities per ray
/// on fig1, which at [`crate::path::DENSITY_COST`] each is 2 % of the work per component.
/// 64 spp, seed 401, tolerance 0 / 0.01 / 0.03 / 0.1: fig1's 400 components go to 208 / 184
/// / 154, its densities 85.0 M → 36.8 / 30.5 / 23.3 M, relMSE 4.12 → 4.16 / 4.19 / 4.33e-2;
/// glossy 230 → 113 / 105 / 92 components, relMSE 1.53 → 1.49 / 1.47 / 1.59e-2. `ga-pt`'s
/// guides keep theirs (its images stay as they were), and so does the paper's end-only
/// estimator (`--nee end`), whose rare large contributions the test paths' `V` sees too
/// seldom: pruned at this tolerance, fig5 at 64 spp (seed 1, no gate) had relMSE 1.55
/// against 1.14.
pub const COMPONENT_TOLERANCE: f64 = 0.02;

/// With `GaConfig::held_out`, the placement paths stop at `max_light_paths /
/// PLACEMENT_SHARE` light-carrying ones: anchors and patches need where light went, not
/// eq. 10's precision. With next-event estimation at every vertex most test paths carry
/// light and this costs a few hundred paths; `ga-pt`'s end-only test paths seldom do (fig5:
/// 1 %), so that there a held-out set costs as much as the first (see `GaConfig::held_out`).
pub const PLACEMENT_SHARE: usize = 4;

/// The outcome of the genetic algorithm at one pixel.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct GaPixel {
    pub x: u32,
    pub y: u32,
    pub origin: Origin,
    /// The mixture this pixel renders with and lends its neighbours.
    pub mixture: Mixture,
    /// Eq. 10 on the test paths: the defensive `srt` density alone, and the best individual.
    pub v_srt: f64,
    pub v_best: f64,
    /// Eq. 10 of the best individual with its evolved weights, before
    /// `GaConfig::convex_weights` replaced them (equal to `v_best` without).
    pub v_evolved: f64,
    /// The GA's best individual was no better than `srt`, which is kept instead.
    pub kept_srt: bool,
    /// With the gate (and an evolved mixture): the evolved estimator against `pt` here.
    pub trial: Option<Trial>,
    /// The GA's best individual (before the comparison with `srt`), which warm-starts
    /// neighbouring GA pixels.
    #[serde(skip)]
    pub best: Option<Individual>,
    /// Whether this pixel's GA started from evolved individuals: its neighbours' best, or
    /// (a pilot pixel) its own scouting run's.
    pub warm: bool,
    /// Test paths sampled (`M`) and those that carry light (stored).
    pub test_paths: usize,
    pub light_paths: usize,
    /// Steps of the evolved generators (fewer than `max_bounces − 1` when pruned).
    pub steps: usize,
    /// Best and mean `V` per generation.
    pub history: Vec<GenerationStats>,
    pub individual_evaluations: u64,
    pub generator_evaluations: u64,
    pub test_path_seconds: f64,
    pub ga_seconds: f64,
}

impl GaPixel {
    /// Whether the gate's trial predicts the evolved estimator for `plan_for` to beat `pt`
    /// here by the winning margin ([`gate_margins`]): a guide's gain one standard error below
    /// its estimate ([`Trial::cautious_gain`]); a mixture's as estimated, whose margin of 2
    /// already allows for its prediction's uncertainty.
    pub fn pays(&self, plan_for: PlanFor) -> bool {
        let win = gate_margins(plan_for).1;
        self.trial.is_some_and(|t| match plan_for {
            PlanFor::Guide => t.cautious_gain() > win,
            PlanFor::Mixture => t.gain > win,
        })
    }

    /// Whether this pixel's estimator should be `pt`: it kept `srt`, or its trial predicts
    /// a loss below the losing margin ([`gate_margins`]) (a NaN gain counts as a loss). A
    /// pixel without a trial (a guide's pixel outside the pilot) keeps its estimator.
    pub fn prefers_pt(&self, plan_for: PlanFor) -> bool {
        self.kept_srt
            || self
                .trial
                .is_some_and(|t| t.gain.is_nan() || t.gain < gate_margins(plan_for).0)
    }
}

/// An evolved GA pixel and the rays its test paths, GA and trial traced.
pub(super) type Evolved = (GaPixel, RayCounts);

/// What every GA pixel of a plan shares: the scene, the defensive `srt` mixture, the
/// settings, the estimator the plan is for and the user's seed, from which each pixel's
/// random streams are derived.
pub(super) struct PixelContext<'a> {
    pub(super) view: &'a SceneView<'a>,
    pub(super) srt: &'a Mixture,
    pub(super) ga: &'a GaConfig,
    pub(super) config: &'a PlanConfig,
    pub(super) max_bounces: u32,
    pub(super) plan_for: PlanFor,
    /// Whether the gate runs (`GateConfig::gate`).
    pub(super) gate: bool,
    pub(super) seed: u64,
    /// Where the waves are kept between processes, if they are.
    pub(super) store: Option<&'a dyn LearnStore>,
}

/// How the GA starts at a pixel, and whether the pixel then runs the gate's trial.
#[derive(Debug)]
pub(super) struct GaRun {
    /// The first generation's evolved individuals (none: a cold start).
    pub(super) seeds: Vec<Individual>,
    pub(super) generations: usize,
    /// The pixel's GA random stream (a pilot pixel that goes on takes a fresh one: its
    /// scouting run's would replay the same random individuals and breeding).
    pub(super) stream: u64,
    /// Whether the pixel runs the gate's trial (with the gate, where the GA did not keep
    /// `srt`).
    pub(super) trial: bool,
}

/// What a pixel keeps of its GA: its best individual's mixture, or `srt` where that was
/// no better on the test paths.
struct Outcome {
    mixture: Mixture,
    /// Eq. 10 of the chosen mixture, and of the best individual with its evolved weights.
    v_best: f64,
    v_evolved: f64,
    kept_srt: bool,
    history: Vec<GenerationStats>,
    /// Individuals and generators evaluated.
    evaluations: (u64, u64),
    /// The best individual (none without light-carrying test paths).
    best: Option<Individual>,
}

/// Test paths and evolution at one pixel.
pub(super) fn run_pixel(
    context: &PixelContext,
    (x, y, origin): (u32, u32, Origin),
    run: &GaRun,
) -> Evolved {
    let &PixelContext {
        view,
        srt,
        ga,
        max_bounces,
        seed,
        ..
    } = context;
    let t0 = Instant::now();
    let footprint = context.config.footprint_pixels(context.plan_for);
    let (paths, mut counts) = TestPaths::sample_around(
        view,
        srt,
        ((x, y), footprint),
        (ga.test_paths, ga.max_light_paths),
        max_bounces,
        derived_seed(seed, Stream::TestPaths.tag()),
    );
    let test_path_seconds = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let pixel = y as u64 * view.scene.camera.width as u64 + x as u64;
    let mut rng = sample_rng(derived_seed(seed, Stream::Ga.tag()), pixel, run.stream);
    let v_srt = fitness::second_moment(view, &paths, srt);
    let ga = &pixel_ga_config(context, &paths, run.generations);
    let steps = ga
        .max_steps
        .unwrap_or(usize::MAX)
        .min(max_bounces.saturating_sub(1).max(1) as usize);
    let outcome = if paths.is_empty() {
        Outcome {
            mixture: srt.clone(),
            v_best: v_srt,
            v_evolved: v_srt,
            kept_srt: true,
            history: Vec::new(),
            evaluations: (0, 0),
            best: None,
        }
    } else {
        let at = ((x, y), footprint);
        let placement = held_out_paths(context, ga, at, &paths, &mut counts);
        let evolution = evolve_from(ga, (&placement, &paths), view, &mut rng, &run.seeds);
        let mixture = context.plan_for == PlanFor::Mixture && srt.nee == Nee::Every;
        let prune = (context.config.prune && mixture).then_some(COMPONENT_TOLERANCE);
        best_or_srt(view, (ga, prune), &paths, evolution, (srt, v_srt))
    };
    let trial = (context.gate && run.trial && !outcome.kept_srt).then(|| {
        let at = ((x, y), paths.weights());
        run_trial(context, at, &outcome.mixture, &mut counts)
    });
    let pixel = GaPixel {
        x,
        y,
        origin,
        best: outcome.best,
        warm: !run.seeds.is_empty(),
        trial,
        steps,
        mixture: outcome.mixture,
        v_srt,
        v_best: outcome.v_best,
        v_evolved: outcome.v_evolved,
        kept_srt: outcome.kept_srt,
        test_paths: paths.sampled,
        light_paths: paths.len(),
        history: outcome.history,
        individual_evaluations: outcome.evaluations.0,
        generator_evaluations: outcome.evaluations.1,
        test_path_seconds,
        ga_seconds: t1.elapsed().as_secs_f64(),
    };
    (pixel, counts)
}

/// The test paths that place the data-driven anchors and patches: with
/// `GaConfig::held_out` (and data-driven samplers to place) a second set, sampled as
/// `paths` was (over the same footprint, `at`) from its own random stream until a quarter as many carry light
/// ([`PLACEMENT_SHARE`]), else `paths` itself.
fn held_out_paths<'p>(
    context: &PixelContext,
    ga: &GaConfig,
    at: ((u32, u32), f32),
    paths: &'p TestPaths,
    counts: &mut RayCounts,
) -> std::borrow::Cow<'p, TestPaths> {
    if ga.held_out != Some(true) || ga.data_anchors == 0.0 {
        return std::borrow::Cow::Borrowed(paths);
    }
    let light = (ga.max_light_paths / PLACEMENT_SHARE).max(1);
    let (placement, c) = TestPaths::sample_around(
        context.view,
        context.srt,
        at,
        (ga.test_paths, light),
        context.max_bounces,
        derived_seed(context.seed, Stream::Placement.tag()),
    );
    counts.add(c);
    std::borrow::Cow::Owned(placement)
}

/// The GA's settings at a pixel: `generations` of them, and with pruning no generator step
/// past the depth where the test paths carry light. A guide takes only the directional
/// samplers, and at most `guide_steps` steps.
fn pixel_ga_config(context: &PixelContext, paths: &TestPaths, generations: usize) -> GaConfig {
    let (ga, config, plan_for) = (context.ga, context.config, context.plan_for);
    GaConfig {
        directions_only: ga.directions_only || plan_for == PlanFor::Guide,
        max_steps: match (
            plan_for,
            config.prune.then(|| paths.steps_needed(PRUNE_SHARE)),
        ) {
            (PlanFor::Guide, needed) => Some(needed.unwrap_or(usize::MAX).min(config.guide_steps)),
            (PlanFor::Mixture, needed) => needed,
        },
        generations,
        held_out: Some(ga.held_out.unwrap_or(plan_for == PlanFor::Mixture)),
        ..ga.clone()
    }
}

/// The evolved individual's mixture where its `V` (after [`convex_weights`] with
/// `GaConfig::convex_weights`) is below `srt`'s `v_srt`, else `srt`.
fn best_or_srt(
    view: &SceneView,
    (ga, prune): (&GaConfig, Option<f64>),
    paths: &TestPaths,
    mut evolution: Evolution,
    (srt, v_srt): (&Mixture, f64),
) -> Outcome {
    let v_evolved = evolution.best_v;
    let mut evaluations = (
        evolution.individual_evaluations,
        evolution.generator_evaluations,
    );
    if ga.convex_weights && v_evolved.is_finite() {
        evaluations.1 += convex_weights(view, (ga, prune), paths, &mut evolution);
    }
    let best = Some(evolution.best.clone());
    let (mixture, v_best, kept_srt) = if evolution.best_v < v_srt {
        let mixture = evolution.best.to_mixture().with_nee(srt.nee);
        (mixture, evolution.best_v, false)
    } else {
        (srt.clone(), v_srt, true)
    };
    Outcome {
        mixture,
        v_best,
        v_evolved,
        kept_srt,
        history: evolution.history,
        evaluations,
        best,
    }
}

/// Replaces the best individual's weights with those that minimise its `V` on the test paths
/// ([`fitness::optimise_weights`]), and its `V` with theirs; with `prune`, then drops the
/// components that lower `V` by less than that share ([`fitness::prune_components`]) and
/// optimises the others' weights again. Returns the generators evaluated.
fn convex_weights(
    view: &SceneView,
    (ga, prune): (&GaConfig, Option<f64>),
    paths: &TestPaths,
    evolution: &mut Evolution,
) -> u64 {
    let best = &mut evolution.best;
    let densities: Vec<Vec<f64>> = best
        .genes
        .iter()
        .map(|gene| {
            let mut d = vec![0.0; paths.len()];
            paths.generator_pdfs(view, &gene.generator, &mut d);
            d
        })
        .collect();
    let refs: Vec<&[f64]> = densities.iter().map(|d| d.as_slice()).collect();
    let tests = (&paths.f2_over_q[..], paths.sampled);
    let mut v = fitness::optimise_weights(
        tests,
        &refs,
        &mut best.weights,
        ga.defensive_weight,
        CONVEX_STEPS,
    );
    if let (Some(tolerance), true) = (prune, v.is_finite()) {
        let settings = (ga.defensive_weight, v, tolerance);
        let (kept, weights) = fitness::prune_components(tests, &refs, &best.weights, settings);
        if kept.len() < refs.len() {
            let genes = std::mem::take(&mut best.genes);
            best.genes = genes
                .into_iter()
                .enumerate()
                .filter(|(i, _)| kept.contains(i))
                .map(|(_, g)| g)
                .collect();
            best.weights = weights;
            let refs: Vec<&[f64]> = kept.iter().map(|&i| refs[i]).collect();
            v = fitness::optimise_weights(
                tests,
                &refs,
                &mut best.weights,
                ga.defensive_weight,
                CONVEX_STEPS,
            );
        }
    }
    evolution.best_v = v;
    densities.len() as u64
}
