//! The pixel plan of `--method ga` (design §7): which pixels run the genetic algorithm, and
//! which mixture every pixel renders with.
//!
//! 1. **Grid.** One ray through each pixel's centre tells whether it sees a scattering
//!    surface at all (pixels that see only background or an emitter need no GA: their value
//!    is emission seen directly). Each cell of a regular grid (`grid` pixels apart) gets a GA
//!    pixel at its centre or the scattering pixel closest to it.
//! 2. **Baseline and extra GA pixels.** A few `srt` samples per pixel estimate its relative
//!    variance; extra GA pixels go to the cells with the highest baseline relative variance,
//!    at their noisiest pixel.
//! 3. **Evolution.** Per GA pixel, `M` test paths from the defensive `srt` density and the
//!    genetic algorithm on them, in parallel; every pixel has its own random streams, derived
//!    from the seed and the pixel alone, so the result does not depend on the thread count.
//!    A pixel keeps `srt` alone when the GA found nothing better on its test paths.
//! 4. **Interpolation.** Every pixel renders with the union of its nearest GA pixels'
//!    mixtures, each scaled by a normalised inverse-square distance weight: one mixture whose
//!    weights sum to 1, containing the defensive `srt` component, so the estimator stays
//!    unbiased.
//!
//! 5. **Gate** (beyond the paper; off with `PlanConfig::gate = false`). The GA pays for
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
//!    ([`crate::render::train_spatial`]). (A mixture's pilot stops
//!    starting pixels once it cannot pay, so there it is `pt` everywhere. cbox, `ga`, 64
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

use super::individual::Individual;
use super::nearest::PointGrid;
use super::population::{evolve_from, GenerationStats};
use super::test_paths::TestPaths;
use super::{fitness, luminance, ChannelWeights, GaConfig, GaConfigError};
use crate::guiding::Guide;
use crate::path::mixture::{Mixture, MixtureScratch};
use crate::path::{camera_sample, emitted, mixture_file, RayCounts, SceneView};
use crate::progress::progress_bar;
use crate::sampling::{camera_ray, sample_rng};
use crate::scene::SceneAnalysis;
use glam::DVec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

/// Stream tags: the baseline, the test paths and the GA use seeds derived from the user's
/// seed with these, never the render's own streams.
const BASELINE_STREAM: u64 = 0x6261_7365_6c69_6e65;
const TEST_PATH_STREAM: u64 = 0x7465_7374_7061_7468;
const GA_STREAM: u64 = 0x6765_6e65_7469_6373;
const GATE_PT_STREAM: u64 = 0x6761_7465_5f70_7400;
const GATE_STREAM: u64 = 0x6761_7465_0000_0000;
const CHECK_STREAM: u64 = 0x6368_6563_6b00_0000;

/// Samples of `pt` (and of the guided path tracer) with which the gate measures their
/// variance at a GA pixel.
pub const GATE_SAMPLES: u32 = 2048;
/// Samples of the mixture estimator with which the gate counts its cost.
pub const COST_SAMPLES: u32 = 256;
/// The gate's thresholds on a trial's predicted gain: `(lose, win)`. The GA goes on past
/// the pilot only if at least half the pilot pixels predict a gain above `win`; a GA pixel
/// prefers `pt` where it predicts one below `lose`.
///
/// The guided path tracer keeps `pt`'s next-event estimation and its BRDF sampling (at the
/// defensive weight), so it rarely loses much, while its 2048-sample trial is noisy (fig5:
/// sending every pixel below 1.25 to `pt` lost 20 % relMSE against no gate): it must win
/// by 1.25 and is dropped below 0.8. The mixture estimator's prediction is the less certain
/// (fig5, 9 GA pixels against 200 000-sample variances: within a factor 2 either way), its
/// variance grows faster away from the GA pixel and can exceed `pt`'s many times: it must
/// win by 2 everywhere.
pub fn gate_margins(target: Target) -> (f64, f64) {
    match target {
        Target::Guide => (0.8, 1.25),
        Target::Mixture => (2.0, 2.0),
    }
}
/// GA pixels evolved before the gate decides whether to evolve the others.
pub const PILOT_PIXELS: usize = 8;
/// The pilot evolves for `1 / PILOT_SHARE` of the generations before its trial decides: a
/// scene where the GA cannot pay costs a quarter of a full pilot (cbox, 2 s budgets: the
/// full pilot took a third of the time). Where the pilot pays, its pixels go on from their
/// best individual for the remaining generations.
pub const PILOT_SHARE: usize = 4;

/// With pruning, generators get the steps that carry all but this share of the test paths'
/// `Σ F²/q`: none, so steps are cut only past the deepest light-carrying test path. (Cutting
/// at 0.1 % made fig5 worse, 4.14 against 2.70 relMSE at 128², 64 spp: with M = 10 000 only
/// ~100 test paths carry light, too few to call a depth's share negligible.)
pub const PRUNE_SHARE: f64 = 0.0;

/// Iterations of [`fitness::optimise_weights`] with `GaConfig::convex_weights` (each costs
/// two passes over the light-carrying test paths per generator; it stops earlier once `V`
/// stops falling).
pub const CONVEX_ITERATIONS: usize = 200;

/// Where the genetic algorithm runs and how its results spread over the image.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PlanConfig {
    /// Distance between grid GA pixels, in pixels, along both axes.
    pub grid: u32,
    /// Extra GA pixels at high baseline variance, as a fraction of the grid pixels.
    pub extra: f64,
    /// `srt` samples per pixel of the baseline pass.
    pub baseline_spp: u32,
    /// GA pixels whose mixtures each pixel combines.
    pub neighbours: usize,
    /// Leave out what the scene does not need: cells whose baseline relative variance is
    /// below `prune_variance` get no GA pixel, and evolved generators get only the steps the
    /// test paths need (`TestPaths::steps_needed`; for `ga-pt` also at most `guide_steps`,
    /// pruning or not).
    pub prune: bool,
    pub prune_variance: f64,
    /// Render with `pt` wherever the evolved estimator is predicted to lose to it, and skip
    /// the GA when a pilot predicts no gain anywhere (see the module documentation).
    pub gate: bool,
    /// Evolve half the GA pixels first, then the others from their evolved neighbours' best
    /// individuals, with half the generations (beyond the paper).
    pub warm_start: bool,
    /// Wall-clock seconds the plan (baseline included) may take: past them, GA pixels not
    /// yet evolved are left out (to `pt` with the gate and the mixture target, to their
    /// neighbours' mixtures otherwise). The GA then runs in chunks and the plan depends on
    /// timing, not only on the seed. `None`: no limit.
    pub time_limit: Option<f64>,
    /// `ga-pt`: vertices the guide steers, i.e. the directional steps the GA evolves (at
    /// most what the test paths need). Path tracing's next-event estimation already finds
    /// the light from the vertices after the first, and one step leaves the GA a search
    /// space it explores in its generations: on fig5 at 64 spp, relMSE 0.391 / 0.376 /
    /// 0.384 (seeds 7 / 11 / 13) against 0.433 / 0.362 / 0.795 (the pilot closed) with
    /// every step the test paths need.
    pub guide_steps: usize,
    /// `ga-pt`: guide the vertices past the GA's with a spatial guide (`path::spatial`), as
    /// `pg` guides every vertex. On by default: at equal time (reports at e5f1d58, 2 / 8 /
    /// 30 s) `ga-pt` had 0.32 / 0.27 / 0.27 of `pt`'s relMSE on fig5 with it and 0.33 /
    /// 0.30 / 0.31 without, fig1 0.48 / 0.43 / 0.40 against 1.00 / 1.01 / 0.99, glossy
    /// 0.33 / 0.33 / 0.43 against 1.04 / 1.03 / 1.02 and cbox 0.92 / 0.92 / 0.82 against
    /// 1.01 / 1.01 / 0.99.
    pub spatial: bool,
    /// `pg`, and `ga-pt` with `spatial`: passes of path tracing that train the spatial
    /// guide, pass `i` with `2^i` samples per pixel (they stay in the image). `None`: as
    /// many as `spatial_time_limit` allows if set, else as many as fit in half the samples
    /// per pixel.
    pub spatial_passes: Option<u32>,
    /// Seconds the spatial guide's training may take (see `spatial_passes`).
    pub spatial_time_limit: Option<f64>,
}

impl Default for PlanConfig {
    fn default() -> Self {
        Self {
            grid: 32,
            extra: 0.25,
            baseline_spp: 4,
            neighbours: 4,
            prune: true,
            prune_variance: 0.5,
            gate: true,
            warm_start: true,
            time_limit: None,
            guide_steps: 1,
            spatial: true,
            spatial_passes: None,
            spatial_time_limit: None,
        }
    }
}

impl PlanConfig {
    pub fn validate(&self) -> Result<(), GaConfigError> {
        let fail = |m: String| Err(GaConfigError(m));
        if self.grid == 0 {
            return fail("the GA grid spacing must be at least 1 pixel".into());
        }
        if !(self.extra.is_finite() && (0.0..=16.0).contains(&self.extra)) {
            return fail(format!("extra GA pixels {} is not in [0, 16]", self.extra));
        }
        if self.baseline_spp == 0 {
            return fail("the baseline needs at least 1 sample per pixel".into());
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
        if !(1..=64).contains(&self.guide_steps) {
            return fail(format!(
                "guide steps {} is not in [1, 64]",
                self.guide_steps
            ));
        }
        if let Some(p) = self.spatial_passes.filter(|p| !(1..=12).contains(p)) {
            return fail(format!("spatial guide passes {p} is not in [1, 12]"));
        }
        if bad_seconds(self.spatial_time_limit) {
            return fail(format!(
                "spatial guide time limit {:?} must be finite and ≥ 0 seconds",
                self.spatial_time_limit
            ));
        }
        if !(1..=64).contains(&self.neighbours) {
            return fail(format!(
                "GA neighbours per pixel {} is not in [1, 64]",
                self.neighbours
            ));
        }
        Ok(())
    }
}

/// The estimator a plan is built for: the gate compares it with `pt`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Target {
    /// `ga`: the mixture estimator (eq. 8).
    Mixture,
    /// `ga-pt`: path tracing guided by the mixture.
    Guide,
}

/// One estimator's samples at a pixel, per sample: mean and variance under the pixel's
/// [`ChannelWeights`] (`√(Σ_c w_c mean_c²)` and `Σ_c w_c Var_c`), and the cost
/// ([`RayCounts::cost`]).
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct Moments {
    pub mean: f64,
    pub variance: f64,
    pub cost: f64,
}

impl Moments {
    /// `1 / (variance × cost)`; infinite without variance.
    fn efficiency(&self) -> f64 {
        1.0 / (self.variance * self.cost)
    }
}

/// The gate's comparison at a GA pixel.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct Trial {
    pub pt: Moments,
    pub evolved: Moments,
    /// `evolved`'s efficiency over `pt`'s; 0 where neither has variance (nothing to gain).
    pub gain: f64,
}

/// Why a GA pixel was chosen.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Origin {
    Grid,
    /// High baseline variance.
    Extra,
}

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
    /// Whether the gate's trial predicts the evolved estimator for `target` to beat `pt`
    /// here by the winning margin ([`gate_margins`]).
    pub fn pays(&self, target: Target) -> bool {
        self.trial.is_some_and(|t| t.gain > gate_margins(target).1)
    }

    /// Whether this pixel's estimator should be `pt`: it kept `srt`, or its trial predicts
    /// a loss below the losing margin ([`gate_margins`]) (a NaN gain counts as a loss). A
    /// pixel without a trial (a guide's pixel outside the pilot) keeps its estimator.
    pub fn prefers_pt(&self, target: Target) -> bool {
        self.kept_srt
            || self
                .trial
                .is_some_and(|t| t.gain.is_nan() || t.gain < gate_margins(target).0)
    }
}

/// Per-phase totals of a plan.
#[derive(Clone, Debug, Default, serde::Serialize)]
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
    /// GA pixels whose evolved estimator is predicted to lose to `pt` (or that kept `srt`).
    pub pt_pixels: usize,
    /// GA pixels not evolved because the plan reached `PlanConfig::time_limit`.
    pub time_limited_pixels: usize,
    /// Whether the baseline ran: not where the gate's pilot closed the GA.
    pub baseline_ran: bool,
    /// Pooled baseline relative variance (one srt sample, `Var/(mean² + 0.01)` over the
    /// cell's samples) of the cells with a scattering pixel: smallest, median, largest.
    pub cell_variance: [f64; 3],
    pub individual_evaluations: u64,
    pub generator_evaluations: u64,
    pub rays: RayCounts,
}

/// GA pixels and their mixtures, and how every other pixel combines them.
#[derive(Clone, Debug)]
pub struct Plan {
    width: u32,
    height: u32,
    pub pixels: Vec<GaPixel>,
    /// With the gate: points where the image renders with `pt` (one pixel of each
    /// low-variance cell, and the GA pixels the pilot left out), interpolated like GA pixels.
    pub pt_points: Vec<(u32, u32)>,
    gate: bool,
    /// The gate's pilot showed that the mixture does not pay: every pixel renders with `pt`
    /// (or the spatial guide). (A guide's failed pilot without the spatial guide keeps its
    /// guides near pilot pixels that predict no loss.)
    closed: bool,
    pub target: Target,
    /// The defensive density alone: the mixture of an image without any GA pixel.
    pub srt: Mixture,
    neighbours: usize,
    /// What the scene contains.
    pub analysis: SceneAnalysis,
    /// Fault injection for statistical tests: leave the interpolation weights unnormalised.
    unnormalised: bool,
    pub stats: PlanStats,
    /// `pixels` and then `pt_points`, bucketed for [`Self::interpolation`] on first use.
    index: OnceLock<PointGrid>,
}

/// Per-pixel baseline estimate.
#[derive(Clone, Copy, Default)]
struct Baseline {
    /// Relative variance of one `srt` sample: `Var[L] / (E[L]² + 0.01)` (luminance).
    rel_variance: f64,
    /// Sum and sum of squares of the samples' luminance.
    sum: f64,
    sum_sq: f64,
    /// Some baseline ray hit a scattering surface.
    scatters: bool,
}

fn derived_seed(seed: u64, stream: u64) -> u64 {
    // One sample_rng draw mixes the two into a fresh 64-bit seed.
    let mut rng = sample_rng(seed, stream, u64::MAX);
    rand::Rng::random::<u64>(&mut rng)
}

/// The cells of a `grid`-pixel grid over a `width × height` image, row by row: `[x0, y0, x1,
/// y1)` each, clipped to the image.
fn grid_cells(width: u32, height: u32, grid: u32) -> impl Iterator<Item = [u32; 4]> {
    (0..height).step_by(grid as usize).flat_map(move |y0| {
        (0..width)
            .step_by(grid as usize)
            .map(move |x0| [x0, y0, (x0 + grid).min(width), (y0 + grid).min(height)])
    })
}

/// Each grid cell's GA pixel: the pixel closest to the cell's centre whose centre ray sees a
/// scattering surface (`None`: the cell has none), in row-major cell order; and the pixels
/// whose centre ray sees none. One ray per pixel, no random numbers: the pilot can run
/// before (and without) the baseline.
fn grid_pixels(
    view: &SceneView,
    grid: u32,
    counts: &mut RayCounts,
) -> (Vec<Option<(u32, u32)>>, usize) {
    let camera = &view.scene.camera;
    let (width, height) = (camera.width, camera.height);
    let rows: Vec<(Vec<bool>, RayCounts)> = (0..height)
        .into_par_iter()
        .map(|y| {
            let mut c = RayCounts::default();
            let row = (0..width)
                .map(|x| {
                    let ray = camera.ray(x as f32 + 0.5, y as f32 + 0.5);
                    view.trace(&ray, &mut c)
                        .is_some_and(|hit| view.material(hit.prim).scatters())
                })
                .collect();
            (row, c)
        })
        .collect();
    let mut scatters = Vec::with_capacity((width * height) as usize);
    for (row, c) in rows {
        scatters.extend(row);
        counts.add(c);
    }
    let cells = grid_cells(width, height, grid)
        .map(|[x0, y0, x1, y1]| {
            let centre = ((x0 + x1 - 1) as f64 / 2.0, (y0 + y1 - 1) as f64 / 2.0);
            let mut best: Option<(f64, u32, u32)> = None;
            for y in y0..y1 {
                for x in x0..x1 {
                    if !scatters[(y * width + x) as usize] {
                        continue;
                    }
                    let d = (x as f64 - centre.0).powi(2) + (y as f64 - centre.1).powi(2);
                    if best.is_none_or(|(bd, ..)| d < bd) {
                        best = Some((d, x, y));
                    }
                }
            }
            best.map(|(_, x, y)| (x, y))
        })
        .collect();
    (cells, scatters.iter().filter(|s| !**s).count())
}

fn baseline(
    view: &SceneView,
    srt: &Mixture,
    config: &PlanConfig,
    max_bounces: u32,
    seed: u64,
) -> (Vec<Baseline>, RayCounts) {
    let camera = &view.scene.camera;
    let (width, height) = (camera.width, camera.height);
    let seed = derived_seed(seed, BASELINE_STREAM);
    let rows: Vec<(Vec<Baseline>, RayCounts)> = (0..height)
        .into_par_iter()
        .map(|y| {
            let mut counts = RayCounts::default();
            let mut scratch = MixtureScratch::default();
            let row = (0..width)
                .map(|x| {
                    let pixel = y as u64 * width as u64 + x as u64;
                    let (mut sum, mut sum_sq, mut scatters) = (0.0, 0.0, false);
                    for s in 0..config.baseline_spp {
                        let mut rng = sample_rng(seed, pixel, s as u64);
                        let ray = camera_ray(camera, (x, y), &mut rng);
                        let Some(x1) = view.trace(&ray, &mut counts) else {
                            continue;
                        };
                        let material = view.material(x1.prim);
                        scatters |= material.scatters();
                        let value = emitted(material, &x1, -ray.dir).as_dvec3()
                            + srt.estimate(
                                view,
                                ray.origin,
                                x1,
                                max_bounces,
                                &mut rng,
                                &mut counts,
                                &mut scratch,
                            );
                        let l = luminance(value);
                        sum += l;
                        sum_sq += l * l;
                    }
                    let n = config.baseline_spp as f64;
                    let mean = sum / n;
                    let var = if n > 1.0 {
                        ((sum_sq - sum * mean) / (n - 1.0)).max(0.0)
                    } else {
                        0.0
                    };
                    Baseline {
                        rel_variance: var / (mean * mean + 0.01),
                        sum,
                        sum_sq,
                        scatters,
                    }
                })
                .collect();
            (row, counts)
        })
        .collect();
    let mut counts = RayCounts::default();
    let mut out = Vec::with_capacity((width * height) as usize);
    for (row, c) in rows {
        out.extend(row);
        counts.add(c);
    }
    (out, counts)
}

/// What [`choose_pixels`] chose and left out.
struct Choice {
    pixels: Vec<(u32, u32, Origin)>,
    /// The GA pixel of each low-variance cell (pruning).
    low: Vec<(u32, u32)>,
    /// Pooled baseline relative variance of every cell with a GA pixel.
    cell_variance: Vec<f64>,
}

/// The GA pixels: each cell's grid pixel ([`grid_pixels`]), then extras in the noisiest
/// cells; with pruning, none in cells whose pooled baseline relative variance is below
/// `config.prune_variance`, except at `keep` (the pilot, already evolved).
fn choose_pixels(
    base: &[Baseline],
    cells: &[Option<(u32, u32)>],
    (width, height): (u32, u32),
    config: &PlanConfig,
    keep: &[(u32, u32)],
) -> Choice {
    let mut chosen = Vec::new();
    let mut low_cells = Vec::new();
    let mut noisy = Vec::new();
    let mut cell_variance = Vec::new();
    for ([x0, y0, x1, y1], cell) in grid_cells(width, height, config.grid).zip(cells) {
        let Some((x, y)) = *cell else {
            continue;
        };
        let (mut sum, mut sum_sq, mut n) = (0.0, 0.0, 0usize);
        let mut noisiest = None::<(f64, u32, u32)>;
        for py in y0..y1 {
            for px in x0..x1 {
                let b = base[(py * width + px) as usize];
                if !b.scatters {
                    continue;
                }
                sum += b.sum;
                sum_sq += b.sum_sq;
                n += config.baseline_spp as usize;
                if noisiest.is_none_or(|(v, ..)| b.rel_variance > v) {
                    noisiest = Some((b.rel_variance, px, py));
                }
            }
        }
        // The cell's samples pooled: rare bright paths, which a few samples per pixel
        // mostly miss, still show up in the cell's variance.
        let mean_noise = if n > 1 {
            let mean = sum / n as f64;
            let var = ((sum_sq - sum * mean) / (n - 1) as f64).max(0.0);
            var / (mean * mean + 0.01)
        } else {
            0.0
        };
        cell_variance.push(mean_noise);
        if config.prune && mean_noise < config.prune_variance && !keep.contains(&(x, y)) {
            low_cells.push((x, y));
            continue;
        }
        chosen.push((x, y, Origin::Grid));
        if let Some((_, nx, ny)) = noisiest.filter(|&(_, nx, ny)| (nx, ny) != (x, y)) {
            noisy.push((mean_noise, nx, ny));
        }
    }
    let extra = (config.extra * chosen.len() as f64).round() as usize;
    noisy.sort_by(|a, b| b.0.total_cmp(&a.0).then((a.2, a.1).cmp(&(b.2, b.1))));
    chosen.extend(
        noisy
            .iter()
            .take(extra)
            .map(|&(_, x, y)| (x, y, Origin::Extra)),
    );
    Choice {
        pixels: chosen,
        low: low_cells,
        cell_variance,
    }
}

/// Test paths and evolution at one pixel.
#[allow(clippy::too_many_arguments)]
fn run_pixel(
    view: &SceneView,
    srt: &Mixture,
    ga: &GaConfig,
    (x, y, origin): (u32, u32, Origin),
    max_bounces: u32,
    seed: u64,
    (config, target): (&PlanConfig, Target),
    (seeds, generations, stream, trial): (&[Individual], usize, u64, bool),
) -> (GaPixel, RayCounts) {
    let t0 = Instant::now();
    let (paths, mut counts) = TestPaths::sample_until(
        view,
        srt,
        (x, y),
        (ga.test_paths, ga.max_light_paths),
        max_bounces,
        derived_seed(seed, TEST_PATH_STREAM),
    );
    let test_path_seconds = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let pixel = y as u64 * view.scene.camera.width as u64 + x as u64;
    let mut rng = sample_rng(derived_seed(seed, GA_STREAM), pixel, stream);
    let v_srt = fitness::second_moment(view, &paths, srt);
    // Pruning: no generator step past the depth where the test paths carry light.
    // A guide takes only the directional samplers.
    let ga = &GaConfig {
        directions_only: ga.directions_only || target == Target::Guide,
        max_steps: match (
            target,
            config.prune.then(|| paths.steps_needed(PRUNE_SHARE)),
        ) {
            (Target::Guide, needed) => Some(needed.unwrap_or(usize::MAX).min(config.guide_steps)),
            (Target::Mixture, needed) => needed,
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
            (target, paths.weights()),
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

/// One estimator's samples at pixel `(x, y)`: `n` samples of `pt`, guided by `guide` when
/// given, or of `mixture`'s estimator (eq. 8) when given, from `stream`'s random streams.
#[allow(clippy::too_many_arguments)]
fn sample_moments(
    view: &SceneView,
    (x, y): (u32, u32),
    max_bounces: u32,
    (seed, stream): (u64, u64),
    (n, weights): (u32, ChannelWeights),
    mixture: Option<&Mixture>,
    guide: Option<&Guide>,
    counts: &mut RayCounts,
) -> Moments {
    let camera = &view.scene.camera;
    let pixel = y as u64 * camera.width as u64 + x as u64;
    let seed = derived_seed(seed, stream);
    let mut scratch = MixtureScratch::default();
    let mut c = RayCounts::default();
    let (mut sum, mut sum_sq) = (DVec3::ZERO, DVec3::ZERO);
    for s in 0..n {
        let mut rng = sample_rng(seed, pixel, s as u64);
        let ray = camera_ray(camera, (x, y), &mut rng);
        let value = camera_sample(
            view,
            &ray,
            max_bounces,
            (mixture, guide),
            &mut rng,
            &mut c,
            &mut scratch,
        );
        sum += value;
        sum_sq += value * value;
    }
    counts.add(c);
    let n = n as f64;
    let mean = sum / n;
    let variance = ((sum_sq - sum * mean) / (n - 1.0)).max(DVec3::ZERO);
    Moments {
        mean: weights.weigh(mean * mean).sqrt(),
        variance: weights.weigh(variance),
        cost: c.cost() / n,
    }
}

/// The gate's comparison at `(x, y)` of `mixture`'s estimator for `target` with `pt`.
///
/// `pt`'s and the guided path tracer's variances come from `GATE_SAMPLES` samples each.
/// The mixture estimator's cannot: its variance hides in rare paths where the mixture's
/// density is far below `srt`'s (down to the defensive weight), which a few hundred of its
/// own samples mostly miss (fig5: the median 512-sample variance is 2–7× below the true
/// one). Its second moment is therefore eq. 10 on fresh `srt` test paths, which sample
/// exactly those paths at `srt`'s rate; its cost comes from `COST_SAMPLES` samples.
#[allow(clippy::too_many_arguments)]
fn run_trial(
    view: &SceneView,
    srt: &Mixture,
    (ga, mixture): (&GaConfig, &Mixture),
    (target, weights): (Target, ChannelWeights),
    (x, y): (u32, u32),
    max_bounces: u32,
    seed: u64,
    counts: &mut RayCounts,
) -> Trial {
    let pt = sample_moments(
        view,
        (x, y),
        max_bounces,
        (seed, GATE_PT_STREAM),
        (GATE_SAMPLES, weights),
        None,
        None,
        counts,
    );
    let evolved = match target {
        Target::Guide => {
            let guide = Guide::new(mixture);
            let stream = (seed, GATE_STREAM);
            let g = Some(&guide);
            sample_moments(
                view,
                (x, y),
                max_bounces,
                stream,
                (GATE_SAMPLES, weights),
                None,
                g,
                counts,
            )
        }
        Target::Mixture => {
            let stream = (seed, GATE_STREAM);
            let m = Some(mixture);
            let cost = sample_moments(
                view,
                (x, y),
                max_bounces,
                stream,
                (COST_SAMPLES, weights),
                m,
                None,
                counts,
            );
            let (mut check, c) = TestPaths::sample_until(
                view,
                srt,
                (x, y),
                (ga.test_paths, ga.max_light_paths),
                max_bounces,
                derived_seed(seed, CHECK_STREAM),
            );
            counts.add(c);
            check.weigh(weights);
            let mean = check.mean();
            Moments {
                mean,
                variance: (fitness::second_moment(view, &check, mixture) - mean * mean).max(0.0),
                cost: cost.cost,
            }
        }
    };
    let gain = if pt.variance > 0.0 {
        evolved.efficiency() / pt.efficiency()
    } else {
        0.0
    };
    Trial { pt, evolved, gain }
}

/// Best individuals of up to `config.neighbours` evolved GA pixels nearest to `at`, within
/// two grid spacings: the first generation of a warm-started GA.
fn neighbour_seeds(
    done: &[Option<(GaPixel, RayCounts)>],
    (x, y, _): (u32, u32, Origin),
    config: &PlanConfig,
) -> Vec<Individual> {
    let reach = 2.0 * config.grid as f64;
    let mut near: Vec<(f64, usize, &Individual)> = done
        .iter()
        .enumerate()
        .filter_map(|(i, d)| {
            let (p, _) = d.as_ref()?;
            let best = p.best.as_ref()?;
            let d = (p.x as f64 - x as f64).hypot(p.y as f64 - y as f64);
            (d <= reach).then_some((d, i, best))
        })
        .collect();
    near.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    near.iter()
        .take(config.neighbours)
        .map(|n| n.2.clone())
        .collect()
}

impl Plan {
    /// Picks the GA pixels (the grid's, then, after the baseline, the extras) and evolves
    /// each of them (in parallel on the current rayon pool), with progress bars on stderr
    /// when `progress`; with the gate, runs the pilot first and compares the evolved
    /// estimator for `target` with `pt` at each pixel that runs a trial.
    pub fn build(
        view: &SceneView,
        ga: &GaConfig,
        config: &PlanConfig,
        (max_bounces, target): (u32, Target),
        seed: u64,
        progress: bool,
    ) -> Result<Self, GaConfigError> {
        ga.validate()?;
        config.validate()?;
        let scene = view.scene;
        let (width, height) = (scene.camera.width, scene.camera.height);
        let srt = mixture_file::srt(scene, max_bounces, ga.srt_absorption);
        let mut stats = PlanStats::default();

        let t0 = Instant::now();
        let mut counts = RayCounts::default();
        let (cells, skipped) = grid_pixels(view, config.grid, &mut counts);
        stats.rays.add(counts);
        stats.skipped_pixels = skipped;
        stats.empty_cells = cells.iter().filter(|c| c.is_none()).count();
        let grid: Vec<(u32, u32)> = cells.iter().flatten().copied().collect();
        let grid_seconds = t0.elapsed().as_secs_f64();
        // Seconds of the baseline, which runs between GA waves.
        let mut baseline_part = 0.0;

        let t1 = Instant::now();
        // With the gate, a pilot of grid pixels spread evenly over the image runs first,
        // before the baseline: where it predicts no gain, the plan costs no baseline.
        let mut chosen: Vec<(u32, u32, Origin)> = if config.gate {
            let k = PILOT_PIXELS.min(grid.len());
            (0..k)
                .map(|j| {
                    let (x, y) = grid[j * grid.len() / k];
                    (x, y, Origin::Grid)
                })
                .collect()
        } else {
            Vec::new()
        };
        let pilot = chosen.len();
        let bar = progress_bar(pilot as u64, "GA", progress);
        let mut done: Vec<Option<(GaPixel, RayCounts)>> = vec![None; pilot];
        // A wave: GA pixels (indices into `chosen`), the individuals each starts from, its
        // generations and its GA random stream (a pilot pixel that goes on takes a fresh
        // one: its scouting run's would replay the same random individuals and breeding).
        // The last field: whether the pixel runs the gate's trial. For a mixture every GA
        // pixel does; for a guide only the pilot (see `trials_everywhere`).
        type Job = (usize, Vec<Individual>, usize, u64, bool);
        let trials_everywhere = target == Target::Mixture;
        let run_job = |at: (u32, u32, Origin), seeds: &[Individual], generations, stream, trial| {
            let r = run_pixel(
                view,
                &srt,
                ga,
                at,
                max_bounces,
                seed,
                (config, target),
                (seeds, generations, stream, trial),
            );
            bar.inc(1);
            r
        };
        let evolve_wave =
            |wave: &[Job], chosen: &[(u32, u32, Origin)], done: &mut Vec<Option<_>>| {
                let results: Vec<(usize, (GaPixel, RayCounts))> = wave
                    .par_iter()
                    .map(|(i, seeds, generations, stream, trial)| {
                        (
                            *i,
                            run_job(chosen[*i], seeds, *generations, *stream, *trial),
                        )
                    })
                    .collect();
                for (i, r) in results {
                    done[i] = Some(r);
                }
            };
        let scout = ga.generations.div_ceil(PILOT_SHARE);
        // For a mixture, a pilot pixel is not started once so many others failed to pay
        // that the pilot cannot (cbox: the GA phase 0.16 -> 0.12 s). Which pixels that skips
        // depends on the threads' timing, so a mixture's pilot that fails leaves the whole
        // image to `pt` (see `Plan::closed`), whichever of its pixels ran.
        let losing = AtomicUsize::new(0);
        let settled =
            || target == Target::Mixture && 2 * (pilot - losing.load(Ordering::Relaxed)) < pilot;
        let scouted_pilot: Vec<(usize, (GaPixel, RayCounts))> = (0..pilot)
            .into_par_iter()
            .filter_map(|i| {
                if settled() {
                    return None;
                }
                let r = run_job(chosen[i], &[], scout, 0, true);
                if !r.0.pays(target) {
                    losing.fetch_add(1, Ordering::Relaxed);
                }
                Some((i, r))
            })
            .collect();
        for (i, r) in scouted_pilot {
            done[i] = Some(r);
        }
        let mut scouted: Vec<(GaPixel, RayCounts)> = Vec::new();
        let mut pt_points = Vec::new();
        // The GA goes on where at least half the pilot pixels predict a gain above the
        // winning margin: one pixel alone (an outlier, or a small region) does not pay for
        // evolving the whole image.
        let paying = done
            .iter()
            .flatten()
            .filter(|(p, _)| p.pays(target))
            .count();
        let pilot_pays = 2 * paying >= pilot.max(1);
        let closed = config.gate && !pilot_pays && (target == Target::Mixture || config.spatial);
        if !config.gate || pilot_pays {
            // The baseline, then the other GA pixels (the pilot's stay, whatever their
            // cells' variance).
            let t2 = Instant::now();
            let (base, counts) = baseline(view, &srt, config, max_bounces, seed);
            stats.rays.add(counts);
            stats.baseline_ran = true;
            let keep: Vec<(u32, u32)> = chosen.iter().map(|&(x, y, _)| (x, y)).collect();
            let choice = choose_pixels(&base, &cells, (width, height), config, &keep);
            stats.low_variance_cells = choice.low.len();
            let mut v = choice.cell_variance;
            v.sort_by(f64::total_cmp);
            if !v.is_empty() {
                stats.cell_variance = [v[0], v[v.len() / 2], v[v.len() - 1]];
            }
            if config.gate {
                pt_points.extend(&choice.low);
            }
            chosen.extend((choice.pixels.iter()).filter(|&&(x, y, _)| !keep.contains(&(x, y))));
            let n = chosen.len();
            done.resize(n, None);
            bar.inc_length((n - pilot) as u64);
            baseline_part = t2.elapsed().as_secs_f64();

            // With warm starts, the grid pixels of "white" cells (in a checkerboard of
            // cells) first, then the rest, seeded from their evolved neighbours.
            let g = config.grid;
            let white = |i: usize| {
                let (x, y, origin) = chosen[i];
                origin == Origin::Grid && (x / g + y / g) % 2 == 0
            };
            let (first, second): (Vec<usize>, Vec<usize>) =
                (pilot..n).partition(|&i| !config.warm_start || white(i));
            // With a time limit, the waves run in chunks, each only if time is left.
            let chunk = match config.time_limit {
                Some(_) => 4 * rayon::current_num_threads(),
                None => usize::MAX,
            };
            let mut late = Vec::new();
            let mut run_chunks = |jobs: &[Job], done: &mut Vec<_>| {
                for c in jobs.chunks(chunk) {
                    if config
                        .time_limit
                        .is_some_and(|limit| t0.elapsed().as_secs_f64() >= limit)
                    {
                        late.extend(c.iter().map(|j| j.0));
                    } else {
                        evolve_wave(c, &chosen, done);
                    }
                }
            };
            // The pilot goes on from each pixel's best individual for the remaining
            // generations, whatever the time limit (the pilot showed the GA pays); its
            // scouting still counts in the stats. A scout without a best individual (no
            // light-carrying test path) or without generations left stands as it is.
            let rest = ga.generations.saturating_sub(scout);
            let go_on: Vec<Job> = (0..pilot)
                .filter_map(|i| {
                    let (p, counts) = done[i].take()?;
                    match p.best.clone() {
                        Some(best) if rest > 0 => {
                            scouted.push((p, counts));
                            Some((i, vec![best], rest, 1, true))
                        }
                        _ => {
                            done[i] = Some((p, counts));
                            None
                        }
                    }
                })
                .collect();
            bar.inc_length(go_on.len() as u64);
            evolve_wave(&go_on, &chosen, &mut done);
            let cold: Vec<Job> = first
                .iter()
                .map(|&i| (i, Vec::new(), ga.generations, 0, trials_everywhere))
                .collect();
            run_chunks(&cold, &mut done);
            // Seeds from the pilot and the first wave only, whatever the chunks. A warm start
            // needs half the generations.
            let warm = ga.generations.div_ceil(2);
            let second: Vec<Job> = second
                .iter()
                .map(|&i| match config.warm_start {
                    true => (
                        i,
                        neighbour_seeds(&done, chosen[i], config),
                        warm,
                        0,
                        trials_everywhere,
                    ),
                    false => (i, Vec::new(), ga.generations, 0, trials_everywhere),
                })
                .collect();
            run_chunks(&second, &mut done);
            stats.time_limited_pixels = late.len();
            // A mixture's variance can grow fast away from its GA pixel, so with the gate a
            // cell the GA did not reach renders with `pt`. A guide keeps `pt`'s next-event
            // estimation and BRDF sampling: once the pilot showed it pays, such a cell takes
            // its evolved neighbours' guides, as without the gate (fig5, 2 s budgets, where
            // half the GA pixels are late: relMSE 0.83 with those cells on `pt`, 0.56
            // without the gate).
            if config.gate && target == Target::Mixture {
                pt_points.extend(late.iter().map(|&i| (chosen[i].0, chosen[i].1)));
            }
        } else {
            // No baseline: every other cell renders with `pt`.
            stats.gated_pixels = grid.len() - done.iter().flatten().count();
            let pilot_at = &chosen;
            pt_points.extend(
                (grid.iter()).filter(|&&(x, y)| !pilot_at.iter().any(|p| (p.0, p.1) == (x, y))),
            );
        }
        let results: Vec<(GaPixel, RayCounts)> = done.into_iter().flatten().collect();
        bar.finish_and_clear();
        stats.baseline_seconds = grid_seconds + baseline_part;
        stats.ga_seconds = t1.elapsed().as_secs_f64() - baseline_part;
        let mut pixels = Vec::with_capacity(results.len());
        // The work of the pilot pixels' scouting runs, which the pixels that went on replaced.
        for (p, counts) in scouted
            .iter()
            .map(|(p, c)| (p, *c))
            .chain(results.iter().map(|(p, c)| (p, *c)))
        {
            stats.rays.add(counts);
            stats.test_path_cpu_seconds += p.test_path_seconds;
            stats.evolve_cpu_seconds += p.ga_seconds;
            stats.individual_evaluations += p.individual_evaluations;
            stats.generator_evaluations += p.generator_evaluations;
        }
        for (p, _) in results {
            if config.gate && p.prefers_pt(target) {
                stats.pt_pixels += 1;
            }
            pixels.push(p);
        }
        Ok(Self {
            width,
            height,
            pixels,
            pt_points,
            gate: config.gate,
            closed,
            target,
            srt,
            neighbours: config.neighbours,
            analysis: scene.analysis(),
            unnormalised: false,
            stats,
            index: OnceLock::new(),
        })
    }

    /// This plan with its interpolation weights deliberately left unnormalised: a wrong input
    /// that the unbiasedness test must reject.
    pub fn with_unnormalised_interpolation(mut self) -> Self {
        self.unnormalised = true;
        self
    }

    /// The GA pixels nearest to `(x, y)` (up to `neighbours`) and their weights, into `out`:
    /// inverse squared distance, normalised to sum 1; a GA pixel itself takes weight 1.
    /// Indices from `pixels.len()` on are `pt_points`.
    pub fn interpolation(&self, x: u32, y: u32, out: &mut Vec<(f64, usize)>) {
        let index = self.index.get_or_init(|| {
            let points = self.pixels.iter().map(|p| (p.x, p.y));
            PointGrid::new(
                points.chain(self.pt_points.iter().copied()).collect(),
                self.width,
                self.height,
            )
        });
        // The `neighbours` smallest distances, sorted, ties by index.
        index.nearest(x, y, self.neighbours, out);
        if let Some(&(_, i)) = out.first().filter(|(d2, _)| *d2 == 0.0) {
            out.clear();
            out.push((1.0, i));
            return;
        }
        let mut total = 0.0;
        for (w, _) in out.iter_mut() {
            *w = 1.0 / *w;
            total += *w;
        }
        if !self.unnormalised {
            out.iter_mut().for_each(|(w, _)| *w /= total);
        }
    }

    /// Whether interpolation point `i` (see [`Self::interpolation`]) prefers `pt`: a
    /// `pt_points` entry, or a GA pixel that kept `srt` or whose gate trial predicts no gain.
    fn prefers_pt(&self, i: usize) -> bool {
        self.pixels.get(i).is_none_or(|p| p.prefers_pt(self.target))
    }

    /// How pixel `(x, y)` renders: `None` with `pt`, else with this mixture (`ga`) or guided
    /// by it (`ga-pt`). Without the gate: the union of the nearest GA pixels' mixtures, each
    /// with its interpolation weight. With it: `pt` where the points preferring `pt` hold at
    /// least half the interpolation weight, else the union of the other points' mixtures,
    /// their weights renormalised. The choice depends on the plan alone, never on the
    /// render's samples, so every pixel's estimator stays unbiased.
    pub fn local(&self, x: u32, y: u32) -> Option<Mixture> {
        let mut weights = Vec::with_capacity(self.neighbours);
        let mut parts = Vec::with_capacity(self.neighbours);
        self.local_parts(x, y, &mut weights, &mut parts)
            .then(|| Mixture::union(&parts))
    }

    /// Whether no pixel renders with the plan's mixtures or guides (the gate's pilot
    /// closed the GA).
    pub fn is_closed(&self) -> bool {
        self.closed
    }

    /// [`Self::local`] without building the union: `false` for `pt`, else `true` with the
    /// weighted mixtures of the union in `parts` (`srt` alone where there is no point to
    /// interpolate). `weights` is scratch. The renderer passes the same buffers for every
    /// pixel, so that this allocates nothing.
    pub fn local_parts<'a>(
        &'a self,
        x: u32,
        y: u32,
        weights: &mut Vec<(f64, usize)>,
        parts: &mut Vec<(f64, &'a Mixture)>,
    ) -> bool {
        parts.clear();
        if self.closed {
            return false;
        }
        self.interpolation(x, y, weights);
        if self.gate {
            let total: f64 = weights.iter().map(|w| w.0).sum();
            let pt: f64 = weights
                .iter()
                .filter(|w| self.prefers_pt(w.1))
                .map(|w| w.0)
                .sum();
            if weights.is_empty() || pt >= 0.5 * total {
                return false;
            }
            weights.retain(|w| !self.prefers_pt(w.1));
            if !self.unnormalised {
                weights.iter_mut().for_each(|w| w.0 /= total - pt);
            }
        }
        if weights.is_empty() {
            parts.push((1.0, &self.srt));
        }
        parts.extend(weights.iter().map(|&(w, i)| (w, &self.pixels[i].mixture)));
        true
    }

    pub fn width(&self) -> u32 {
        self.width
    }

    pub fn height(&self) -> u32 {
        self.height
    }

    /// Wall-clock time of the whole plan (baseline and GA).
    pub fn elapsed(&self) -> Duration {
        Duration::from_secs_f64(self.stats.baseline_seconds + self.stats.ga_seconds)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::path::generator::PathGenerator;
    use crate::sampling::light_point::LightPointSampler;

    fn mixture(absorption: f64) -> Mixture {
        let light = LightPointSampler::uniform(0);
        Mixture::new(vec![PathGenerator::srt(3, absorption, light)], vec![1.0])
    }

    fn pixel(x: u32, gain: Option<f64>) -> GaPixel {
        let moments = Moments::default();
        GaPixel {
            x,
            y: 0,
            origin: Origin::Grid,
            mixture: mixture(0.25),
            v_srt: 1.0,
            v_best: 0.5,
            v_evolved: 0.5,
            kept_srt: gain.is_none(),
            trial: gain.map(|gain| Trial {
                pt: moments,
                evolved: moments,
                gain,
            }),
            best: None,
            warm: false,
            test_paths: 0,
            light_paths: 0,
            steps: 1,
            history: Vec::new(),
            individual_evaluations: 0,
            generator_evaluations: 0,
            test_path_seconds: 0.0,
            ga_seconds: 0.0,
        }
    }

    /// GA pixels at x = 0 (predicted gain 3), 10 (gain 0.5) and 20 (kept srt), a `pt`
    /// point at x = 30, two neighbours per pixel.
    fn plan(gate: bool) -> Plan {
        Plan {
            width: 40,
            height: 1,
            pixels: vec![pixel(0, Some(3.0)), pixel(10, Some(0.5)), pixel(20, None)],
            pt_points: if gate { vec![(30, 0)] } else { Vec::new() },
            gate,
            closed: false,
            target: Target::Guide,
            srt: mixture(0.5),
            neighbours: 2,
            analysis: SceneAnalysis {
                triangles: 0,
                diffuse_triangles: 0,
                glossy_triangles: 0,
                mirror_triangles: 0,
                emitter_triangles: 0,
                emitter_area: 0.0,
                smallest_emitter_area: 0.0,
                extent: 1.0,
            },
            unnormalised: false,
            stats: PlanStats::default(),
            index: OnceLock::new(),
        }
    }

    #[test]
    fn the_gate_renders_with_pt_where_the_neighbours_predict_a_loss() {
        let gated = plan(true);
        // At and next to the paying GA pixel: its mixture alone (the other neighbour, which
        // prefers pt, holds less than half the weight and is left out).
        for x in [0, 1, 4] {
            let m = gated.local(x, 0).expect("evolved mixture near x = 0");
            assert_eq!(m.generators.len(), 1, "x = {x}");
            assert!(
                (m.weights[0] - 1.0).abs() < 1e-12,
                "renormalised at x = {x}"
            );
            assert_eq!(m.generators[0].steps[0].absorption, 0.25);
        }
        // Nearer the losing pixel, the srt-only one and the pt point: pt.
        for x in [6, 10, 15, 20, 25, 30, 39] {
            assert!(gated.local(x, 0).is_none(), "x = {x}");
        }
        // A pixel the trial says loses is a loss whatever the target's margin.
        assert!(!gated.pixels[1].pays(Target::Guide) && !gated.pixels[1].pays(Target::Mixture));
        assert!(gated.pixels[0].pays(Target::Mixture));
        // Without the gate every pixel renders with the interpolated union (the paper).
        let paper = plan(false);
        for x in 0..40 {
            let m = paper.local(x, 0).expect("a mixture everywhere");
            let total: f64 = m.weights.iter().sum();
            assert!(
                (total - 1.0).abs() < 1e-12,
                "x = {x}: weights sum to {total}"
            );
        }
        // The fault injection still reaches the gated path: unnormalised weights show.
        let mut wrong = plan(true);
        wrong.unnormalised = true;
        let m = wrong.local(4, 0).expect("evolved mixture");
        assert!((m.weights.iter().sum::<f64>() - 1.0).abs() > 1e-3);
    }
}
