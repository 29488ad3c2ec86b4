//! `nee-only` (feature `testing`, for the test suite): path tracing whose light comes
//! from next-event estimation alone at every non-delta vertex, with no multiple importance
//! sampling: emission found by a BSDF-sampled direction counts only when no light sample
//! could have found it (seen from the camera or through a mirror). No Russian roulette.
//! Unbiased, and noisier than `pt` where lights are large and surfaces glossy; it exists to
//! show that a method is this one file and one line in the list of [`super::Method`]s, and
//! that every command renders it.

use super::{Context, Integrator, PixelEstimator, PixelIntegrator, PrepareError};
use crate::accel::Ray;
use crate::path::pt::LightPoint;
use crate::path::{emitted, RayCounts, SceneView, SurfacePoint};
use crate::sampling::brdf::{self, Frame};
use crate::sampling::{specular, uniform, Rng};
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

/// The light a point sampled on the emitters (or, with the scene's environment share, a
/// direction uniform over the sphere towards its environment) sends to `x` (shading frame `frame`) and
/// on towards `wo`, over its density in solid angle.
fn light_sample(
    view: &SceneView,
    (x, frame, wo): (&SurfacePoint, Frame, Vec3),
    material: &Material,
    rng: &mut Rng,
    counts: &mut RayCounts,
) -> Vec3 {
    let env_share = view.scene.environment_share();
    if env_share <= 0.0 {
        return match LightPoint::sample(view, (x, frame.n), rng) {
            Some(l) if view.unoccluded(x, &l.y, counts) => {
                let le = view.material(l.y.prim).ke;
                brdf::eval(material, frame, wo, l.wi) * le * (l.cos_x / l.pdf_solid_angle())
            }
            _ => Vec3::ZERO,
        };
    }
    let mut u = [uniform(rng), uniform(rng), uniform(rng)];
    if let Some(env) = view
        .scene
        .environment
        .filter(|_| f64::from(u[0]) < env_share)
    {
        let wi = env.sample(u[1], u[2]);
        let cos = frame.n.dot(wi);
        if cos <= 0.0 || !view.escapes(x, wi, counts) {
            return Vec3::ZERO;
        }
        let pdf = (env_share * env.pdf()) as f32;
        return brdf::eval(material, frame, wo, wi) * env.radiance * (cos / pdf);
    }
    u[0] = ((f64::from(u[0]) - env_share) / (1.0 - env_share)) as f32;
    match LightPoint::from_uniforms(view, (x, frame.n), u) {
        Some(l) if view.unoccluded(x, &l.y, counts) => {
            let le = view.material(l.y.prim).ke;
            let pdf = (1.0 - env_share) as f32 * l.pdf_solid_angle();
            brdf::eval(material, frame, wo, l.wi) * le * (l.cos_x / pdf)
        }
        _ => Vec3::ZERO,
    }
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
        for bounce in 0..=self.max_bounces {
            let hit = view.trace(&ray, counts);
            if count_emission {
                // The camera ray's as the scene shows it (`hide_emitters`).
                radiance += beta
                    * match &hit {
                        _ if bounce == 0 => view.seen_directly(hit.as_ref(), ray.dir),
                        Some(x) => emitted(view.material(x.prim), x, -ray.dir),
                        None => view.escaped(),
                    };
            }
            let Some(x) = hit else {
                break;
            };
            let wo = -ray.dir;
            let frame = Frame::facing(&x, wo);
            let material = view.scattering_material(&x, wo);
            if !material.scatters() {
                break;
            }
            if !material.mirror {
                radiance += beta * light_sample(view, (&x, frame, wo), material, rng, counts);
            }
            let u = [0; 3].map(|_| f64::from(uniform(rng)));
            let s = if material.mirror {
                specular::sample(material, x.ns, wo, u[0])
            } else {
                brdf::sample(material, frame, wo, u)
            };
            let Some(s) = s else {
                break;
            };
            count_emission = s.delta;
            beta *= s.weight;
            ray = view.spawn(&x, s.wi);
        }
        radiance.as_dvec3()
    }
}
