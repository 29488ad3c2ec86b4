//! `lt`: light tracing ([`crate::path::lt`]). Each pixel sample traces one light path,
//! splatted onto the pixels whose camera sees its vertices, beside what the sample's camera
//! ray sees directly. The light paths of pixel sample `(p, s)` are drawn from that sample's
//! random stream, so that they belong to whoever renders the sample: the film's passes
//! make the image independent of the thread count, shards split the light paths as they
//! split the samples, and a render stops and resumes between passes.
//!
//! It pays where the light reaches the visible surfaces through what a camera path cannot
//! connect through: a lamp inside glass, a caustic seen directly on a diffuse surface. It
//! cannot see a mirror or smooth glass directly (no connection to a pinhole passes through a
//! delta lobe), so its image lacks those paths.

use super::{Context, Integrator, MethodInfo, PixelIntegrator, PrepareError};
use crate::accel::Ray;
use crate::film::{PixelEstimator, Splats};
use crate::path::lt::LightTracer;
use crate::path::{RayCounts, SceneView};
use crate::sampling::Rng;
use glam::DVec3;

/// Light tracing, one light path per pixel sample.
#[derive(Clone, Copy, Debug)]
pub struct LightTracing {
    pub tracer: LightTracer,
}

/// Its image leaves out the paths through a delta lobe at the first camera vertex.
pub const METHOD: MethodInfo = MethodInfo {
    sees_through_delta: false,
    ..MethodInfo::plain(prepare)
};

fn prepare(context: &Context) -> Result<Box<dyn Integrator>, PrepareError> {
    Ok(Box::new(LightTracing {
        tracer: LightTracer::new(context.settings.max_bounces),
    }))
}

impl PixelIntegrator for LightTracing {
    type Estimator<'a> = LightTracing;
    fn estimator(&self) -> LightTracing {
        *self
    }
}

impl PixelEstimator for LightTracing {
    const SPLATS: bool = true;
    fn start(&mut self, _x: u32, _y: u32) {}
    fn sample(
        &mut self,
        view: &SceneView,
        ray: &Ray,
        rng: &mut Rng,
        counts: &mut RayCounts,
        splats: &mut Splats,
    ) -> DVec3 {
        let direct = self.tracer.seen_directly(view, ray, rng, counts);
        self.tracer.trace(view, rng, counts, &mut |index, value| {
            splats.add(index, value)
        });
        splats.count_light_paths(1);
        direct.as_dvec3()
    }
}
