//! The plan's settings ([`PlanConfig`]): where the GA runs, how its results spread over the
//! image, and its time limit (the gate's settings are [`GateConfig`], the
//! spatial guide's `integrators::settings::SpatialConfig`).

use super::super::GaConfigError;
use super::types::PlanFor;

/// The gate's settings, table `[gate]`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GateConfig {
    /// Render with `pt` wherever the evolved estimator is predicted to lose to it, and skip
    /// the GA when a pilot predicts no gain anywhere (see the module documentation of
    /// `genetic::plan`).
    pub gate: bool,
}

impl Default for GateConfig {
    fn default() -> Self {
        Self { gate: true }
    }
}

/// Where the genetic algorithm runs and how its results spread over the image.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PlanConfig {
    /// Distance between grid GA pixels, in pixels, along both axes. `None`: 32 for `ga`, 64
    /// for `ga-pt` ([`Self::grid`]).
    #[serde(rename = "ga_grid")]
    pub grid: Option<u32>,
    /// Extra GA pixels at high baseline variance, as a fraction of the grid pixels.
    #[serde(rename = "ga_extra")]
    pub extra: f64,
    /// `srt` samples per pixel of the baseline pass.
    pub baseline_spp: u32,
    /// `ga` keeps the baseline's samples in the image where its GA pixels' test paths show
    /// `srt`'s variance at most this many times the evolved mixtures' (median over the GA
    /// pixels; [`super::Plan::settle_baseline`]): 0 never keeps them, `inf` always.
    pub baseline_keep_ratio: f64,
    /// GA pixels whose mixtures each pixel combines (and whose best individuals start a
    /// warm-started GA pixel's population). `None`: 2 for `ga`, 4 for `ga-pt`. The union of
    /// `k` mixtures costs `ga` every component's densities on every path it samples, while
    /// `ga-pt` blends only the guides' first steps: at 2 s, six seeds, `ga --no-gate` with 2
    /// has 0.87 (fig5), 0.83 (fig1), 0.92 (glossy), 0.83 (cbox) × its relMSE with 4, and
    /// `ga-pt` with 2 has 1.11, 1.10, 1.22 × its relMSE with 4 (fig5, fig1, glossy; see
    /// docs/methods.md).
    #[serde(rename = "ga_neighbours")]
    pub neighbours: Option<usize>,
    /// Leave out what the scene does not need: cells whose baseline relative variance is
    /// below `prune_variance` get no GA pixel, and evolved generators get only the steps the
    /// test paths need (`TestPaths::steps_needed`; for `ga-pt` also at most `guide_steps`,
    /// pruning or not), and `ga`'s evolved mixtures only the components that pay for their
    /// densities (`pixel::COMPONENT_TOLERANCE`).
    pub prune: bool,
    pub prune_variance: f64,
    /// Evolve half the GA pixels first, then the others from their evolved neighbours' best
    /// individuals, with half the generations (beyond the paper).
    pub warm_start: bool,
    /// Wall-clock seconds the plan (baseline included) may take: past them, GA pixels not
    /// yet evolved are left out (to `pt` with the gate in a plan for the mixture, to their
    /// neighbours' mixtures otherwise). The GA then runs in chunks and the plan depends on
    /// timing, not only on the seed. `None`: no limit.
    #[serde(rename = "ga_time_limit")]
    pub time_limit: Option<f64>,
    /// `ga-pt`: vertices the guide steers, i.e. the directional steps the GA evolves (at
    /// most what the test paths need). Path tracing's next-event estimation already finds
    /// the light from the vertices after the first, and one step leaves the GA a search
    /// space it explores in its generations: on fig5 at 64 spp, relMSE 0.391 / 0.376 /
    /// 0.384 (seeds 7 / 11 / 13) against 0.433 / 0.362 / 0.795 (the pilot closed) with
    /// every step the test paths need.
    pub guide_steps: usize,
    /// A GA pixel's test paths start in the square of `footprint × ga_grid` pixels centred
    /// on it (at least the pixel itself): the pixels its mixture renders with its
    /// neighbours', rather than that pixel alone (beyond the paper). 0: the pixel (the
    /// paper's). `None`: 1 for `ga`, 0 for `ga-pt` (whose guides the footprint let through
    /// the pilot on glossy, to 1.26 × `pg`'s error at 2 s against 1.15 × without; see
    /// docs/methods.md).
    pub footprint: Option<f64>,
}

impl Default for PlanConfig {
    fn default() -> Self {
        Self {
            grid: None,
            extra: 0.25,
            baseline_spp: 4,
            baseline_keep_ratio: super::BASELINE_KEEP_RATIO,
            neighbours: None,
            prune: true,
            prune_variance: 0.5,
            warm_start: true,
            time_limit: None,
            guide_steps: 1,
            footprint: None,
        }
    }
}

impl PlanConfig {
    /// The side, in pixels, of the square a GA pixel's test paths start in, in a plan for
    /// the mixture estimator (`ga`) or for guides (`ga-pt`).
    pub fn footprint_pixels(&self, plan_for: PlanFor) -> f32 {
        let share = self.footprint.unwrap_or(match plan_for {
            PlanFor::Mixture => 1.0,
            PlanFor::Guide => 0.0,
        });
        (share * f64::from(self.grid(plan_for))).max(1.0) as f32
    }

    /// Distance between grid GA pixels in a plan for `plan_for`. `ga-pt`'s guides beside
    /// the spatial guide pay for fewer GA pixels: at 256² its GA phase then takes 0.14 s of a
    /// 2 s budget on fig5 instead of 0.27 s, and its relMSE over `pg`'s at 2 s (geometric
    /// mean over seeds 401–406, and 407–412) is 0.603 and 0.579 against 0.653 and 0.647 with
    /// 32, at 8 and 30 s (seed 101) 0.536 and 0.578 against 0.566 and 0.584; on fig1, cbox
    /// and glossy within 2 % of it either way (docs/methods.md).
    pub fn grid(&self, plan_for: PlanFor) -> u32 {
        self.grid.unwrap_or(match plan_for {
            PlanFor::Mixture => 32,
            PlanFor::Guide => 64,
        })
    }

    /// GA pixels whose mixtures each pixel combines in a plan for `plan_for`.
    pub fn neighbours(&self, plan_for: PlanFor) -> usize {
        self.neighbours.unwrap_or(match plan_for {
            PlanFor::Mixture => 2,
            PlanFor::Guide => 4,
        })
    }

    pub fn validate(&self) -> Result<(), GaConfigError> {
        let fail = |m: String| Err(GaConfigError(m));
        if self.grid == Some(0) {
            return fail("the GA grid spacing must be at least 1 pixel".into());
        }
        if !(self.extra.is_finite() && (0.0..=16.0).contains(&self.extra)) {
            return fail(format!("extra GA pixels {} is not in [0, 16]", self.extra));
        }
        if self.baseline_spp == 0 {
            return fail("the baseline needs at least 1 sample per pixel".into());
        }
        if self.baseline_keep_ratio.is_nan() || self.baseline_keep_ratio < 0.0 {
            return fail(format!(
                "baseline keep ratio {} must be ≥ 0 (inf: always keep)",
                self.baseline_keep_ratio
            ));
        }
        if !(self.prune_variance.is_finite() && self.prune_variance >= 0.0) {
            return fail(format!(
                "prune variance {} must be finite and ≥ 0",
                self.prune_variance
            ));
        }
        // A time limit must be a finite, non-negative number of seconds.
        let bad_seconds = |limit: Option<f64>| limit.is_some_and(|t| !(t.is_finite() && t >= 0.0));
        if bad_seconds(self.time_limit) {
            return fail(format!(
                "GA time limit {:?} must be finite and ≥ 0 seconds",
                self.time_limit
            ));
        }
        if let Some(f) = self
            .footprint
            .filter(|f| !(f.is_finite() && (0.0..=16.0).contains(f)))
        {
            return fail(format!(
                "test-path footprint {f} is not in [0, 16] grid spacings"
            ));
        }
        if !(1..=64).contains(&self.guide_steps) {
            return fail(format!(
                "guide steps {} is not in [1, 64]",
                self.guide_steps
            ));
        }
        if let Some(k) = self.neighbours.filter(|k| !(1..=64).contains(k)) {
            return fail(format!("GA neighbours per pixel {k} is not in [1, 64]"));
        }
        Ok(())
    }
}
