//! The data the plan's files share: the estimator a plan is for ([`PlanFor`]), a GA pixel's
//! outcome ([`GaPixel`]) with the gate's trial of it ([`Trial`], from [`Moments`]) and the
//! gate's margins, and the plan's per-phase totals ([`PlanStats`]).

use super::super::individual::Individual;
use super::super::population::GenerationStats;
use crate::path::generator::Nee;
use crate::path::mixture::Mixture;
use crate::path::RayCounts;

/// The estimator a plan is built for, which its GA pixels evolve and its gate compares with
/// `pt`: the plan's mixtures are either what the pixels sample from, or what guides their path
/// tracer. (`PlanInputs { plan_for: PlanFor::Guide, … }` reads "a plan for a guide".)
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PlanFor {
    /// `ga`: the mixture estimator (eq. 8).
    Mixture,
    /// `ga-pt`: path tracing guided by the mixture.
    Guide,
}

impl PlanFor {
    /// The estimator of the GA's test paths, fitness and mixtures for the estimators' `nee`:
    /// a guide's GA keeps the end-only one, with which `ga-pt` was tuned (the guided path
    /// tracer does its own next-event estimation).
    pub fn test_path_nee(self, nee: Nee) -> Nee {
        match self {
            PlanFor::Mixture => nee,
            PlanFor::Guide => Nee::End,
        }
    }
}

/// Why a GA pixel was chosen.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Origin {
    Grid,
    /// High baseline variance.
    Extra,
}

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

/// The gate's thresholds on a trial's predicted gain: `(lose, win)`. The GA goes on past
/// the pilot only if at least half the pilot pixels predict a gain above `win`; a GA pixel
/// prefers `pt` where it predicts one below `lose`.
///
/// The guided path tracer keeps `pt`'s next-event estimation and its BRDF sampling (at the
/// defensive weight), so it rarely loses much, while its 2048-sample trial is noisy enough
/// that sending every pixel below the winning margin to `pt` made the image worse than no
/// gate: it must win by 1.25 and is dropped below 0.8. The mixture estimator's prediction
/// is the less certain, and its variance grows faster away from the GA pixel and can
/// exceed `pt`'s many times: it must win by 2 everywhere. (reports/README.md,
/// "Measurements formerly in code comments (2026-12-07)", `gate_margins`.)
pub fn gate_margins(plan_for: PlanFor) -> (f64, f64) {
    match plan_for {
        PlanFor::Guide => (0.8, 1.25),
        PlanFor::Mixture => (2.0, 2.0),
    }
}

/// One estimator's samples at a pixel, per sample: mean and variance under the pixel's
/// [`ChannelWeights`](super::super::ChannelWeights) (`√(Σ_c w_c mean_c²)` and
/// `Σ_c w_c Var_c`), and the cost ([`RayCounts::cost`]).
#[derive(Clone, Copy, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct Moments {
    pub mean: f64,
    pub variance: f64,
    pub cost: f64,
    /// The standard error of `variance` over `variance` (0 where not measured): from the
    /// samples' fourth central moment, `√((μ₄ − σ⁴) / n) / σ²` per channel.
    #[serde(default)]
    pub variance_error: f64,
}

impl Moments {
    /// `1 / (variance × cost)`; infinite without variance.
    pub(super) fn efficiency(&self) -> f64 {
        1.0 / (self.variance * self.cost)
    }
}

/// The gate's comparison at a GA pixel.
#[derive(Clone, Copy, Debug, serde::Serialize, serde::Deserialize)]
pub struct Trial {
    pub pt: Moments,
    pub evolved: Moments,
    /// `evolved`'s efficiency over `pt`'s; 0 where neither has variance (nothing to gain).
    pub gain: f64,
}

impl Trial {
    /// The gain one standard error below its estimate, on a log scale: `gain · e^(−ε)`, `ε`
    /// the two variances' relative standard errors added in quadrature
    /// ([`Moments::variance_error`]).
    ///
    /// A guide's pilot counts this against the winning margin. Its 2048-sample variances are
    /// heavy-tailed where rare paths carry the light, so the estimate alone lets a pilot
    /// pass on scenes where the GA then loses to `pg`; one standard error below stops those
    /// pilots and keeps the ones that pay (docs/methods/ga.md, "The gate";
    /// reports/README.md, "`ga-pt`'s cautious pilot
    /// (2026-12-05)").
    pub fn cautious_gain(&self) -> f64 {
        let error = self.pt.variance_error.hypot(self.evolved.variance_error);
        self.gain * (-error).exp()
    }
}

/// Per-phase totals of a plan.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct PlanStats {
    /// Wall-clock seconds of the grid rays and the baseline pass (none where the gate's
    /// pilot closes the GA), and of the GA phase (test paths included).
    pub baseline_seconds: f64,
    pub ga_seconds: f64,
    /// Summed over GA pixels (CPU seconds): tracing test paths, and evolving.
    pub test_path_cpu_seconds: f64,
    pub evolve_cpu_seconds: f64,
    /// Pixels whose centre ray sees no scattering surface (background or emitters only).
    pub skipped_pixels: usize,
    /// Grid cells without a scattering pixel, hence without a GA pixel.
    pub empty_cells: usize,
    /// Grid cells left without a GA pixel because their baseline variance is low (pruning;
    /// 0 where the pilot closed the GA and no baseline ran).
    pub low_variance_cells: usize,
    /// Grid pixels not evolved because fewer than half the pilot pixels predicted a gain
    /// over `pt` (gate).
    pub gated_pixels: usize,
    /// The geometric mean of the scouted pilot pixels' predicted gains over `pt` (0 without
    /// a pilot).
    #[serde(default)]
    pub pilot_gain: f64,
    /// GA pixels whose evolved estimator is predicted to lose to `pt` (or that kept `srt`).
    pub pt_pixels: usize,
    /// GA pixels not evolved because the plan reached `PlanConfig::time_limit`.
    pub time_limited_pixels: usize,
    /// Whether the baseline ran: not where the gate's pilot closed the GA.
    pub baseline_ran: bool,
    /// Samples per pixel of the baseline that the image keeps
    /// ([`Plan::settle_baseline`](super::Plan::settle_baseline)).
    pub baseline_kept_spp: u32,
    /// Pooled baseline relative variance (one srt sample, `Var/(mean² + 0.01)` over the
    /// cell's samples) of the cells with a scattering pixel: smallest, median, largest.
    pub cell_variance: [f64; 3],
    pub individual_evaluations: u64,
    pub generator_evaluations: u64,
    pub rays: RayCounts,
}

impl PlanStats {
    /// Adds the GA pixels' work to the totals, that of the pilot's `scouted` runs (which the
    /// pixels that went on replaced) included, and counts the pixels that prefer `pt` with
    /// the gate; returns the pixels.
    pub(super) fn count_pixels(
        &mut self,
        scouted: &[Evolved],
        results: Vec<Evolved>,
        gate: bool,
        plan_for: PlanFor,
    ) -> Vec<GaPixel> {
        for (p, counts) in scouted
            .iter()
            .map(|(p, c)| (p, *c))
            .chain(results.iter().map(|(p, c)| (p, *c)))
        {
            self.rays.add(counts);
            self.test_path_cpu_seconds += p.test_path_seconds;
            self.evolve_cpu_seconds += p.ga_seconds;
            self.individual_evaluations += p.individual_evaluations;
            self.generator_evaluations += p.generator_evaluations;
        }
        let mut pixels = Vec::with_capacity(results.len());
        for (p, _) in results {
            if gate && p.prefers_pt(plan_for) {
                self.pt_pixels += 1;
            }
            pixels.push(p);
        }
        pixels
    }
}
