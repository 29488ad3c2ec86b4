//! `splat-mirror` (feature `testing`, for the test suite): `pt`'s samples of each pixel,
//! splatted onto the pixel mirrored left to right instead of kept, one light path each.
//! Its image is `pt`'s mirrored: bit for bit where the image's pixel count is a power of
//! two, since each splat is scaled by that count and the splat layer divided by the light
//! paths, that count times the samples per pixel. It shows that the film sums, normalises,
//! shards, stops and resumes a method that splats, as light tracing will.

use super::pt::PathTracing;
use super::{Context, Integrator, MethodInfo, PixelIntegrator, PrepareError};
use crate::accel::Ray;
use crate::film::{PixelEstimator, Splats};
use crate::path::{RayCounts, SceneView};
use crate::sampling::Rng;
use glam::DVec3;

/// `pt`'s samples of an image `width` pixels wide and `pixels` pixels in all, splatted
/// onto the mirrored pixel.
#[derive(Clone, Copy, Debug)]
pub struct SplatMirror {
    pt: PathTracing,
    width: u32,
    pixels: u32,
    /// The pixel this one's samples splat onto.
    target: u32,
}

/// Its image is the scene's mirrored, so `check` does not compare it with `pt`'s.
pub const METHOD: MethodInfo = MethodInfo {
    renders_the_scene: false,
    ..MethodInfo::plain(prepare)
};

fn prepare(context: &Context) -> Result<Box<dyn Integrator>, PrepareError> {
    let camera = &context.view.scene.camera;
    Ok(Box::new(SplatMirror {
        pt: PathTracing {
            max_bounces: context.settings.max_bounces,
        },
        width: camera.width,
        pixels: camera.width * camera.height,
        target: 0,
    }))
}

impl PixelIntegrator for SplatMirror {
    type Estimator<'a> = SplatMirror;
    fn estimator(&self) -> SplatMirror {
        *self
    }
}

impl PixelEstimator for SplatMirror {
    const SPLATS: bool = true;
    fn start(&mut self, x: u32, y: u32) {
        self.target = y * self.width + (self.width - 1 - x);
    }
    fn sample(
        &mut self,
        view: &SceneView,
        ray: &Ray,
        rng: &mut Rng,
        counts: &mut RayCounts,
        splats: &mut Splats,
    ) -> DVec3 {
        let value = self.pt.sample(view, ray, rng, counts, splats);
        splats.add(self.target, value * f64::from(self.pixels));
        splats.count_light_paths(1);
        DVec3::ZERO
    }
}
