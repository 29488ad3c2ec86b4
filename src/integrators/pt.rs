//! `pt`: path tracing with next-event estimation at every vertex ([`crate::path::pt`]).

use super::{Context, Integrator, MethodInfo, PixelIntegrator, PrepareError};
use crate::accel::Ray;
use crate::film::{PixelEstimator, Splats};
use crate::path::{pt, RayCounts, SceneView};
use crate::sampling::Rng;
use glam::DVec3;

/// Path tracing to at most `max_bounces` scattering events; its own pixel estimator.
#[derive(Clone, Copy, Debug)]
pub struct PathTracing {
    pub max_bounces: u32,
}

pub const METHOD: MethodInfo = MethodInfo {
    settings: &["lights"],
    ..MethodInfo::plain(prepare)
};

fn prepare(context: &Context) -> Result<Box<dyn Integrator>, PrepareError> {
    Ok(Box::new(PathTracing {
        max_bounces: context.settings.max_bounces,
    }))
}

impl PixelIntegrator for PathTracing {
    type Estimator<'a> = PathTracing;
    fn estimator(&self) -> PathTracing {
        *self
    }
}

impl PixelEstimator for PathTracing {
    fn start(&mut self, _x: u32, _y: u32) {}
    fn sample(
        &mut self,
        view: &SceneView,
        ray: &Ray,
        rng: &mut Rng,
        counts: &mut RayCounts,
        _splats: &mut Splats,
    ) -> DVec3 {
        pt::radiance(view, ray, self.max_bounces, rng, counts).as_dvec3()
    }
}

/// `pt` without the paths that go on through a delta lobe at the camera ray's hit
/// ([`pt::NoDeltaFirst`]): what a light tracer (`lt`) estimates, for `check` and the tests
/// to compare it with.
#[derive(Clone, Copy, Debug)]
pub struct NoDeltaFirst {
    pub max_bounces: u32,
}

impl PixelIntegrator for NoDeltaFirst {
    type Estimator<'a> = NoDeltaFirst;
    fn estimator(&self) -> NoDeltaFirst {
        *self
    }
}

impl PixelEstimator for NoDeltaFirst {
    fn start(&mut self, _x: u32, _y: u32) {}
    fn sample(
        &mut self,
        view: &SceneView,
        ray: &Ray,
        rng: &mut Rng,
        counts: &mut RayCounts,
        _splats: &mut Splats,
    ) -> DVec3 {
        let guide = pt::NoDeltaFirst;
        pt::radiance_guided(
            view,
            ray,
            self.max_bounces,
            rng,
            counts,
            &guide,
            pt::NO_RECORDER,
        )
        .as_dvec3()
    }
}
