//! What a method that learns learned while it was prepared ([`Learned`]): the GA plan of
//! `ga` and `ga-pt`, and the spatial guide of `pg` and `ga-pt` with its training passes'
//! per-pixel sums and the decision of its trial of the plan's guides. Saved in a plan file
//! (`genpath learn`, [`crate::shard::plan_file`]) it prepares the method again without
//! training ([`prepare_learned`]): the render is the one that trained in-process, bit for
//! bit, and shards of it render with one learned state.

use super::ga::Ga;
use super::ga_pt::GaPt;
use super::pg::{PlanGuides, SpatialIntegrator, SpatialTraining};
use super::{Integrator, Method, PixelSums, PrepareError, RenderSettings, Settings};
use crate::genetic::plan::Plan;
use crate::guiding::SpatialField;
use crate::path::SceneView;
use std::sync::Arc;

/// The learned state of a prepared method.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Learned {
    /// The GA plan (`ga`, `ga-pt`).
    pub plan: Option<Plan>,
    /// The spatial guide and its training (`pg`, `ga-pt` with the spatial guide).
    pub spatial: Option<SpatialLearned>,
}

/// A trained spatial guide, the per-pixel sums of its training passes' samples (which the
/// image keeps), and where the plan's guides sample beside it.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct SpatialLearned {
    pub guide: SpatialField,
    pub samples: PixelSums,
    pub plan_guides: PlanGuides,
}

impl Learned {
    /// The per-pixel sums of the samples preparing took, which the image of a render that
    /// trained keeps: the spatial guide's training passes' (`pg`, `ga-pt`), or the GA plan's
    /// baseline's (`ga`, where it keeps them).
    pub fn samples(&self) -> Option<&PixelSums> {
        match &self.spatial {
            Some(spatial) => Some(&spatial.samples),
            None => self.plan.as_ref().and_then(Plan::baseline),
        }
        .filter(|s| s.spp > 0)
    }

    /// Samples per pixel the training took (in the image of a render that trained).
    pub fn training_spp(&self) -> u32 {
        self.samples().map_or(0, |s| s.spp)
    }
}

impl From<&SpatialTraining> for SpatialLearned {
    fn from(training: &SpatialTraining) -> Self {
        Self {
            guide: training.guide.as_ref().clone(),
            samples: training.samples.clone(),
            plan_guides: training.plan_guides,
        }
    }
}

/// Prepares `settings.method` with `learned` instead of training. A render of the whole
/// image (`settings.shard` whole) starts from the training's samples, as the render that
/// trained does; a shard renders only its share of the samples after them (the learn job's
/// training shard holds those). Refuses a state of another method or image size.
pub fn prepare_learned(
    view: &SceneView,
    config: &Settings,
    settings: &RenderSettings,
    learned: Learned,
) -> Result<Box<dyn Integrator>, PrepareError> {
    let mismatch = |what: String| PrepareError::Learned {
        method: settings.method,
        what,
    };
    let camera = &view.scene.camera;
    let pixels = (camera.width * camera.height) as usize;
    let check_sums = |s: &PixelSums, of: &str| {
        if s.sum.len() != pixels || s.sum_sq.len() != pixels || s.spp > settings.spp {
            return Err(mismatch(format!(
                "{of} sums of {} pixels and {} spp for {pixels} pixels at {} spp",
                s.sum.len(),
                s.spp,
                settings.spp
            )));
        }
        Ok(())
    };
    if let Some(plan) = &learned.plan {
        if (plan.width(), plan.height()) != (camera.width, camera.height) {
            return Err(mismatch(format!(
                "a GA plan of {}×{} pixels for an image of {}×{}",
                plan.width(),
                plan.height(),
                camera.width,
                camera.height
            )));
        }
        if let Some(baseline) = plan.baseline() {
            check_sums(baseline, "baseline")?;
        }
    }
    if let Some(spatial) = &learned.spatial {
        check_sums(&spatial.samples, "training")?;
        spatial.guide.check().map_err(mismatch)?;
    }
    let max_bounces = settings.max_bounces;
    let keeps_taken = settings.shard.is_whole();
    let spatial_guide = config.spatial.spatial_guide;
    let integrator: Box<dyn Integrator> = match (settings.method, learned.plan, learned.spatial) {
        (Method::Ga, Some(plan), None) => Box::new(Ga {
            plan,
            max_bounces,
            keeps_taken,
        }),
        (Method::GaPt, Some(plan), None) if !spatial_guide => Box::new(GaPt { plan, max_bounces }),
        (Method::GaPt, Some(plan), Some(s)) if spatial_guide => {
            Box::new(spatial_integrator(Some(plan), s, settings))
        }
        (Method::Pg, None, Some(s)) => Box::new(spatial_integrator(None, s, settings)),
        (_, plan, spatial) => {
            return Err(mismatch(format!(
                "{} GA plan and {} spatial guide",
                if plan.is_some() { "a" } else { "no" },
                if spatial.is_some() { "a" } else { "no" },
            )))
        }
    };
    Ok(integrator)
}

fn spatial_integrator(
    plan: Option<Plan>,
    spatial: SpatialLearned,
    settings: &RenderSettings,
) -> SpatialIntegrator {
    SpatialIntegrator {
        plan,
        training: SpatialTraining {
            guide: Arc::new(spatial.guide),
            samples: spatial.samples,
            plan_guides: spatial.plan_guides,
        },
        max_bounces: settings.max_bounces,
        keeps_taken: settings.shard.is_whole(),
    }
}
