//! `ga-pt`: path tracing guided at each pixel by the directional samplers of the mixtures
//! its neighbouring GA pixels evolved ([`Guide`]); with the spatial guide (the default),
//! the vertices past them are guided as `pg` guides them ([`super::pg`]).

use super::ga::{
    build_plan, check_plan_size, describe_plan, explain_plan, plan_check, plan_summary,
};
use super::pg::SpatialIntegrator;
use super::{
    pg, Context, Description, ExplainError, Integrator, Learned, Method, MethodInfo,
    PixelIntegrator, PrepareError, SelfCheck, Settings,
};
use crate::accel::Ray;
use crate::film::{PixelEstimator, Splats};
use crate::genetic::plan::{Plan, PlanFor};
use crate::guiding::{Guide, PathSegmentStorage};
use crate::image::Image;
use crate::path::mixture::Mixture;
use crate::path::pt::Unguided;
use crate::path::{pt, RayCounts, SceneView};
use crate::sampling::Rng;
use crate::scene::Camera;
use glam::DVec3;

/// A GA plan's guides, with path tracing's own sampling past them.
pub struct GaPt {
    pub plan: Plan,
    pub max_bounces: u32,
    /// Whether the plan was read from a plan file rather than built.
    pub from_plan_file: bool,
}

/// `ga-pt` learns a GA plan (whose GA pixels `learn --shard` splits over jobs), and with
/// the spatial guide the guide's training beside it; it explains its plan.
pub const METHOD: MethodInfo = MethodInfo {
    prepare_learned: Some(prepare_learned),
    splits_learning: true,
    explains: true,
    ..MethodInfo::plain(prepare)
};

/// `ga-pt` from a learned plan, with the spatial guide's learned training where the
/// settings ask for the guide.
fn prepare_learned(
    context: &Context,
    learned: Learned,
) -> Result<Box<dyn Integrator>, PrepareError> {
    if context.config.spatial.spatial_guide {
        return Ok(Box::new(SpatialIntegrator::learned(context, learned)?));
    }
    let plan: Plan = learned.state()?;
    check_plan_size(&plan, context)?;
    Ok(Box::new(GaPt {
        plan,
        max_bounces: context.settings.max_bounces,
        from_plan_file: true,
    }))
}

fn prepare(context: &Context) -> Result<Box<dyn Integrator>, PrepareError> {
    let spatial = context.config.spatial.spatial_guide;
    if spatial {
        pg::check_schedule(context)?;
    }
    let plan = build_plan(context, PlanFor::Guide)?;
    if spatial {
        return Ok(Box::new(pg::train(context, Some(plan))?));
    }
    Ok(Box::new(GaPt {
        plan,
        max_bounces: context.settings.max_bounces,
        from_plan_file: false,
    }))
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

impl PixelIntegrator for GaPt {
    type Estimator<'a> = GuideEstimator<'a>;
    fn estimator(&self) -> GuideEstimator<'_> {
        GuideEstimator::new(Some(&self.plan), self.max_bounces, Guide::default())
    }
    fn learned(&self) -> Option<Learned> {
        let summary = serde_json::json!({ "plan": plan_summary(&self.plan), "spatial": null });
        Some(Learned::new(Method::GaPt, None, &self.plan, &summary))
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
