//! `nee-only` (feature `testing`, for the test suite): path tracing whose light comes
//! from next-event estimation alone at every non-delta vertex, with no multiple importance
//! sampling: emission found by a BSDF-sampled direction counts only when no light sample
//! could have found it (seen from the camera or through a mirror). No Russian roulette.
//! Unbiased, and noisier than `pt` where lights are large and surfaces glossy; it exists to
//! show that a method is this one file and one line in the list of [`super::Method`]s, and
//! that every command renders it.

use super::{Context, Integrator, PixelEstimator, PixelIntegrator, PrepareError};
use crate::accel::Ray;
use crate::path::{emitted, RayCounts, SceneView, SurfacePoint};
use crate::sampling::{brdf, uniform, Rng};
use crate::scene::Material;
use glam::{DVec3, Vec3};

/// Next-event estimation alone, to at most `max_bounces` scattering events.
#[derive(Clone, Copy, Debug)]
pub struct NeeOnly {
    max_bounces: u32,
}

pub fn prepare(context: &Context) -> Result<Box<dyn Integrator>, PrepareError> {
    Ok(Box::new(NeeOnly {
        max_bounces: context.settings.max_bounces,
    }))
}

impl PixelIntegrator for NeeOnly {
    type Estimator<'a> = NeeOnly;
    fn estimator(&self) -> NeeOnly {
        *self
    }
}

/// The light a point sampled on the emitters sends to `x` (normal `n`) and on towards `wo`,
/// over its density in solid angle.
fn light_sample(
    view: &SceneView,
    (x, n, wo): (&SurfacePoint, Vec3, Vec3),
    material: &Material,
    rng: &mut Rng,
    counts: &mut RayCounts,
) -> Vec3 {
    let scene = view.scene;
    let u = [uniform(rng), uniform(rng), uniform(rng)];
    let ls = scene.emitters.sample(&scene.mesh, u);
    let y = SurfacePoint {
        p: ls.point,
        ng: scene.mesh.normals[ls.prim as usize],
        prim: ls.prim,
    };
    let d = y.p - x.p;
    let dist2 = d.length_squared();
    let wi = d / dist2.sqrt();
    let (cos_x, cos_light) = (n.dot(wi), -y.ng.dot(wi));
    if !(cos_x > 0.0 && cos_light > 0.0 && dist2 > 0.0 && view.unoccluded(x, &y, counts)) {
        return Vec3::ZERO;
    }
    let pdf_solid_angle = (ls.pdf_area * dist2 as f64 / cos_light as f64) as f32;
    brdf::eval(material, n, wo, wi) * view.material(y.prim).ke * (cos_x / pdf_solid_angle)
}

impl PixelEstimator for NeeOnly {
    fn start(&mut self, _x: u32, _y: u32) {}
    fn sample(
        &mut self,
        view: &SceneView,
        ray: &Ray,
        rng: &mut Rng,
        counts: &mut RayCounts,
    ) -> DVec3 {
        let (mut ray, mut beta, mut radiance) = (*ray, Vec3::ONE, Vec3::ZERO);
        // Whether emission at the next hit counts: no light sample could have found it.
        let mut count_emission = true;
        for _ in 0..=self.max_bounces {
            let Some(x) = view.trace(&ray, counts) else {
                break;
            };
            let material = view.material(x.prim);
            let wo = -ray.dir;
            if count_emission {
                radiance += beta * emitted(material, &x, wo);
            }
            let n = brdf::facing_normal(x.ng, wo);
            let material = view.scattering_material(&x, wo);
            if !material.scatters() {
                break;
            }
            if !material.mirror {
                radiance += beta * light_sample(view, (&x, n, wo), material, rng, counts);
            }
            let u = [0; 3].map(|_| f64::from(uniform(rng)));
            let Some(s) = brdf::sample(material, n, wo, u) else {
                break;
            };
            count_emission = s.delta;
            beta *= s.weight;
            ray = view.spawn(&x, s.wi);
        }
        radiance.as_dvec3()
    }
}
