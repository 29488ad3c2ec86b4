//! The pixel plan of `--method ga`: which pixels run the genetic algorithm, and
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
//!    training passes', since they are a large share of the plan's time (reports/README.md,
//!    "Measurements formerly in code comments (2026-12-07)", `genetic::plan`'s baseline).
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
//!    in rays and densities ([`RayCounts::cost`](crate::path::RayCounts::cost)), so that
//!    the plan stays deterministic.
//!    Pixels whose nearest GA pixels mostly predict a loss render with `pt`. The GA runs
//!    first at `PILOT_PIXELS` grid pixels spread over the image, for `1 / PILOT_SHARE` of
//!    the generations, before the baseline; unless at least half of them predict a gain,
//!    the other grid pixels are not evolved and become `pt` points, and the baseline is not
//!    run: the image renders with `pt`, for a guide except near a pilot pixel that does not
//!    predict a loss; with the spatial guide (`ga-pt`'s default) a failed pilot leaves
//!    every pixel to it, since the pilot compared the GA's guides with `pt`, not with the
//!    spatial guide, and the guides it kept were worse than the spatial guide alone
//!    (reports/README.md, "Results", "What changed between de6d183 and ebcb7fc", item 3);
//!    where it passes, the spatial guide's training passes try the guides against that
//!    guide alone (`integrators::pg::train_spatial`). (A pilot that closes the plan when it
//!    fails — a mixture's, or a guide's beside the spatial guide — stops starting pixels
//!    once it cannot pay, so there it is `pt` or the spatial guide everywhere. The pilot
//!    runs before the baseline so that a scene where the GA cannot pay spends nothing on a
//!    baseline: reports/README.md, "Measurements formerly in code comments (2026-12-07)",
//!    `genetic::plan`'s pilot.) Where they do, the pilot pixels go on from their best
//!    individuals (with a fresh random stream). For a guide the other GA pixels then run
//!    no trial and keep their guides: a guide keeps `pt`'s next-event estimation and BRDF
//!    sampling, so it rarely loses much, and the trials cost a large share of the GA phase
//!    for no better image (docs/methods/ga.md, "The gate"). A mixture's variance can
//!    exceed `pt`'s many times, so there every GA pixel runs its trial. Low-variance cells
//!    (pruning) render with `pt` too.
//!
//! The test paths, the GA and the gate draw from streams disjoint from the final render's, so
//! the mixtures and choices do not depend on the samples they are used with.

mod baseline;
mod build;
mod config;
mod context;
mod gate;
mod interpolation;
mod pilot;
mod pixel;
pub mod report;
mod stages;
mod types;
mod waves;

pub use build::PlanInputs;
pub use config::{GateConfig, PlanConfig};
pub use gate::{COST_SAMPLES, GATE_SAMPLES};
pub use pilot::{PILOT_PIXELS, PILOT_SHARE};
pub use pixel::{COMPONENT_TOLERANCE, CONVEX_STEPS, PRUNE_SHARE};
pub use stages::{LearnStore, PlanError, StoreError, WaveEntry};
pub use types::{gate_margins, GaPixel, Moments, Origin, PlanFor, PlanStats, Trial};

use super::nearest::PointGrid;
use crate::film::PixelSums;
use crate::path::mixture::Mixture;
use crate::scene::SceneAnalysis;
use std::sync::OnceLock;
use std::time::Duration;

/// The default of `PlanConfig::baseline_keep_ratio`. Averaged with equal weights, `b`
/// samples of variance `r σ²` beside `n` of variance `σ²` lower the variance of the mean
/// while `r < 2 + b/n`: 2 is that bound at large `n`, not tuned on any scene. It keeps
/// the baseline where `srt` is close to the evolved mixtures and drops it where they are
/// far better (the medians of `V_srt / V_best` on the test scenes: docs/methods/ga.md,
/// "Baseline"; their seed in reports/README.md,
/// "`ga` keeps its baseline's samples (issue 23, 2026-12-04)").
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
    /// measure its guided path tracer, and `srt` samples beside its guided ones raise its
    /// error (docs/methods/ga.md, "Baseline").
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
