//! Image rendering: tiles in parallel (rayon), one deterministic random stream per pixel
//! sample, a progress bar with ETA on stderr.

use crate::accel::Ray;
use crate::genetic::plan::{Plan, PlanConfig, Target};
use crate::genetic::{GaConfig, GaConfigError};
use crate::image::Image;
use crate::path::guide::Guide;
use crate::path::mixture::{Mixture, MixtureScratch};
use crate::path::mixture_file;
use crate::path::spatial::{LevelsTrial, PathRecorder, Records, SpatialGuide};
use crate::path::{emitted, pt, Method, RayCounts, SceneView};
use crate::sampling::{derive_seed, sample_rng, uniform, Rng};
use glam::DVec3;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rayon::prelude::*;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Side of the square tiles the image is split into for parallel rendering.
pub const TILE: u32 = 16;

/// What one render needs besides the scene.
#[derive(Clone, Debug, serde::Serialize)]
pub struct RenderSettings {
    pub method: Method,
    pub spp: u32,
    pub max_bounces: u32,
    pub seed: u64,
    /// Show a progress bar on stderr.
    #[serde(skip)]
    pub progress: bool,
}

/// How each pixel sample is estimated.
#[derive(Clone, Copy)]
pub enum Estimator<'a> {
    /// Path tracing (`pt`).
    Pt,
    /// The same mixture of path generators at every pixel (`srt`, `mixture`): eq. 8.
    Mixture(&'a Mixture),
    /// Per pixel, the mixture the GA plan gives it (`ga`): eq. 8.
    Ga(&'a Plan),
    /// Per pixel, path tracing guided by the GA plan's mixture there (`ga-pt --spatial-guide
    /// false`).
    GaPt(&'a Plan),
    /// Path tracing guided by a spatial guide beyond the GA plan's levels (`ga-pt
    /// --spatial-guide`), or at every vertex without a plan (`pg`); the samples its training
    /// took are part of the image.
    Spatial(Option<&'a Plan>, &'a SpatialTraining),
}

/// Everything a method needs besides the render settings.
#[derive(Clone, Debug)]
pub struct MethodConfig {
    pub method: Method,
    /// Absorption of the `srt` generator (`srt`, and the defensive component of `ga`).
    pub srt_absorption: f64,
    /// The mixture of `--method mixture`, already loaded.
    pub mixture: Option<Mixture>,
    pub ga: GaConfig,
    pub plan: PlanConfig,
}

/// Why a method cannot be prepared.
#[derive(Debug, thiserror::Error)]
pub enum PrepareError {
    #[error(transparent)]
    Ga(#[from] GaConfigError),
    #[error("--method mixture needs --generators FILE")]
    NoMixture,
    #[error(
        "--spatial-passes {passes} trains on {needs} samples per pixel, more than --spp {spp} \
         (pass i takes 2^i)"
    )]
    TrainingExceedsSpp { passes: u32, needs: u64, spp: u32 },
}

/// A method made ready to render: the mixture or the GA plan it renders with.
pub enum Prepared {
    Pt,
    Mixture(Mixture),
    Ga(Plan),
    GaPt(Plan),
    Spatial(Option<Plan>, SpatialTraining),
}

impl Prepared {
    /// Builds what `config.method` needs: the `srt` mixture, the given mixture, or a GA plan
    /// (baseline, test paths and evolution, with progress bars when `settings.progress`).
    pub fn new(
        view: &SceneView,
        config: &MethodConfig,
        settings: &RenderSettings,
    ) -> Result<Self, PrepareError> {
        let schedule = TrainingSchedule::new(&config.plan, settings.spp);
        if let TrainingSchedule::Passes(passes) = schedule {
            let needs = (1u64 << passes) - 1;
            let spatial = config.method == Method::Pg
                || (config.method == Method::GaPt && config.plan.spatial);
            if spatial
                && config.plan.spatial_time_limit.is_none()
                && needs > u64::from(settings.spp)
            {
                let spp = settings.spp;
                return Err(PrepareError::TrainingExceedsSpp { passes, needs, spp });
            }
        }
        let spatial = |plan| train_spatial(view, settings, schedule, plan);
        Ok(match config.method {
            Method::Pt => Prepared::Pt,
            Method::Pg => Prepared::Spatial(None, spatial(None)),
            Method::Srt => Prepared::Mixture(mixture_file::srt(
                view.scene,
                settings.max_bounces,
                config.srt_absorption,
            )),
            Method::Mixture => match &config.mixture {
                Some(m) => Prepared::Mixture(m.clone()),
                None => return Err(PrepareError::NoMixture),
            },
            Method::Ga | Method::GaPt => {
                let ga = GaConfig {
                    srt_absorption: config.srt_absorption,
                    ..config.ga.clone()
                };
                let target = if config.method == Method::Ga {
                    Target::Mixture
                } else {
                    Target::Guide
                };
                let plan = Plan::build(
                    view,
                    &ga,
                    &config.plan,
                    (settings.max_bounces, target),
                    settings.seed,
                    settings.progress,
                )?;
                if config.method == Method::Ga {
                    Prepared::Ga(plan)
                } else if config.plan.spatial {
                    let training = spatial(Some(&plan));
                    Prepared::Spatial(Some(plan), training)
                } else {
                    Prepared::GaPt(plan)
                }
            }
        })
    }

    pub fn estimator(&self) -> Estimator<'_> {
        match self {
            Prepared::Pt => Estimator::Pt,
            Prepared::Mixture(m) => Estimator::Mixture(m),
            Prepared::Ga(plan) => Estimator::Ga(plan),
            Prepared::GaPt(plan) => Estimator::GaPt(plan),
            Prepared::Spatial(plan, spatial) => Estimator::Spatial(plan.as_ref(), spatial),
        }
    }

    pub fn plan(&self) -> Option<&Plan> {
        match self {
            Prepared::Ga(plan) | Prepared::GaPt(plan) | Prepared::Spatial(Some(plan), _) => {
                Some(plan)
            }
            _ => None,
        }
    }

    /// The spatial guide of `pg` (and of `ga-pt` with `PlanConfig::spatial`).
    pub fn spatial(&self) -> Option<&SpatialGuide> {
        match self {
            Prepared::Spatial(_, t) => Some(&t.guide),
            _ => None,
        }
    }

    /// Samples per pixel already in the image before rendering: the spatial guide's
    /// training samples.
    pub fn samples_taken(&self) -> u32 {
        match self {
            Prepared::Spatial(_, t) => t.samples.spp,
            _ => 0,
        }
    }

    pub fn mixture(&self) -> Option<&Mixture> {
        match self {
            Prepared::Mixture(m) => Some(m),
            _ => None,
        }
    }
}

/// A rendered image with the per-pixel statistics of its estimator.
#[derive(Clone, Debug)]
pub struct Film {
    /// Per-pixel mean of the samples.
    pub image: Image,
    /// Per-pixel, per-channel estimated variance of that mean (sample variance / spp).
    pub variance_of_mean: Vec<[f64; 3]>,
    pub rays: RayCounts,
    pub elapsed: Duration,
}

struct Tile {
    x0: u32,
    y0: u32,
    x1: u32,
    y1: u32,
}

struct TileResult {
    /// Per pixel: its index, and the sum and sum of squares of its samples (with those
    /// taken before).
    sums: Vec<(usize, DVec3, DVec3)>,
    /// Samples per pixel in those sums.
    spp: u32,
    rays: RayCounts,
}

fn tiles(width: u32, height: u32) -> Vec<Tile> {
    let mut tiles = Vec::new();
    for y0 in (0..height).step_by(TILE as usize) {
        for x0 in (0..width).step_by(TILE as usize) {
            tiles.push(Tile {
                x0,
                y0,
                x1: (x0 + TILE).min(width),
                y1: (y0 + TILE).min(height),
            });
        }
    }
    tiles
}

/// A progress bar on stderr with ETA, or a hidden one.
pub fn progress_bar(len: u64, label: &str, visible: bool) -> ProgressBar {
    if !visible {
        return ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::hidden());
    }
    let bar = ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::stderr());
    let style = ProgressStyle::with_template(
        "{prefix:>8} [{bar:40}] {percent:>3}% {elapsed_precise} ETA {eta_precise}",
    )
    .unwrap_or_else(|_| ProgressStyle::default_bar())
    .progress_chars("=> ");
    bar.set_style(style);
    bar.set_prefix(label.to_string());
    bar
}

/// Renders every pixel of the scene's camera with `settings`.
pub fn render(view: &SceneView, settings: &RenderSettings, estimator: Estimator) -> Film {
    let start = Instant::now();
    let camera = &view.scene.camera;
    let (width, height) = (camera.width, camera.height);
    let tiles = tiles(width, height);
    let bar = progress_bar(tiles.len() as u64, "render", settings.progress);
    let results: Vec<TileResult> = tiles
        .par_iter()
        .map(|tile| {
            let result = render_tile(view, settings, estimator, tile, None);
            bar.inc(1);
            result
        })
        .collect();
    bar.finish_and_clear();

    let mut image = Image::new(width, height);
    let mut variance_of_mean = vec![[0.0; 3]; (width * height) as usize];
    let mut rays = RayCounts::default();
    for result in &results {
        let spp = result.spp.max(1) as f64;
        for &(i, sum, sum_sq) in &result.sums {
            let m = sum / spp;
            // Unbiased sample variance, divided by spp for the variance of the mean.
            let var = if result.spp > 1 {
                (sum_sq - sum * m) / (spp - 1.0) / spp
            } else {
                DVec3::ZERO
            };
            image.pixels[i] = m.as_vec3().to_array();
            variance_of_mean[i] = var.max(DVec3::ZERO).to_array();
        }
        rays.add(result.rays);
    }
    Film {
        image,
        variance_of_mean,
        rays,
        elapsed: start.elapsed(),
    }
}

/// One sample of the radiance along camera ray `ray`: path tracing, guided by the guide when
/// given, or with a mixture the emission seen at the first hit plus the mixture's estimator
/// (eq. 8) from there.
#[allow(clippy::too_many_arguments)]
pub fn sample(
    view: &SceneView,
    ray: &Ray,
    max_bounces: u32,
    (mixture, guide): (Option<&Mixture>, Option<&Guide>),
    rng: &mut Rng,
    counts: &mut RayCounts,
    scratch: &mut MixtureScratch,
) -> DVec3 {
    let Some(mixture) = mixture else {
        return pt::radiance_guided(view, ray, max_bounces, rng, counts, guide, None).as_dvec3();
    };
    match view.trace(ray, counts) {
        None => DVec3::ZERO,
        Some(x1) => {
            let direct = emitted(view.material(x1.prim), &x1, -ray.dir).as_dvec3();
            direct + mixture.estimate(view, ray.origin, x1, max_bounces, rng, counts, scratch)
        }
    }
}

fn render_tile(
    view: &SceneView,
    settings: &RenderSettings,
    estimator: Estimator,
    tile: &Tile,
    mut recorder: Option<(&mut PathRecorder, u32)>,
) -> TileResult {
    let camera = &view.scene.camera;
    let n = ((tile.x1 - tile.x0) * (tile.y1 - tile.y0)) as usize;
    let mut sums = Vec::with_capacity(n);
    let mut rays = RayCounts::default();
    let mut scratch = MixtureScratch::default();
    // A guide per pixel, made in the same storage.
    // With a spatial guide, the samples its training took start every pixel's sums.
    // And where the plan's guides sample beside it.
    let (spatial, taken, levels) = match estimator {
        Estimator::Spatial(_, t) => (Some(Arc::clone(&t.guide)), Some(&t.samples), t.levels),
        _ => (None, None, Levels::All),
    };
    let spatial_guided = spatial.is_some();
    let mut guide = Guide::default().with_spatial(spatial);
    let (mut weights, mut parts) = (Vec::new(), Vec::new());
    for y in tile.y0..tile.y1 {
        for x in tile.x0..tile.x1 {
            let pixel = y as u64 * camera.width as u64 + x as u64;
            let local = match estimator {
                Estimator::Ga(plan) => plan.local(x, y),
                _ => None,
            };
            let guided = match estimator {
                Estimator::GaPt(plan) | Estimator::Spatial(Some(plan), _) => {
                    let guided =
                        !levels.off_at(x, y) && plan.local_parts(x, y, &mut weights, &mut parts);
                    if guided {
                        guide.rebuild(&parts);
                    } else if spatial_guided {
                        // No levels: the spatial guide alone.
                        guide.rebuild(&[]);
                    }
                    guided || spatial_guided
                }
                Estimator::Spatial(None, _) => true,
                _ => false,
            };
            let mixture = match estimator {
                Estimator::Pt | Estimator::GaPt(_) | Estimator::Spatial(..) => None,
                Estimator::Mixture(m) => Some(m),
                Estimator::Ga(_) => local.as_ref(),
            };
            let (mut sum, mut sum_sq) = match taken {
                Some(t) => t.at(pixel as usize),
                None => (DVec3::ZERO, DVec3::ZERO),
            };
            for s in 0..settings.spp {
                let mut rng = sample_rng(settings.seed, pixel, s as u64);
                // Box filter: a uniformly jittered position inside the pixel.
                let ray = camera.ray(x as f32 + uniform(&mut rng), y as f32 + uniform(&mut rng));
                let guide = guided.then_some(&guide);
                let recording = match &mut recorder {
                    Some((r, recorded)) if s < *recorded && mixture.is_none() => Some(&mut **r),
                    _ => None,
                };
                let value = match recording {
                    // Training a spatial guide: path tracing that records.
                    Some(r) => pt::radiance_guided(
                        view,
                        &ray,
                        settings.max_bounces,
                        &mut rng,
                        &mut rays,
                        guide,
                        Some(r),
                    )
                    .as_dvec3(),
                    None => sample(
                        view,
                        &ray,
                        settings.max_bounces,
                        (mixture, guide),
                        &mut rng,
                        &mut rays,
                        &mut scratch,
                    ),
                };
                sum += value;
                sum_sq += value * value;
            }
            sums.push((pixel as usize, sum, sum_sq));
        }
    }
    TileResult {
        sums,
        spp: taken.map_or(0, |t| t.spp) + settings.spp,
        rays,
    }
}

/// Stream tag of the spatial guide's training passes: disjoint from the render's streams.
const SPATIAL_STREAM: u64 = 0x7370_6174_6961_6c00;

/// Most training passes (the last one of 2048 samples per pixel).
pub const MAX_SPATIAL_PASSES: u32 = 12;

/// Records one training pass may keep (24 bytes each), at about [`RECORDS_PER_SAMPLE`]
/// records per path: a pass records that many of its samples per pixel and no more (at
/// 256², 61 samples per pixel).
const MAX_PASS_RECORDS: usize = 8_000_000;
const RECORDS_PER_SAMPLE: usize = 2;

/// Per pixel, the sums of the samples taken so far, which a render adds its own to.
#[derive(Clone, Debug, Default)]
pub struct PixelSums {
    /// Samples per pixel so far.
    pub spp: u32,
    sum: Vec<DVec3>,
    sum_sq: Vec<DVec3>,
}

impl PixelSums {
    /// Pixel `i`'s sum and sum of squares.
    fn at(&self, i: usize) -> (DVec3, DVec3) {
        (self.sum[i], self.sum_sq[i])
    }
}

/// A spatial guide and the path-traced samples its training took: they are samples of the
/// image like any other (each unbiased given the guide it was drawn with), and renders
/// keep them.
pub struct SpatialTraining {
    pub guide: Arc<SpatialGuide>,
    pub samples: PixelSums,
    /// Where a GA plan's per-pixel guides sample beside the spatial guide.
    pub levels: Levels,
}

/// Where a GA plan's per-pixel guides (`ga-pt`) sample beside the spatial guide.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Levels {
    /// At every pixel the plan guides.
    All,
    /// At fifteen pixels in sixteen: the sixteenth (row and column 3 modulo 4) is a
    /// training pass's control arm, left to the spatial guide alone.
    Trial,
    /// Nowhere: the trial found that they cost the spatial guide more than they gave.
    Off,
}

impl Levels {
    /// Whether pixel `(x, y)` renders without the plan's guides.
    fn off_at(self, x: u32, y: u32) -> bool {
        match self {
            Levels::All => false,
            Levels::Trial => x % 4 == 3 && y % 4 == 3,
            Levels::Off => true,
        }
    }
}

/// A training pass's trial of the plan's per-pixel guides decides when the pixels they
/// guide have more than this many times the mean relative variance of the control arm
/// (then the guides go), or less than its inverse (then they stay and trials stop); in
/// between, they stay for the next pass, which tries again. (2 s budgets, seeds 401–406:
/// glossy's pilot passes on seeds 404 and 405 only, and the trial of pass 2 gives 2.11 and
/// 1.91 there, where the guides doubled `ga-pt`'s error against `pg`; fig5 0.28–0.44.)
pub const LEVELS_KEEP_RATIO: f64 = 1.15;

/// The first training pass that tries the plan's guides: the guide that pass 1 samples with
/// has learned from one sample per pixel, too little to judge against.
pub const FIRST_TRIAL_PASS: u32 = 2;

/// A trial with fewer control pixels decides nothing: the plan's guides stay.
pub const MIN_TRIAL_PIXELS: usize = 256;

/// How long the spatial guide trains: pass `i` takes `2^i` samples per pixel, and the guide
/// the next pass samples with is learned from that pass's records alone (as in "practical
/// path guiding": each pass has as many samples as all the passes before it, and better
/// ones).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TrainingSchedule {
    /// This many passes.
    Passes(u32),
    /// Passes while their samples stay within half of `spp`.
    Samples(u32),
    /// Passes while the next one (twice the last one's time) fits in `seconds` in all.
    Seconds(f64),
}

impl TrainingSchedule {
    /// `plan.spatial_passes` if set, else a share of `plan.spatial_time_limit` if set, else
    /// half of `spp`.
    pub fn new(plan: &PlanConfig, spp: u32) -> Self {
        match (plan.spatial_passes, plan.spatial_time_limit) {
            (Some(p), _) => Self::Passes(p),
            (None, Some(t)) => Self::Seconds(t),
            (None, None) => Self::Samples(spp),
        }
    }

    /// Whether pass `pass` (`2^pass` samples per pixel) runs, after `elapsed` seconds of
    /// passes of which the last took `last` seconds.
    fn runs(&self, pass: u32, elapsed: f64, last: f64) -> bool {
        if pass == 0 {
            return true;
        }
        pass < MAX_SPATIAL_PASSES
            && match *self {
                Self::Passes(p) => pass < p,
                Self::Samples(spp) => (2u64 << pass) - 1 <= u64::from(spp / 2),
                Self::Seconds(t) => elapsed + 2.0 * last <= t,
            }
    }
}

/// A spatial guide trained by passes of path tracing (`schedule`): the first unguided
/// beyond `plan`'s levels (`ga-pt --spatial-guide`; `None` for `pg`), each later one guided
/// by the guide learned from the pass before it, every pass rendered as the final image is
/// (with `plan`'s per-pixel guides). Records and samples are gathered per tile and merged in
/// tile order, so the guide does not depend on the thread count.
///
/// With a plan that guides, the passes from [`FIRST_TRIAL_PASS`] on also try its guides:
/// each leaves one pixel in sixteen to the spatial guide alone ([`Levels::Trial`]) and
/// compares the two arms' relative variance, until the ratio leaves
/// `[1 / LEVELS_KEEP_RATIO, LEVELS_KEEP_RATIO]`; above it, the plan's guides sample nowhere
/// from then on ([`Levels::Off`]). The gate's pilot could only compare them with `pt`, since
/// the spatial guide learns after the plan (with the plan's guides: fig5 needs that). Which
/// estimator a later pass or the render uses depends on the samples of the passes before, as
/// the spatial guide itself does, never on its own samples: every sample stays unbiased.
pub fn train_spatial(
    view: &SceneView,
    settings: &RenderSettings,
    schedule: TrainingSchedule,
    plan: Option<&Plan>,
) -> SpatialTraining {
    let start = Instant::now();
    let camera = &view.scene.camera;
    let tiles = tiles(camera.width, camera.height);
    let pixels = (camera.width * camera.height) as usize;
    let mut records = Records::around(&view.scene.mesh);
    // Before the first pass: no samples, and a guide that has learned nothing.
    let mut training = SpatialTraining {
        guide: Arc::new(records.guide()),
        samples: PixelSums {
            spp: 0,
            sum: vec![DVec3::ZERO; pixels],
            sum_sq: vec![DVec3::ZERO; pixels],
        },
        levels: Levels::All,
    };
    let mut levels_trial = None;
    let open_plan = plan.filter(|p| !p.is_closed());
    let mut trialling = open_plan.is_some();
    let mut recorded_in_all = 0;
    let bar = progress_bar(0, "guide", settings.progress);
    let (mut pass, mut last) = (0, 0.0);
    while schedule.runs(pass, start.elapsed().as_secs_f64(), last) {
        let t0 = Instant::now();
        // From pass `FIRST_TRIAL_PASS` on, each pass tries the plan's guides against the
        // spatial guide alone until a trial decides (the guides stay where it does not).
        let trial = trialling && pass >= FIRST_TRIAL_PASS;
        if trial {
            training.levels = Levels::Trial;
        }
        let pass_settings = RenderSettings {
            spp: 1 << pass,
            seed: derive_seed(settings.seed, SPATIAL_STREAM ^ u64::from(pass)),
            ..settings.clone()
        };
        bar.set_length(u64::from(training.samples.spp + pass_settings.spp));
        let estimator = Estimator::Spatial(plan, &training);
        // The pass records its first `recorded` samples per pixel: records take memory.
        let recorded =
            (MAX_PASS_RECORDS / (RECORDS_PER_SAMPLE * pixels)).clamp(1, 1 << pass) as u32;
        let per_tile: Vec<_> = tiles
            .par_iter()
            .map(|tile| {
                let mut recorder = PathRecorder::new(&records);
                let recording = Some((&mut recorder, recorded));
                let result = render_tile(view, &pass_settings, estimator, tile, recording);
                (recorder, result.sums)
            })
            .collect();
        records.clear();
        let mut arms = TrialArms::new();
        for (recorder, sums) in per_tile {
            records.add_recorded(recorder);
            for (i, sum, sum_sq) in sums {
                if let (true, Some(plan)) = (trial, open_plan) {
                    let before = training.samples.at(i);
                    let n = pass_settings.spp;
                    // The mean of the passes before, independent of this pass's samples: a
                    // rare large sample must not lower its own pixel's relative variance.
                    let mean = before.0 / f64::from(training.samples.spp);
                    arms.add(
                        plan,
                        i,
                        camera.width,
                        (sum - before.0, sum_sq - before.1, n),
                        mean,
                    );
                }
                training.samples.sum[i] = sum;
                training.samples.sum_sq[i] = sum_sq;
            }
        }
        if trial {
            let outcome;
            (outcome, trialling) = arms.decide(pass);
            training.levels = if outcome.kept {
                Levels::All
            } else {
                Levels::Off
            };
            levels_trial = Some(outcome);
        }
        training.samples.spp += pass_settings.spp;
        recorded_in_all += records.len();
        training.guide = Arc::new(records.guide());
        bar.set_position(u64::from(training.samples.spp));
        last = t0.elapsed().as_secs_f64();
        pass += 1;
    }
    bar.finish_and_clear();
    // No other owner is left: this moves the guide out.
    let mut guide = Arc::unwrap_or_clone(training.guide);
    guide.stats.passes = pass;
    guide.stats.spp = training.samples.spp;
    guide.stats.records = recorded_in_all;
    guide.stats.seconds = start.elapsed().as_secs_f64();
    guide.stats.levels_trial = levels_trial;
    SpatialTraining {
        guide: Arc::new(guide),
        samples: training.samples,
        levels: training.levels,
    }
}

/// The two arms of a training pass's trial of a plan's per-pixel guides: per arm, the sum
/// over its pixels of a sample's relative variance, and its pixels. `weights` and `parts`
/// are [`Plan::local_parts`]'s buffers, reused for every pixel.
struct TrialArms<'a> {
    guided: (f64, usize),
    control: (f64, usize),
    weights: Vec<(f64, usize)>,
    parts: Vec<(f64, &'a Mixture)>,
}

impl<'a> TrialArms<'a> {
    fn new() -> Self {
        Self {
            guided: (0.0, 0),
            control: (0.0, 0),
            weights: Vec::new(),
            parts: Vec::new(),
        }
    }

    /// Adds pixel `i` of an image `width` wide, whose pass took `n` samples with sum and
    /// sum of squares `pass`, and whose mean over the passes before is `mean`. Pixels the plan
    /// does not guide (`pt`'s points, a closed plan) are in neither arm.
    fn add(
        &mut self,
        plan: &'a Plan,
        i: usize,
        width: u32,
        pass: (DVec3, DVec3, u32),
        mean: DVec3,
    ) {
        let (x, y) = ((i % width as usize) as u32, (i / width as usize) as u32);
        if !plan.local_parts(x, y, &mut self.weights, &mut self.parts) {
            return;
        }
        let (sum, sum_sq, n) = (pass.0, pass.1, f64::from(pass.2));
        // Unbiased sample variance of one sample, per channel, weighed as relMSE weighs.
        let variance = (sum_sq - sum * sum / n) / (n - 1.0);
        let relative = variance / (mean * mean + DVec3::splat(1e-2));
        let arm = if Levels::Trial.off_at(x, y) {
            &mut self.control
        } else {
            &mut self.guided
        };
        arm.0 += relative.max(DVec3::ZERO).element_sum() / 3.0;
        arm.1 += 1;
    }

    /// The trial's outcome in pass `pass`, and whether the next pass tries again: the
    /// guides stayed, but without a clear win (or with too few control pixels to tell).
    fn decide(&self, pass: u32) -> (LevelsTrial, bool) {
        let mean = |arm: (f64, usize)| arm.0 / arm.1.max(1) as f64;
        let ratio = mean(self.guided) / mean(self.control);
        // A ratio that is not a number (no variance in either arm) decides nothing.
        let undecided = self.control.1 < MIN_TRIAL_PIXELS || ratio.is_nan();
        let kept = undecided || ratio <= LEVELS_KEEP_RATIO;
        let trial = LevelsTrial {
            pass,
            guided_pixels: self.guided.1,
            control_pixels: self.control.1,
            ratio,
            kept,
        };
        (
            trial,
            kept && (undecided || ratio >= 1.0 / LEVELS_KEEP_RATIO),
        )
    }
}
