//! `ga`: genetic path generation (paper §4–5). Each pixel renders eq. 8 with the mixture its
//! neighbouring GA pixels evolved, or with `pt` where the plan has none for it.

use super::{Context, Integrator, Learned, PixelIntegrator, PrepareError};
use crate::accel::Ray;
use crate::film::{PixelEstimator, PixelSums, Splats};
use crate::genetic::plan::{Plan, PlanFor, PlanInputs};
use crate::path::mixture::{Mixture, MixtureScratch};
use crate::path::pt::Unguided;
use crate::path::{camera_sample, RayCounts, SceneView};
use crate::sampling::Rng;
use glam::DVec3;

/// A GA plan rendered by its mixtures.
pub struct Ga {
    pub plan: Plan,
    pub max_bounces: u32,
    /// Whether the image keeps the plan's baseline samples: not in a shard rendered with a
    /// saved learned state ([`super::learned`]), whose training shard holds them.
    pub keeps_taken: bool,
}

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

pub fn prepare(context: &Context) -> Result<Box<dyn Integrator>, PrepareError> {
    Ok(Box::new(Ga {
        plan: build_plan(context, PlanFor::Mixture)?,
        max_bounces: context.settings.max_bounces,
        keeps_taken: true,
    }))
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
    fn plan(&self) -> Option<&Plan> {
        Some(&self.plan)
    }
    fn learned(&self) -> Option<Learned> {
        Some(Learned {
            plan: Some(self.plan.clone()),
            spatial: None,
        })
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
