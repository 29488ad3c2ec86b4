//! `srt` and `mixture`: one mixture of path generators at every pixel, estimated by eq. 8.

use super::{
    Context, Description, Integrator, MethodInfo, PixelIntegrator, PrepareError, Settings,
};
use crate::accel::Ray;
use crate::film::{PixelEstimator, Splats};
use crate::path::mixture::{Mixture, MixtureScratch};
use crate::path::pt::Unguided;
use crate::path::{camera_sample, mixture_file, RayCounts, SceneView};
use crate::sampling::Rng;
use glam::DVec3;

/// The same mixture at every pixel.
pub struct MixtureIntegrator {
    pub mixture: Mixture,
    pub max_bounces: u32,
}

/// `srt`: the paper's stochastic ray tracing, a mixture of its one generator.
/// `srt`: the paper's stochastic ray tracing, one generator.
pub const SRT: MethodInfo = MethodInfo {
    settings: &["srt"],
    ..MethodInfo::plain(prepare_srt)
};
/// `mixture`: a mixture of generators from a file, with `srt`'s next-event estimation.
pub const METHOD: MethodInfo = MethodInfo {
    settings: &["srt", "mixture"],
    ..MethodInfo::plain(prepare)
};

fn prepare_srt(context: &Context) -> Result<Box<dyn Integrator>, PrepareError> {
    let max_bounces = context.settings.max_bounces;
    let srt = &context.config.srt;
    let mixture = mixture_file::srt(context.view.scene, max_bounces, srt.absorption(srt.nee))
        .with_nee(srt.nee);
    Ok(Box::new(MixtureIntegrator {
        mixture,
        max_bounces,
    }))
}

/// `mixture`: the mixture read from `--generators`.
fn prepare(context: &Context) -> Result<Box<dyn Integrator>, PrepareError> {
    let mixture = context
        .config
        .loaded_mixture
        .clone()
        .ok_or(PrepareError::NoMixture)?
        .with_nee(context.config.srt.nee);
    Ok(Box::new(MixtureIntegrator {
        mixture,
        max_bounces: context.settings.max_bounces,
    }))
}

/// A mixture's estimator, with the buffers it reuses.
pub struct MixtureEstimator<'a> {
    mixture: &'a Mixture,
    max_bounces: u32,
    scratch: MixtureScratch,
}

impl PixelIntegrator for MixtureIntegrator {
    type Estimator<'a> = MixtureEstimator<'a>;
    fn estimator(&self) -> MixtureEstimator<'_> {
        MixtureEstimator {
            mixture: &self.mixture,
            max_bounces: self.max_bounces,
            scratch: MixtureScratch::default(),
        }
    }
    fn describe(&self, _config: &Settings) -> Description {
        let mut description = Description::default();
        (description.stats).insert("mixture".into(), serde_json::json!(self.mixture));
        description
    }
}

impl PixelEstimator for MixtureEstimator<'_> {
    fn start(&mut self, _x: u32, _y: u32) {}
    fn sample(
        &mut self,
        view: &SceneView,
        ray: &Ray,
        rng: &mut Rng,
        counts: &mut RayCounts,
        _splats: &mut Splats,
    ) -> DVec3 {
        let mixture = (Some(self.mixture), None::<&Unguided>);
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
