//! The pixel plan of `--method ga` (design §7): which pixels run the genetic algorithm, and
//! which mixture every pixel renders with.
//!
//! 1. **Grid.** One ray through each pixel's centre tells whether it sees a scattering
//!    surface at all (pixels that see only background or an emitter need no GA: their value
//!    is emission seen directly). Each cell of a regular grid (`grid` pixels apart) gets a GA
//!    pixel at its centre or the scattering pixel closest to it.
//! 2. **Baseline and extra GA pixels.** A few `srt` samples per pixel estimate its relative
//!    variance; extra GA pixels go to the cells with the highest baseline relative variance,
//!    at their noisiest pixel. The samples are unbiased samples of the image, drawn from
//!    their own streams: the image keeps them ([`Plan::baseline`]), as `pg` keeps its
//!    training passes' (on fig1 at 2 s they were 0.33 s of a 0.65 s plan).
//! 3. **Evolution.** Per GA pixel, `M` test paths from the defensive `srt` density and the
//!    genetic algorithm on them, in parallel; every pixel has its own random streams, derived
//!    from the seed and the pixel alone, so the result does not depend on the thread count.
//!    A pixel keeps `srt` alone when the GA found nothing better on its test paths.
//! 4. **Interpolation.** Every pixel renders with the union of its nearest GA pixels'
//!    mixtures, each scaled by a normalised inverse-square distance weight: one mixture whose
//!    weights sum to 1, containing the defensive `srt` component, so the estimator stays
//!    unbiased.
//!
//! 5. **Gate** (beyond the paper; off with `GateConfig::gate = false`). The GA pays for
//!    itself only where its estimator beats path tracing at equal time, so each GA pixel
//!    (for a guide, each pilot pixel: see below) measures it: `GATE_SAMPLES` samples of
//!    `pt` and of the evolved estimator (the mixture for `ga`, the guided path tracer for
//!    `ga-pt`), and the predicted gain `Var_pt · cost_pt / (Var · cost)` with costs counted
//!    in rays and densities ([`RayCounts::cost`]), so that the plan stays deterministic.
//!    Pixels whose nearest GA pixels mostly predict a loss render with `pt`. The GA runs
//!    first at `PILOT_PIXELS` grid pixels spread over the image, for `1 / PILOT_SHARE` of
//!    the generations, before the baseline; unless at least half of them predict a gain,
//!    the other grid pixels are not evolved and become `pt` points, and the baseline is not
//!    run: the image renders with `pt`, for a guide except near a pilot pixel that does not
//!    predict a loss; with the spatial guide (`ga-pt`'s default) a failed pilot leaves
//!    every pixel to it, since the pilot compared the GA's guides with `pt`, not with the
//!    spatial guide (fig1, 2 s: 0.54 → 0.52 × `pt`, as `pg`); where it passes, the
//!    spatial guide's training passes try the guides against that guide alone
//!    ([`crate::integrators::pg::train_spatial`]). (A pilot that closes the
//!    plan when it fails — a mixture's, or a guide's beside the spatial guide — stops
//!    starting pixels once it cannot pay, so there it is `pt` or the spatial guide
//!    everywhere. cbox, `ga`, 64
//!    spp: the plan took 0.09–0.16 s of baseline and 0.16–0.26 s of GA with the baseline
//!    first, 0.01 s of grid rays and 0.16 s of GA with the pilot first.) Where they do, the pilot pixels go on from their best individuals
//!    (with a fresh random stream). For a guide the other GA pixels then run no trial and
//!    keep their guides: a guide keeps `pt`'s next-event estimation and BRDF sampling, so
//!    it rarely loses much, and on fig5 the trials cost 40 % of the GA phase while the
//!    pixels they sent to `pt` made the image no better. A mixture's variance can exceed
//!    `pt`'s many times, so there every GA pixel runs its trial. Low-variance cells
//!    (pruning) render with `pt` too.
//!
//! The test paths, the GA and the gate draw from streams disjoint from the final render's, so
//! the mixtures and choices do not depend on the samples they are used with.

mod baseline;
mod config;
mod gate;
mod interpolation;
mod pixel;
pub mod report;
mod stages;
mod waves;

pub use baseline::Origin;
pub use config::PlanConfig;
pub use gate::{
    gate_margins, GateConfig, Moments, Trial, COST_SAMPLES, GATE_SAMPLES, PILOT_PIXELS, PILOT_SHARE,
};
pub use pixel::{GaPixel, COMPONENT_TOLERANCE, CONVEX_STEPS, PRUNE_SHARE};
pub use stages::{LearnStore, PlanError, WaveEntry};

use super::nearest::PointGrid;
use super::{GaConfig, GaConfigError};
use crate::film::PixelSums;
use crate::path::generator::{Nee, SrtAbsorption};
use crate::path::mixture::Mixture;
use crate::path::{mixture_file, RayCounts, SceneView};
use crate::scene::SceneAnalysis;
use baseline::scattering_cells;
use gate::{pilot_gain, pilot_pays, pilot_pixels, scout_pilot};
use pixel::{Evolved, PixelContext};
use std::sync::OnceLock;
use std::time::{Duration, Instant};
use waves::Waves;

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

/// What a plan is built from: the settings of the GA, of the plan and of the gate, the
/// estimator it is for, and what the scene's paths are.
#[derive(Clone, Copy, Debug)]
pub struct PlanInputs<'a> {
    pub ga: &'a GaConfig,
    pub plan: &'a PlanConfig,
    pub gate: GateConfig,
    pub plan_for: PlanFor,
    pub max_bounces: u32,
    /// Absorption of the defensive `srt` generator.
    pub srt_absorption: SrtAbsorption,
    /// The estimator a mixture plan's test paths, fitness and mixtures are those of (a
    /// guide's GA keeps the end-only one).
    pub nee: Nee,
    /// A spatial guide takes over where the plan's guides do not (`ga-pt` with
    /// `spatial_guide`), so a failed pilot leaves every pixel to it.
    pub spatial_guide: bool,
    /// Where the GA pixels' waves are kept between processes (`genpath learn`), if they
    /// are ([`stages`]).
    pub store: Option<&'a dyn LearnStore>,
}

impl<'a> PlanInputs<'a> {
    /// A plan for `plan_for` with `ga` and `plan`, and the defaults of the other settings:
    /// the gate on, the default `srt` absorption, and for a guide the spatial guide.
    pub fn new(
        ga: &'a GaConfig,
        plan: &'a PlanConfig,
        plan_for: PlanFor,
        max_bounces: u32,
    ) -> Self {
        Self {
            ga,
            plan,
            gate: GateConfig::default(),
            plan_for,
            max_bounces,
            srt_absorption: plan_for
                .test_path_nee(Nee::default())
                .default_srt_absorption(),
            nee: Nee::default(),
            spatial_guide: plan_for == PlanFor::Guide,
            store: None,
        }
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
    /// Samples per pixel of the baseline that the image keeps ([`Plan::settle_baseline`]).
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
    fn count_pixels(
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

/// The default of `PlanConfig::baseline_keep_ratio`. Averaged with equal weights, `b`
/// samples of variance `r σ²` beside `n` of variance `σ²` lower the variance of the mean
/// while `r < 2 + b/n`. (Test paths at 256², seed 401: the median of `V_srt / V_best` is 1.16
/// on fig1, 1.37 on cbox, 2.25 on glossy and 5.6 on fig5.)
pub const BASELINE_KEEP_RATIO: f64 = 2.0;

/// GA pixels and their mixtures, and how every other pixel combines them. It serialises
/// (a plan file, `genpath learn`) without its lookup index, which is rebuilt on first use.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Plan {
    width: u32,
    height: u32,
    pub pixels: Vec<GaPixel>,
    /// Points where the image renders with the plan's fallback, interpolated like GA
    /// pixels: one pixel of each low-variance cell, and with the gate the GA pixels the
    /// pilot or the time limit left out. The fallback is `pt` with the gate, the defensive
    /// `srt` mixture without it (the paper's estimator: a cell whose `srt` samples the
    /// baseline found quiet gets no GA pixel, and an evolved mixture from another cell
    /// would cost its densities there for samplers aimed elsewhere).
    pub fallback_points: Vec<(u32, u32)>,
    gate: bool,
    /// The gate's pilot showed that the mixture does not pay: every pixel renders with `pt`
    /// (or the spatial guide). (A guide's failed pilot without the spatial guide keeps its
    /// guides near pilot pixels that predict no loss.)
    closed: bool,
    pub plan_for: PlanFor,
    /// The defensive density alone: the mixture of an image without any GA pixel.
    pub srt: Mixture,
    neighbours: usize,
    /// What the scene contains.
    pub analysis: SceneAnalysis,
    /// Fault injection for statistical tests: leave the interpolation weights unnormalised.
    unnormalised: bool,
    pub stats: PlanStats,
    /// The per-pixel sums of the baseline's `srt` samples (none where it did not run, or
    /// where the image does not keep them: [`Self::settle_baseline`]): unbiased samples of
    /// the image, which `ga` keeps as `pg` keeps its training passes'.
    pub baseline: PixelSums,
    /// `pixels` and then `fallback_points`, bucketed for [`Self::interpolation`] on first use.
    #[serde(skip)]
    index: OnceLock<PointGrid>,
}

impl Plan {
    /// Picks the GA pixels (the grid's, then, after the baseline, the extras) and evolves
    /// each of them (in parallel on the current rayon pool), with progress bars on stderr
    /// when `progress`; with the gate, runs the pilot first and compares the evolved
    /// estimator for `plan_for` with `pt` at each pixel that runs a trial.
    pub fn build(
        view: &SceneView,
        inputs: &PlanInputs,
        seed: u64,
        progress: bool,
    ) -> Result<Self, PlanError> {
        let PlanInputs {
            plan: config,
            max_bounces,
            plan_for,
            ..
        } = *inputs;
        let gate = inputs.gate.gate;
        let ga = &GaConfig {
            srt_absorption: inputs.srt_absorption,
            nee: inputs.nee,
            ..inputs.ga.clone()
        };
        ga.validate()?;
        config.validate()?;
        if let (Some(_), Some(limit)) = (inputs.store, config.time_limit) {
            // Which pixels a time limit leaves out depends on the machine and its load.
            return Err(GaConfigError(format!(
                "ga_time_limit {limit}: a plan learned by `genpath learn` must not depend on \
                 time (its waves are kept and may be split over jobs); leave it out"
            ))
            .into());
        }
        let scene = view.scene;
        let (width, height) = (scene.camera.width, scene.camera.height);
        let nee = plan_for.test_path_nee(ga.nee);
        let srt = mixture_file::srt(scene, max_bounces, ga.srt_absorption).with_nee(nee);
        let mut stats = PlanStats::default();

        let t0 = Instant::now();
        let cells = scattering_cells(view, config.grid(plan_for), &mut stats);
        let grid: Vec<(u32, u32)> = cells.iter().flatten().copied().collect();
        let grid_seconds = t0.elapsed().as_secs_f64();

        let t1 = Instant::now();
        let context = PixelContext {
            view,
            srt: &srt,
            ga,
            config,
            max_bounces,
            plan_for,
            gate,
            seed,
            store: inputs.store,
        };
        let mut waves = Waves::new(&context, pilot_pixels(&grid, gate), progress, t0);
        let scout = ga.generations.div_ceil(PILOT_SHARE);
        // Whether a pilot that fails leaves every pixel to `pt` or the spatial guide.
        let closes = plan_for == PlanFor::Mixture || inputs.spatial_guide;
        scout_pilot(&mut waves, scout, closes)?;
        stats.pilot_gain = pilot_gain(&waves);
        let pilot_pays = pilot_pays(&waves);
        let closed = gate && !pilot_pays && closes;
        let mut fallback_points = Vec::new();
        // Seconds of the baseline, which runs between GA waves.
        let (baseline_part, baseline) = if !gate || pilot_pays {
            waves.past_pilot(&cells, scout, &mut stats, &mut fallback_points)?
        } else {
            waves.leave_to_pt(&grid, &mut stats, &mut fallback_points);
            (0.0, PixelSums::default())
        };
        if inputs.store.is_some_and(|s| s.split()) {
            return Err(PlanError::ShareDone {
                wave: None,
                evolved: 0,
                missing: 0,
            });
        }
        let (results, scouted) = waves.finish();
        stats.baseline_seconds = grid_seconds + baseline_part;
        stats.ga_seconds = t1.elapsed().as_secs_f64() - baseline_part;
        let pixels = stats.count_pixels(&scouted, results, gate, plan_for);
        Ok(Self {
            width,
            height,
            pixels,
            fallback_points,
            gate,
            closed,
            plan_for,
            srt,
            neighbours: config.neighbours(plan_for),
            analysis: scene.analysis(),
            unnormalised: false,
            stats,
            baseline,
            index: OnceLock::new(),
        })
    }

    #[cfg(any(test, feature = "testing"))]
    /// This plan with its interpolation weights deliberately left unnormalised: a wrong input
    /// that the unbiasedness test must reject.
    pub fn with_unnormalised_interpolation(mut self) -> Self {
        self.unnormalised = true;
        self
    }

    #[cfg(any(test, feature = "testing"))]
    /// This plan with every mixture's light-technique densities left out when evaluated
    /// (`Mixture::with_light_density_dropped`): a wrong input that the unbiasedness test
    /// must reject.
    pub fn with_light_density_dropped(mut self) -> Self {
        self.srt = self.srt.with_light_density_dropped();
        for p in &mut self.pixels {
            p.mixture = p.mixture.clone().with_light_density_dropped();
        }
        self
    }

    /// Whether no pixel renders with the plan's mixtures or guides (the gate's pilot
    /// closed the GA).
    pub fn is_closed(&self) -> bool {
        self.closed
    }

    pub fn width(&self) -> u32 {
        self.width
    }

    pub fn height(&self) -> u32 {
        self.height
    }

    /// Keeps the baseline's samples for an image of `spp` samples per pixel where they lower
    /// its error: a mixture's plan ([`PlanFor::Mixture`]) whose baseline `spp` holds, and
    /// whose GA pixels' test paths show `srt` at most `keep_ratio` times the evolved
    /// mixtures' variance (the median over the GA pixels of eq. 10's `V_srt / V_best`;
    /// [`BASELINE_KEEP_RATIO`]). Else it drops them and the image takes all its samples
    /// itself. The choice depends on the test paths alone, drawn from their own streams, so
    /// the image stays unbiased. A guide's plan (`ga-pt`) keeps none: the test paths do not
    /// measure its guided path tracer, and on fig5 at 2 s its 4 baseline samples among
    /// about 45 raised `ga-pt`'s error from 0.33 to 1.12 × `pt`'s.
    pub fn settle_baseline(&mut self, spp: u32, keep_ratio: f64) {
        let mut ratios: Vec<f64> = (self.pixels.iter())
            .filter(|p| p.v_best > 0.0)
            .map(|p| p.v_srt / p.v_best)
            .collect();
        ratios.sort_by(f64::total_cmp);
        let srt_near = ratios
            .get(ratios.len() / 2)
            .is_none_or(|&r| r <= keep_ratio);
        let keep = self.plan_for == PlanFor::Mixture && self.baseline.spp <= spp && srt_near;
        if !keep {
            self.baseline = PixelSums::default();
        }
        self.stats.baseline_kept_spp = self.baseline.spp;
    }

    /// The baseline's samples, if the plan has any.
    pub fn baseline(&self) -> Option<&PixelSums> {
        (self.baseline.spp > 0).then_some(&self.baseline)
    }

    /// Wall-clock time of the whole plan (baseline and GA).
    pub fn elapsed(&self) -> Duration {
        Duration::from_secs_f64(self.stats.baseline_seconds + self.stats.ga_seconds)
    }
}
