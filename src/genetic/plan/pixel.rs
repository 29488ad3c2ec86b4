//! One GA pixel: its test paths, the genetic algorithm on them, the choice between the best
//! individual and `srt`, and the gate's trial ([`GaPixel`]).

use super::super::individual::Individual;
use super::super::population::{evolve_from, Evolution, GenerationStats};
use super::super::test_paths::TestPaths;
use super::super::{fitness, GaConfig};
use super::context::{GaRun, PixelContext};
use super::gate::run_trial;
use super::types::{Evolved, GaPixel, Origin, PlanFor};
use crate::path::generator::Nee;
use crate::path::mixture::Mixture;
use crate::path::{RayCounts, SceneView};
use crate::sampling::{derived_seed, sample_rng, Stream};
use std::time::Instant;

/// With pruning, generators get the steps that carry all but this share of the test paths'
/// `Σ F²/q`: none, so steps are cut only past the deepest light-carrying test path. (Where
/// few test paths carry light, as on fig5, they are too few to call a depth's share
/// negligible, and a share above 0 made the image worse: reports/README.md, "Measurements
/// formerly in code comments (2026-12-07)", `PRUNE_SHARE`.)
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
/// vertex of every path of every pixel whose mixture holds it (at
/// [`crate::path::DENSITY_COST`] each), and the weight steps never drop one; this share
/// leaves out most of them for little more error, where a larger one raised the error
/// (reports/README.md, "Measurements formerly in code comments (2026-12-07)",
/// `COMPONENT_TOLERANCE`; docs/methods/ga.md, "Convex mixture weights"). `ga-pt`'s guides
/// keep theirs (its images stay as they were), and so does the paper's end-only estimator
/// (`--nee end`), whose rare large contributions the test paths' `V` sees too seldom to
/// prune by (the same bullet of reports/README.md).
pub const COMPONENT_TOLERANCE: f64 = 0.02;

/// With `GaConfig::held_out`, the placement paths stop at `max_light_paths /
/// PLACEMENT_SHARE` light-carrying ones: anchors and patches need where light went, not
/// eq. 10's precision. With next-event estimation at every vertex most test paths carry
/// light and this costs a few hundred paths; `ga-pt`'s end-only test paths seldom do, so
/// that there a held-out set costs as much as the first (see `GaConfig::held_out`, and
/// docs/methods/ga.md, "Held-out placement").
pub const PLACEMENT_SHARE: usize = 4;

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
