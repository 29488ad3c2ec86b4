//! `bsdf-only` (feature `test-method`, for the test suite): path tracing that finds light
//! only by hitting it, every direction drawn from the BSDF, no next-event estimation and
//! no Russian roulette. Unbiased and slow to converge; it exists to show that a method is
//! this one file and one line in the list of [`super::Method`]s, and that every command
//! renders it.

use super::{Context, Integrator, PixelEstimator, PixelIntegrator, PrepareError};
use crate::accel::Ray;
use crate::path::{emitted, RayCounts, SceneView};
use crate::sampling::{brdf, uniform, Rng};
use glam::{DVec3, Vec3};

/// BSDF sampling alone, to at most `max_bounces` scattering events.
#[derive(Clone, Copy, Debug)]
pub struct BsdfOnly {
    max_bounces: u32,
}

pub fn prepare(context: &Context) -> Result<Box<dyn Integrator>, PrepareError> {
    Ok(Box::new(BsdfOnly {
        max_bounces: context.settings.max_bounces,
    }))
}

impl PixelIntegrator for BsdfOnly {
    type Estimator<'a> = BsdfOnly;
    fn estimator(&self) -> BsdfOnly {
        *self
    }
}

impl PixelEstimator for BsdfOnly {
    fn start(&mut self, _x: u32, _y: u32) {}
    fn sample(
        &mut self,
        view: &SceneView,
        ray: &Ray,
        rng: &mut Rng,
        counts: &mut RayCounts,
    ) -> DVec3 {
        let (mut ray, mut beta, mut radiance) = (*ray, Vec3::ONE, Vec3::ZERO);
        for _ in 0..=self.max_bounces {
            let Some(x) = view.trace(&ray, counts) else {
                break;
            };
            let material = view.material(x.prim);
            radiance += beta * emitted(material, &x, -ray.dir);
            let wo = -ray.dir;
            let n = brdf::facing_normal(x.ng, wo);
            let u = [0; 3].map(|_| f64::from(uniform(rng)));
            let Some(s) = brdf::sample(material, n, wo, u).filter(|_| material.scatters()) else {
                break;
            };
            beta *= s.weight;
            ray = view.spawn(&x, s.wi);
        }
        radiance.as_dvec3()
    }
}
