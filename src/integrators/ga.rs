//! `ga`: genetic path generation (paper §4–5). Each pixel renders eq. 8 with the mixture its
//! neighbouring GA pixels evolved, or with `pt` where the plan has none for it.

use super::{
    Context, Description, ExplainError, Integrator, Learned, Method, MethodInfo, PixelIntegrator,
    PrepareError, SelfCheck, Settings,
};
use crate::accel::Ray;
use crate::film::{PixelEstimator, PixelSums, Splats};
use crate::genetic::explain;
use crate::genetic::plan::{report, Plan, PlanFor, PlanInputs};
use crate::image::Image;
use crate::path::mixture::{Mixture, MixtureScratch};
use crate::path::pt::Unguided;
use crate::path::{camera_sample, RayCounts, SceneView};
use crate::sampling::Rng;
use crate::scene::Camera;
use glam::DVec3;

/// A GA plan rendered by its mixtures.
pub struct Ga {
    pub plan: Plan,
    pub max_bounces: u32,
    /// Whether the image keeps the plan's baseline samples: not in a shard rendered with a
    /// saved learned state ([`super::learned`]), whose training shard holds them.
    pub keeps_taken: bool,
    /// Whether the plan was read from a plan file rather than built.
    pub from_plan_file: bool,
}

/// `ga` learns a GA plan, whose GA pixels `learn --shard` splits over jobs, and explains it.
pub const METHOD: MethodInfo = MethodInfo {
    prepare_learned: Some(prepare_learned),
    splits_learning: true,
    explains: true,
    settings: &["srt", "ga", "plan", "gate", "lights"],
    ..MethodInfo::plain(prepare)
};

/// Builds the GA plan for `plan_for` with `context`'s settings; it keeps its baseline's
/// samples for the image where they help ([`Plan::settle_baseline`]).
pub fn build_plan(context: &Context, plan_for: PlanFor) -> Result<Plan, PrepareError> {
    let (config, settings) = (context.config, context.settings);
    let inputs = PlanInputs {
        ga: &config.ga,
        plan: &config.plan,
        gate: config.gate,
        plan_for,
        max_bounces: settings.max_bounces,
        srt_absorption: config
            .srt
            .absorption(plan_for.test_path_nee(config.srt.nee)),
        nee: config.srt.nee,
        spatial_guide: plan_for == PlanFor::Guide && config.spatial.spatial_guide,
        store: settings.learning.as_deref(),
    };
    let mut plan = Plan::build(context.view, &inputs, settings.seed, settings.progress)?;
    plan.settle_baseline(settings.spp, config.plan.baseline_keep_ratio);
    Ok(plan)
}

fn prepare(context: &Context) -> Result<Box<dyn Integrator>, PrepareError> {
    Ok(Box::new(Ga {
        plan: build_plan(context, PlanFor::Mixture)?,
        max_bounces: context.settings.max_bounces,
        keeps_taken: true,
        from_plan_file: false,
    }))
}

/// `ga` with the plan of `learned` (its baseline's samples are the learned samples).
fn prepare_learned(
    context: &Context,
    learned: Learned,
) -> Result<Box<dyn Integrator>, PrepareError> {
    let mut plan: Plan = learned.state()?;
    check_plan_size(&plan, context)?;
    plan.baseline = learned.samples.unwrap_or_default();
    Ok(Box::new(Ga {
        plan,
        max_bounces: context.settings.max_bounces,
        keeps_taken: context.settings.shard.is_whole(),
        from_plan_file: true,
    }))
}

/// Refuses a learned plan of another image size than `context`'s.
pub fn check_plan_size(plan: &Plan, context: &Context) -> Result<(), PrepareError> {
    let camera = &context.view.scene.camera;
    if (plan.width(), plan.height()) == (camera.width, camera.height) {
        return Ok(());
    }
    Err(PrepareError::Learned {
        method: context.settings.method.name(),
        what: format!(
            "a GA plan of {}×{} pixels for an image of {}×{}",
            plan.width(),
            plan.height(),
            camera.width,
            camera.height
        ),
    })
}

/// A GA plan's part of a method's [`Description`]: its JSON statistics (`ga`), its phases'
/// seconds (`baseline`, `ga`) and its line on stderr.
pub fn describe_plan(plan: &Plan, config: &Settings, from_plan_file: bool) -> Description {
    let configs = (&config.ga, &config.plan, &config.gate);
    let mut description = Description::default();
    (description.stats).insert("ga".into(), report::json(plan, configs, from_plan_file));
    description.phases = vec![
        ("baseline", plan.stats.baseline_seconds),
        ("ga", plan.stats.ga_seconds),
    ];
    let improved = plan.pixels.iter().filter(|p| !p.kept_srt).count();
    description.lines.push(format!(
        "genpath: GA on {} pixels ({improved} improved on srt) in {:.2} s",
        plan.pixels.len(),
        plan.elapsed().as_secs_f64()
    ));
    description
}

/// What a plan file's header says of a GA plan.
pub fn plan_summary(plan: &Plan) -> serde_json::Value {
    serde_json::json!({
        "plan_for": plan.plan_for,
        "ga_pixels": plan.pixels.len(),
        "improved_pixels": plan.pixels.iter().filter(|x| !x.kept_srt).count(),
        "fallback_points": plan.fallback_points.len(),
        "closed_by_gate": plan.is_closed(),
        "stats": plan.stats,
    })
}

/// `render --explain`'s picture of what `plan` learned over `image`.
pub fn explain_plan(camera: &Camera, image: &Image, plan: &Plan) -> Result<String, ExplainError> {
    explain::svg(camera, image, plan).map_err(|e| ExplainError(e.into()))
}

/// What `check` verifies of `plan`: the mixtures it evolved, at their GA pixels, and its
/// fitness values (eq. 10's variances, and each generation's best and mean).
pub fn plan_check(plan: &Plan) -> SelfCheck<'_> {
    let pixels = plan.pixels.iter();
    SelfCheck {
        mixtures: pixels.clone().map(|p| ((p.x, p.y), &p.mixture)).collect(),
        numbers: pixels
            .flat_map(|p| {
                [p.v_srt, p.v_best]
                    .into_iter()
                    .chain(p.history.iter().flat_map(|h| [h.best, h.mean]))
            })
            .collect(),
    }
}

/// A pixel's mixture from the plan (none: `pt`).
pub struct GaEstimator<'a> {
    plan: &'a Plan,
    max_bounces: u32,
    local: Option<Mixture>,
    scratch: MixtureScratch,
}

impl PixelIntegrator for Ga {
    type Estimator<'a> = GaEstimator<'a>;
    fn estimator(&self) -> GaEstimator<'_> {
        GaEstimator {
            plan: &self.plan,
            max_bounces: self.max_bounces,
            local: None,
            scratch: MixtureScratch::default(),
        }
    }
    fn taken(&self) -> Option<&PixelSums> {
        self.plan.baseline().filter(|_| self.keeps_taken)
    }
    fn taken_spp(&self) -> u32 {
        self.plan.baseline.spp
    }
    fn learned(&self) -> Option<Learned> {
        let mut plan = self.plan.clone();
        let baseline = std::mem::take(&mut plan.baseline);
        let samples = (baseline.spp > 0).then_some(baseline);
        let summary = serde_json::json!({ "plan": plan_summary(&self.plan), "spatial": null });
        Some(Learned::new(Method::Ga, samples, &plan, &summary))
    }
    fn describe(&self, config: &Settings) -> Description {
        describe_plan(&self.plan, config, self.from_plan_file)
    }
    fn explain(&self, camera: &Camera, image: &Image) -> Option<Result<String, ExplainError>> {
        Some(explain_plan(camera, image, &self.plan))
    }
    fn self_check(&self) -> SelfCheck<'_> {
        plan_check(&self.plan)
    }
}

impl PixelEstimator for GaEstimator<'_> {
    fn start(&mut self, x: u32, y: u32) {
        self.local = self.plan.local(x, y);
    }
    fn sample(
        &mut self,
        view: &SceneView,
        ray: &Ray,
        rng: &mut Rng,
        counts: &mut RayCounts,
        _splats: &mut Splats,
    ) -> DVec3 {
        let mixture = (self.local.as_ref(), None::<&Unguided>);
        camera_sample(
            view,
            ray,
            self.max_bounces,
            mixture,
            rng,
            counts,
            &mut self.scratch,
        )
    }
}
