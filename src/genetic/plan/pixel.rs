//! One GA pixel: its test paths, the genetic algorithm on them, the choice between the best
//! individual and `srt`, and the gate's trial ([`GaPixel`]).

use super::super::individual::Individual;
use super::super::population::{evolve_from, GenerationStats};
use super::super::test_paths::TestPaths;
use super::super::{fitness, GaConfig};
use super::baseline::Origin;
use super::config::PlanConfig;
use super::gate::{gate_margins, run_trial, Trial};
use super::PlanFor;
use crate::path::mixture::Mixture;
use crate::path::{RayCounts, SceneView};
use crate::sampling::{derived_seed, sample_rng, Stream};
use std::time::Instant;

/// With pruning, generators get the steps that carry all but this share of the test paths'
/// `Σ F²/q`: none, so steps are cut only past the deepest light-carrying test path. (Cutting
/// at 0.1 % made fig5 worse, 4.14 against 2.70 relMSE at 128², 64 spp: with M = 10 000 only
/// ~100 test paths carry light, too few to call a depth's share negligible.)
pub const PRUNE_SHARE: f64 = 0.0;

/// Iterations of [`fitness::optimise_weights`] with `GaConfig::convex_weights` (each costs
/// two passes over the light-carrying test paths per generator; it stops earlier once `V`
/// stops falling).
pub const CONVEX_ITERATIONS: usize = 200;

/// The outcome of the genetic algorithm at one pixel.
#[derive(Clone, Debug, serde::Serialize)]
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
    /// here by the winning margin ([`gate_margins`]).
    pub fn pays(&self, plan_for: PlanFor) -> bool {
        self.trial
            .is_some_and(|t| t.gain > gate_margins(plan_for).1)
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

/// Test paths and evolution at one pixel.
#[allow(clippy::too_many_arguments)]
pub(super) fn run_pixel(
    view: &SceneView,
    srt: &Mixture,
    ga: &GaConfig,
    (x, y, origin): (u32, u32, Origin),
    max_bounces: u32,
    seed: u64,
    (config, plan_for): (&PlanConfig, PlanFor),
    (seeds, generations, stream, trial): (&[Individual], usize, u64, bool),
) -> (GaPixel, RayCounts) {
    let t0 = Instant::now();
    let (paths, mut counts) = TestPaths::sample_until(
        view,
        srt,
        (x, y),
        (ga.test_paths, ga.max_light_paths),
        max_bounces,
        derived_seed(seed, Stream::TestPaths.tag()),
    );
    let test_path_seconds = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let pixel = y as u64 * view.scene.camera.width as u64 + x as u64;
    let mut rng = sample_rng(derived_seed(seed, Stream::Ga.tag()), pixel, stream);
    let v_srt = fitness::second_moment(view, &paths, srt);
    // Pruning: no generator step past the depth where the test paths carry light.
    // A guide takes only the directional samplers.
    let ga = &GaConfig {
        directions_only: ga.directions_only || plan_for == PlanFor::Guide,
        max_steps: match (
            plan_for,
            config.prune.then(|| paths.steps_needed(PRUNE_SHARE)),
        ) {
            (PlanFor::Guide, needed) => Some(needed.unwrap_or(usize::MAX).min(config.guide_steps)),
            (PlanFor::Mixture, needed) => needed,
        },
        generations,
        ..ga.clone()
    };
    let steps = ga
        .max_steps
        .unwrap_or(usize::MAX)
        .min(max_bounces.saturating_sub(1).max(1) as usize);
    let mut best = None;
    let (mixture, v_best, v_evolved, kept_srt, history, evals) = if paths.is_empty() {
        (srt.clone(), v_srt, v_srt, true, Vec::new(), (0, 0))
    } else {
        let mut evolution = evolve_from(ga, &paths, view, &mut rng, seeds);
        let v_evolved = evolution.best_v;
        let mut evals = (
            evolution.individual_evaluations,
            evolution.generator_evaluations,
        );
        if ga.convex_weights && v_evolved.is_finite() {
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
            evals.1 += densities.len() as u64;
            let refs: Vec<&[f64]> = densities.iter().map(|d| d.as_slice()).collect();
            let v = fitness::optimise_weights(
                (&paths.f2_over_q, paths.sampled),
                &refs,
                &mut best.weights,
                ga.defensive_weight,
                CONVEX_ITERATIONS,
            );
            evolution.best_v = v;
        }
        best = Some(evolution.best.clone());
        if evolution.best_v < v_srt {
            (
                evolution.best.to_mixture(),
                evolution.best_v,
                v_evolved,
                false,
                evolution.history,
                evals,
            )
        } else {
            (
                srt.clone(),
                v_srt,
                v_evolved,
                true,
                evolution.history,
                evals,
            )
        }
    };
    let trial = (config.gate && trial && !kept_srt).then(|| {
        let evolved = (ga, &mixture);
        run_trial(
            view,
            srt,
            evolved,
            (plan_for, paths.weights()),
            (x, y),
            max_bounces,
            seed,
            &mut counts,
        )
    });
    let pixel = GaPixel {
        x,
        y,
        origin,
        best,
        warm: !seeds.is_empty(),
        trial,
        steps,
        mixture,
        v_srt,
        v_best,
        v_evolved,
        kept_srt,
        test_paths: paths.sampled,
        light_paths: paths.len(),
        history,
        individual_evaluations: evals.0,
        generator_evaluations: evals.1,
        test_path_seconds,
        ga_seconds: t1.elapsed().as_secs_f64(),
    };
    (pixel, counts)
}
