//! Building a plan ([`Plan::build`]) from what it is built from ([`PlanInputs`]): the grid,
//! the gate's pilot, the baseline and the GA pixels' waves.

use super::super::{GaConfig, GaConfigError};
use super::baseline::scattering_cells;
use super::config::{GateConfig, PlanConfig};
use super::context::PixelContext;
use super::pilot::{pilot_gain, pilot_pays, pilot_pixels, scout_pilot, PILOT_SHARE};
use super::stages::{LearnStore, PlanError};
use super::types::{PlanFor, PlanStats};
use super::waves::Waves;
use super::Plan;
use crate::film::PixelSums;
use crate::path::generator::{Nee, SrtAbsorption};
use crate::path::{mixture_file, SceneView};
use std::sync::OnceLock;
use std::time::Instant;

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
    /// are ([`stages`](super::stages)).
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
}
