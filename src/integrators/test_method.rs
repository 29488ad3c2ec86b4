//! `nee-only` (feature `testing`, for the test suite): path tracing whose light comes
//! from next-event estimation alone at every non-delta vertex, with no multiple importance
//! sampling: emission found by a BSDF-sampled direction counts only when no light sample
//! could have found it (seen from the camera or through a mirror). No Russian roulette.
//! Unbiased, and noisier than `pt` where lights are large and surfaces glossy; it exists to
//! show that a method is this one file and one line in the list of [`super::Method`]s, and
//! that every command renders it.

use super::{Context, Integrator, MethodInfo, PixelIntegrator, PrepareError};
use crate::accel::Ray;
use crate::film::{PixelEstimator, Splats};
use crate::path::pt::LightCandidate;
use crate::path::{emitted, RayCounts, SceneView};
use crate::sampling::{uniform, Rng};
use crate::scene::material::bsdf::{self, Frame};
use crate::scene::material::specular;
use crate::scene::MaterialAt;
use crate::scene::SurfacePoint;
use glam::{DVec3, Vec3};

/// Next-event estimation alone, to at most `max_bounces` scattering events.
#[derive(Clone, Copy, Debug)]
pub struct NeeOnly {
    max_bounces: u32,
}

pub const METHOD: MethodInfo = MethodInfo::plain(prepare);

fn prepare(context: &Context) -> Result<Box<dyn Integrator>, PrepareError> {
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

/// The light a light sample (`pt`'s: a point on the area emitters, a direction towards the
/// environment, or a delta light) sends to `x` (shading frame `frame`) and on towards `wo`, over its
/// density.
fn light_sample(
    view: &SceneView,
    (x, frame, wo): (&SurfacePoint, Frame, Vec3),
    material: MaterialAt,
    rng: &mut Rng,
    counts: &mut RayCounts,
) -> Vec3 {
    let u = [uniform(rng), uniform(rng), uniform(rng)];
    match LightCandidate::sample(view, (x, &material, frame), u) {
        Some(l) if l.visible(view, x, rng, counts) => {
            bsdf::eval(material, frame, wo, l.wi) * l.le * (l.cos_x / l.pdf(1.0))
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
        _splats: &mut Splats,
    ) -> DVec3 {
        let (mut ray, mut beta, mut radiance) = (*ray, Vec3::ONE, Vec3::ZERO);
        // Whether emission at the next hit counts: no light sample could have found it.
        let mut count_emission = true;
        for bounce in 0..=self.max_bounces {
            let hit = view.trace_through(&ray, rng, counts);
            if count_emission {
                // The camera ray's as the scene shows it (`hide_emitters`).
                radiance += beta
                    * match &hit {
                        _ if bounce == 0 => view.seen_directly(hit.as_ref(), ray.dir),
                        Some(x) => emitted(view.material(x.prim), x, -ray.dir),
                        None => view.escaped(ray.dir),
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
                bsdf::sample(material, frame, wo, u)
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
