//! `pg`: path tracing guided by a spatial guide ([`crate::guiding::field`]) learned from
//! path-traced training passes whose samples stay in the image; also `ga-pt` with the
//! spatial guide, whose training passes render with the GA plan's per-pixel guides.
//!
//! The integrator owns its training loop (as in Müller's `guided_path.cpp`): pass `i` takes
//! `2^i` samples per pixel, rendered by the shared image loop with an estimator that
//! records, and the next pass samples with the guide learned from it.

use super::ga::{check_plan_size, describe_plan, explain_plan, plan_check, plan_summary};
use super::settings::{SpatialConfig, MAX_SPATIAL_PASSES};
use super::{
    Context, Control, Description, ExplainError, Integrator, Learned, Method, MethodInfo,
    PixelIntegrator, PrepareError, RenderSettings, SelfCheck, Settings,
};
use crate::accel::Ray;
use crate::film::{self, render_tile, Pass, PixelEstimator, PixelResult, PixelSums, Splats};
use crate::genetic::plan::{LearnStore, Plan};
use crate::guiding::selection::Selection;
use crate::guiding::{Guide, GuidesTrial, PathSegmentStorage, SampleStorage, SpatialField};
use crate::image::Image;
use crate::path::mixture::Mixture;
use crate::path::pt::Unguided;
use crate::path::{pt, RayCounts, SceneView};
use crate::progress::progress_bar;
use crate::sampling::{derive_seed, Rng, Stream};
use crate::scene::Camera;
use glam::DVec3;
use rayon::prelude::*;
use std::sync::Arc;
use std::time::Instant;

/// `pg` learns a spatial guide (its training passes run in one job).
pub const METHOD: MethodInfo = MethodInfo {
    prepare_learned: Some(prepare_learned),
    settings: &["spatial", "lights"],
    ..MethodInfo::plain(prepare)
};

fn prepare(context: &Context) -> Result<Box<dyn Integrator>, PrepareError> {
    check_schedule(context)?;
    Ok(Box::new(train(context, None)?))
}

fn prepare_learned(
    context: &Context,
    learned: Learned,
) -> Result<Box<dyn Integrator>, PrepareError> {
    Ok(Box::new(SpatialIntegrator::learned(context, learned)?))
}

/// Refuses `--spatial-passes` whose training would take more samples than `--spp`.
pub fn check_schedule(context: &Context) -> Result<(), PrepareError> {
    let (spatial, spp) = (&context.config.spatial, context.settings.spp);
    if let TrainingSchedule::Passes(passes) = TrainingSchedule::new(spatial, spp) {
        let needs = (1u64 << passes) - 1;
        if spatial.spatial_time_limit.is_none() && needs > u64::from(spp) {
            return Err(PrepareError::TrainingExceedsSpp { passes, needs, spp });
        }
    }
    Ok(())
}

/// Trains the spatial guide with `context`'s settings, beside a GA plan's per-pixel guides
/// and their trial where given (`ga-pt`).
pub fn train(
    context: &Context,
    beside: Option<(Plan, &dyn PlanTrial)>,
) -> Result<SpatialIntegrator, PrepareError> {
    let schedule = TrainingSchedule::new(&context.config.spatial, context.settings.spp);
    let trained_beside = beside.as_ref().map(|(plan, trial)| Beside {
        plan,
        trial: *trial,
    });
    let selection = context.config.spatial.guide_selection;
    let training = train_spatial(
        context.view,
        context.settings,
        (schedule, selection),
        trained_beside,
    )?;
    let plan = beside.map(|(plan, _)| plan);
    Ok(SpatialIntegrator {
        method: context.settings.method,
        plan,
        training,
        max_bounces: context.settings.max_bounces,
        keeps_taken: true,
        from_plan_file: false,
    })
}

/// What a spatial guide's training leaves to a plan file beside its samples: the guide, the
/// GA plan it trained beside (`ga-pt`), and where that plan's guides sample.
#[derive(serde::Serialize, serde::Deserialize)]
struct SpatialState {
    plan: Option<Plan>,
    guide: SpatialField,
    plan_guides: PlanGuides,
}

/// Path tracing guided by a trained spatial guide, beside a GA plan's per-pixel guides
/// where it has one (`ga-pt`) and where the training's trial left them.
pub struct SpatialIntegrator {
    /// The method it is (`pg`, or `ga-pt` with its plan), which its learned state names.
    pub method: Method,
    pub plan: Option<Plan>,
    pub training: SpatialTraining,
    pub max_bounces: u32,
    /// Whether the image keeps the training's samples: not in a shard rendered with a
    /// saved learned state ([`super::learned`]), whose training shard holds them.
    pub keeps_taken: bool,
    /// Whether the guide (and plan) were read from a plan file rather than trained.
    pub from_plan_file: bool,
}

impl SpatialIntegrator {
    /// The integrator of `learned`, a spatial training's state (`pg`'s, or `ga-pt`'s with
    /// its GA plan).
    pub fn learned(context: &Context, learned: Learned) -> Result<Self, PrepareError> {
        let mismatch = |what: String| PrepareError::Learned {
            method: context.settings.method.name(),
            what,
        };
        let state: SpatialState = learned.state()?;
        if let Some(plan) = &state.plan {
            check_plan_size(plan, context)?;
        }
        state.guide.check().map_err(|e| mismatch(e.to_string()))?;
        let Some(samples) = learned.samples else {
            return Err(mismatch(
                "a spatial guide without its training's samples".into(),
            ));
        };
        let settings = context.settings;
        Ok(Self {
            method: settings.method,
            plan: state.plan,
            training: SpatialTraining {
                guide: Arc::new(state.guide),
                samples,
                plan_guides: state.plan_guides,
            },
            max_bounces: settings.max_bounces,
            keeps_taken: settings.shard.is_whole(),
            from_plan_file: true,
        })
    }
}

impl PixelIntegrator for SpatialIntegrator {
    type Estimator<'a> = SpatialEstimator<'a>;
    fn estimator(&self) -> SpatialEstimator<'_> {
        SpatialEstimator::new(self.plan.as_ref(), &self.training, self.max_bounces, None)
    }
    fn taken(&self) -> Option<&PixelSums> {
        self.keeps_taken.then_some(&self.training.samples)
    }
    fn taken_spp(&self) -> u32 {
        self.training.samples.spp
    }
    fn learned(&self) -> Option<Learned> {
        let training = &self.training;
        let summary = serde_json::json!({
            "plan": self.plan.as_ref().map(plan_summary),
            "spatial": { "stats": training.guide.stats, "plan_guides": training.plan_guides },
        });
        let state = SpatialState {
            plan: self.plan.clone(),
            guide: training.guide.as_ref().clone(),
            plan_guides: training.plan_guides,
        };
        Some(Learned::new(
            self.method,
            Some(training.samples.clone()),
            &state,
            &summary,
        ))
    }
    fn describe(&self, config: &Settings) -> Description {
        let mut description = match &self.plan {
            Some(plan) => describe_plan(plan, config, self.from_plan_file),
            None => Description::default(),
        };
        let s = &self.training.guide.stats;
        (description.stats).insert("spatial".into(), serde_json::json!(s));
        description.phases.push(("spatial", s.seconds));
        description.lines.push(format!(
            "genpath: spatial guide: {} of {} regions trained on {} records from {} passes ({} spp of the image) in {:.2} s",
            s.trained_cells, s.cells, s.records, s.passes, s.spp, s.seconds
        ));
        description
    }
    fn explain(&self, camera: &Camera, image: &Image) -> Option<Result<String, ExplainError>> {
        (self.plan.as_ref()).map(|plan| explain_plan(camera, image, plan))
    }
    fn self_check(&self) -> SelfCheck<'_> {
        self.plan
            .as_ref()
            .map_or_else(SelfCheck::default, plan_check)
    }
}

/// A pixel's guide, rebuilt in the same storage at every pixel.
pub struct GuideEstimator<'a> {
    plan: Option<&'a Plan>,
    max_bounces: u32,
    guide: Guide,
    guided: bool,
    weights: Vec<(f64, usize)>,
    parts: Vec<(f64, &'a Mixture)>,
}

impl<'a> GuideEstimator<'a> {
    pub fn new(plan: Option<&'a Plan>, max_bounces: u32, guide: Guide) -> Self {
        Self {
            plan,
            max_bounces,
            guide,
            guided: false,
            weights: Vec::new(),
            parts: Vec::new(),
        }
    }

    /// Rebuilds the guide for pixel `(x, y)` from the plan's levels there, unless
    /// `levels_off`; whether they guide it. Where they do not, a plan's guide is remade
    /// with no levels when `clear`.
    pub fn start_levels(&mut self, (x, y): (u32, u32), levels_off: bool, clear: bool) -> bool {
        let Some(plan) = self.plan else {
            return false;
        };
        let guided =
            !levels_off && plan.neighbour_mixtures(x, y, &mut self.weights, &mut self.parts);
        if guided {
            self.guide.rebuild(&self.parts);
        } else if clear {
            self.guide.rebuild(&[]);
        }
        guided
    }

    /// Path tracing guided by the guide as set for the pixel (`guided`), recording into
    /// `recorder` when given.
    pub fn radiance(
        &self,
        (view, ray): (&SceneView, &Ray),
        guided: bool,
        rng: &mut Rng,
        counts: &mut RayCounts,
        recorder: Option<&mut PathSegmentStorage>,
    ) -> DVec3 {
        let max_bounces = self.max_bounces;
        let radiance = match guided {
            true => pt::radiance_guided(view, ray, max_bounces, rng, counts, &self.guide, recorder),
            false => pt::radiance_guided(view, ray, max_bounces, rng, counts, &Unguided, recorder),
        };
        radiance.as_dvec3()
    }
}

impl PixelEstimator for GuideEstimator<'_> {
    fn start(&mut self, x: u32, y: u32) {
        self.guided = self.start_levels((x, y), false, false);
    }
    fn sample(
        &mut self,
        view: &SceneView,
        ray: &Ray,
        rng: &mut Rng,
        counts: &mut RayCounts,
        _splats: &mut Splats,
    ) -> DVec3 {
        self.radiance((view, ray), self.guided, rng, counts, None)
    }
}

/// A pixel's guide: the plan's levels where they sample, the spatial guide everywhere
/// else. In a training pass it records its pixel's first samples.
pub struct SpatialEstimator<'a> {
    guide: GuideEstimator<'a>,
    plan_guides: PlanGuides,
    recorder: Option<(PathSegmentStorage, u32)>,
    /// Samples of the pixel so far.
    taken: u32,
}

impl<'a> SpatialEstimator<'a> {
    /// With `recorder`, each pixel's first `.1` samples record into it.
    fn new(
        plan: Option<&'a Plan>,
        training: &SpatialTraining,
        max_bounces: u32,
        recorder: Option<(PathSegmentStorage, u32)>,
    ) -> Self {
        let guide = Guide::default().with_spatial(Some(Arc::clone(&training.guide)));
        Self {
            guide: GuideEstimator::new(plan, max_bounces, guide),
            plan_guides: training.plan_guides,
            recorder,
            taken: 0,
        }
    }
}

impl PixelEstimator for SpatialEstimator<'_> {
    fn start(&mut self, x: u32, y: u32) {
        self.guide
            .start_levels((x, y), self.plan_guides.off_at(x, y), true);
        self.taken = 0;
    }
    fn sample(
        &mut self,
        view: &SceneView,
        ray: &Ray,
        rng: &mut Rng,
        counts: &mut RayCounts,
        _splats: &mut Splats,
    ) -> DVec3 {
        let recorder = match &mut self.recorder {
            Some((r, recorded)) if self.taken < *recorded => Some(r),
            _ => None,
        };
        self.taken += 1;
        self.guide
            .radiance((view, ray), true, rng, counts, recorder)
    }
}

/// Records one training pass may keep (24 bytes each), at about [`RECORDS_PER_SAMPLE`]
/// records per path: a pass records that many of its samples per pixel and no more (at
/// 256², 61 samples per pixel).
const MAX_PASS_RECORDS: usize = 8_000_000;
const RECORDS_PER_SAMPLE: usize = 2;

/// A spatial guide and the path-traced samples its training took: they are samples of the
/// image like any other (each unbiased given the guide it was drawn with), and renders
/// keep them.
#[derive(serde::Serialize, serde::Deserialize)]
pub struct SpatialTraining {
    pub guide: Arc<SpatialField>,
    pub samples: PixelSums,
    /// Where a GA plan's per-pixel guides sample beside the spatial guide.
    pub plan_guides: PlanGuides,
}

/// Where a GA plan's per-pixel guides (`ga-pt`) sample beside the spatial guide.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum PlanGuides {
    /// At every pixel the plan guides.
    Everywhere,
    /// At fifteen pixels in sixteen, outside a training pass's trial's control arm: the
    /// sixteenth (row and column 3 modulo 4), left to the spatial guide alone.
    OutsideControl,
    /// Nowhere: the trial found that they cost the spatial guide more than they gave.
    Nowhere,
}

impl PlanGuides {
    /// Whether pixel `(x, y)` renders without the plan's guides.
    pub fn off_at(self, x: u32, y: u32) -> bool {
        match self {
            PlanGuides::Everywhere => false,
            PlanGuides::OutsideControl => x % 4 == 3 && y % 4 == 3,
            PlanGuides::Nowhere => true,
        }
    }
}

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
    /// `spatial_passes` if set, else a share of `spatial_time_limit` if set, else half of
    /// `spp`.
    pub fn new(config: &SpatialConfig, spp: u32) -> Self {
        match (config.spatial_passes, config.spatial_time_limit) {
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

/// The settings of training pass `pass` (`2^pass` samples per pixel from its own stream) of
/// a render with `settings`: nothing resumes or checkpoints it, and a stop (`genpath learn`
/// on a signal) ends it and the training, which the learning then discards.
fn training_pass(settings: &RenderSettings, pass: u32) -> Pass {
    Pass {
        run_spp: 1 << pass,
        seed: derive_seed(settings.seed, Stream::Spatial.tag() ^ u64::from(pass)),
        shard: settings.shard,
        control: Control {
            stop: settings.control.stop.clone(),
            ..Default::default()
        },
        progress: settings.progress,
    }
}

/// Per-pixel guides that sample beside the spatial guide (a GA plan's, `ga-pt`'s), and the
/// trial of them that the training passes run.
#[derive(Clone, Copy)]
pub struct Beside<'a> {
    pub plan: &'a Plan,
    pub trial: &'a dyn PlanTrial,
}

/// A trial of a plan's per-pixel guides against the spatial guide alone, run by the
/// training passes (`ga-pt`'s, in `integrators::ga_pt`): a pass that tries leaves the control
/// pixels ([`PlanGuides::OutsideControl`]) to the spatial guide alone, and its arms decide
/// after the pass whether the guides stay ([`PlanGuides::Everywhere`]) or go
/// ([`PlanGuides::Nowhere`]).
pub trait PlanTrial: Sync {
    /// Whether pass `pass` tries the guides (while no trial has decided).
    fn tries(&self, pass: u32) -> bool;
    /// The arms of one pass over an image `width` pixels wide, after passes whose sums are
    /// `before`.
    fn arms<'a>(&self, plan: &'a Plan, before: &PixelSums, width: u32) -> Box<dyn TrialArms + 'a>;
}

/// The arms of one training pass's trial ([`PlanTrial`]).
pub trait TrialArms {
    /// Adds pixel `i`'s new samples of the pass: their sum, sum of squares and count, taken
    /// at a cost of `cost` rays.
    fn add(&mut self, i: usize, pass: (DVec3, DVec3, u32), cost: f64);
    /// The trial's outcome in pass `pass`, and whether the next pass tries again.
    fn decide(&self, pass: u32) -> (GuidesTrial, bool);
}

/// A spatial guide trained by passes of path tracing (`schedule`): the first unguided
/// beyond `beside`'s plan's levels (`ga-pt --spatial-guide`; `None` for `pg`), each later
/// one guided by the guide learned from the pass before it, every pass rendered as the
/// final image is (with the plan's per-pixel guides). Records and samples are gathered per
/// tile and merged in tile order, so the guide does not depend on the thread count.
///
/// With a plan that guides, the passes that its [`PlanTrial`] tries compare the guides with
/// the spatial guide alone. Which estimator a later pass or the render uses depends on the
/// samples of the passes before, as the spatial guide itself does, never on its own
/// samples: every sample stays unbiased.
pub fn train_spatial(
    view: &SceneView,
    settings: &RenderSettings,
    (schedule, selection): (TrainingSchedule, Selection),
    beside: Option<Beside>,
) -> Result<SpatialTraining, PrepareError> {
    let plan = beside.map(|b| b.plan);
    let start = Instant::now();
    let camera = &view.scene.camera;
    let tiles = film::tiles(camera.width, camera.height);
    let pixels = (camera.width * camera.height) as usize;
    let mut records =
        SampleStorage::around(&view.scene.mesh).learning_selection(selection == Selection::Learned);
    let open_plan = plan.filter(|p| !p.is_closed());
    let store = settings.learning.as_deref();
    let mut at = Between::start(store, &mut records, pixels, open_plan.is_some())?;
    let bar = progress_bar(0, "guide", settings.progress);
    let stop = &settings.control.stop;
    let elapsed = |at: &Between| at.seconds + start.elapsed().as_secs_f64();
    while schedule.runs(at.passes, elapsed(&at), at.last) && stop.requested().is_none() {
        let t0 = Instant::now();
        let pass = at.passes;
        let training = &mut at.training;
        // Until a trial decides, the passes the trial tries leave the control pixels to the
        // spatial guide alone (the guides stay where it does not decide).
        let trial = at.trialling && beside.is_some_and(|b| b.trial.tries(pass));
        if trial {
            training.plan_guides = PlanGuides::OutsideControl;
        }
        let pass_settings = training_pass(settings, pass);
        bar.set_length(u64::from(training.samples.spp + pass_settings.run_spp));
        // The pass records its first `recorded` samples per pixel: records take memory.
        let recorded =
            (MAX_PASS_RECORDS / (RECORDS_PER_SAMPLE * pixels)).clamp(1, 1 << pass) as u32;
        let per_tile: Vec<_> = tiles
            .par_iter()
            .map(|tile| {
                let recorder = Some((PathSegmentStorage::new(&records), recorded));
                let max_bounces = settings.max_bounces;
                let mut estimator = SpatialEstimator::new(plan, training, max_bounces, recorder);
                let result = render_tile(
                    view,
                    &pass_settings,
                    &mut estimator,
                    Some(&training.samples),
                    tile,
                );
                let Some((recorder, _)) = estimator.recorder else {
                    unreachable!("made with a recorder");
                };
                (recorder, result.sums)
            })
            .collect();
        if stop.requested().is_some() {
            // A pass cut short: the training stands as after the last whole one.
            break;
        }
        records.clear();
        let mut arms = (beside.filter(|_| trial))
            .map(|b| b.trial.arms(b.plan, &training.samples, camera.width));
        merge_pass(
            per_tile,
            &mut records,
            training,
            arms.as_deref_mut(),
            pass_settings.run_spp,
        );
        if let Some(arms) = arms {
            let outcome;
            (outcome, at.trialling) = arms.decide(pass);
            training.plan_guides = if outcome.kept {
                PlanGuides::Everywhere
            } else {
                PlanGuides::Nowhere
            };
            at.guides_trial = Some(outcome);
        }
        training.samples.spp += pass_settings.run_spp;
        at.recorded_in_all += records.len();
        training.guide = Arc::new(records.field());
        bar.set_position(u64::from(training.samples.spp));
        at.last = t0.elapsed().as_secs_f64();
        at.passes += 1;
        if let Some(store) = store {
            at.keep(store, elapsed(&at), &records)?;
        }
    }
    bar.finish_and_clear();
    let seconds = elapsed(&at);
    let Between {
        passes,
        training,
        guides_trial,
        recorded_in_all,
        ..
    } = at;
    // No other owner is left: this moves the guide out.
    let mut guide = Arc::unwrap_or_clone(training.guide);
    guide.stats.passes = passes;
    guide.stats.spp = training.samples.spp;
    guide.stats.records = recorded_in_all;
    guide.stats.seconds = seconds;
    guide.stats.guides_trial = guides_trial;
    Ok(SpatialTraining {
        guide: Arc::new(guide),
        samples: training.samples,
        plan_guides: training.plan_guides,
    })
}

/// The training between two passes: what the next pass starts from, which `genpath learn`
/// keeps after each pass ([`crate::genetic::plan::LearnStore::save_training`], with the
/// seconds so far and the records' dark cells beside it), so that learning stopped by a
/// signal goes on from the next pass to the same guide.
#[derive(serde::Serialize, serde::Deserialize)]
struct Between {
    /// Passes finished.
    passes: u32,
    training: SpatialTraining,
    /// The last decided trial of a plan's guides, and whether the trials go on.
    guides_trial: Option<GuidesTrial>,
    trialling: bool,
    recorded_in_all: usize,
    /// Seconds of the passes of earlier processes (a time schedule's clock goes on from
    /// them; kept beside the state), and of the last pass.
    #[serde(skip)]
    seconds: f64,
    last: f64,
}

impl Between {
    /// Keeps this training in `store` after a finished pass, with the seconds so far and the
    /// records' dark cells ([`SampleStorage::dark`]), which the next guide keeps.
    fn keep(
        &self,
        store: &dyn LearnStore,
        seconds: f64,
        records: &SampleStorage,
    ) -> Result<(), PrepareError> {
        let kept = |e: String| PrepareError::Kept(e);
        let bytes = bincode::serialize(&(self, seconds, records.dark()))
            .map_err(|e| kept(e.to_string()))?;
        store
            .save_training(self.passes, &bytes)
            .map_err(|e| kept(e.to_string()))
    }

    /// The training kept by an earlier process in `store` (and its records' dark cells,
    /// set in `records`), or, before the first pass, no samples and a guide that has learned
    /// nothing; `trialling` whether a plan's guides are to be tried.
    fn start(
        store: Option<&dyn LearnStore>,
        records: &mut SampleStorage,
        pixels: usize,
        trialling: bool,
    ) -> Result<Self, PrepareError> {
        let kept = |e: String| PrepareError::Kept(e);
        let loaded = store.map(|s| s.load_training()).transpose();
        let at = match loaded.map_err(|e| kept(e.to_string()))? {
            Some(Some(bytes)) => {
                let (at, seconds, dark): (Between, f64, Vec<bool>) =
                    bincode::deserialize(&bytes)
                        .map_err(|e| kept(format!("the spatial guide's training: {e}")))?;
                records.set_dark(dark).map_err(|e| kept(e.to_string()))?;
                Between { seconds, ..at }
            }
            _ => Between {
                passes: 0,
                training: SpatialTraining {
                    guide: Arc::new(records.field()),
                    samples: PixelSums::zero(pixels),
                    plan_guides: PlanGuides::Everywhere,
                },
                guides_trial: None,
                trialling,
                recorded_in_all: 0,
                seconds: 0.0,
                last: 0.0,
            },
        };
        if at.training.samples.sum.len() != pixels {
            return Err(kept(format!(
                "the spatial guide's kept training is of {} pixels, not {pixels}",
                at.training.samples.sum.len()
            )));
        }
        Ok(at)
    }
}

/// Merges a training pass of `spp` samples per pixel, tile by tile in tile order: its
/// records into `records`, its pixel sums into `training`'s, and, in a pass that tries a
/// plan's guides, each pixel's new samples into the trial's `arms`.
fn merge_pass(
    per_tile: Vec<(PathSegmentStorage, Vec<PixelResult>)>,
    records: &mut SampleStorage,
    training: &mut SpatialTraining,
    mut arms: Option<&mut (dyn TrialArms + '_)>,
    spp: u32,
) {
    for (recorder, sums) in per_tile {
        records.add_recorded(recorder);
        for pixel in sums {
            let (i, sum, sum_sq) = (pixel.index, pixel.sum, pixel.sum_sq);
            if let Some(arms) = arms.as_deref_mut() {
                let before = training.samples.at(i);
                arms.add(i, (sum - before.0, sum_sq - before.1, spp), pixel.cost);
            }
            training.samples.sum[i] = sum;
            training.samples.sum_sq[i] = sum_sq;
        }
    }
}
