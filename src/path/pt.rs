//! `pt`: unidirectional path tracing with next-event estimation at every vertex and BSDF
//! sampling, combined by the power heuristic (Veach & Guibas 1995), Russian roulette from
//! depth 5. The baseline users compare genpath against.
//!
//! With a [`Guide`] (`--method ga-pt`), directions out of non-delta vertices come from the
//! guide's per-vertex mixture of BRDF and anchor samplers instead of the BSDF alone, and the
//! power heuristic weighs light sampling against that mixture's density.

use super::{emitted, RayCounts, SceneView, SurfacePoint};
use crate::accel::Ray;
use crate::guiding::{Guide, PathSegmentStorage};
use crate::sampling::{brdf, uniform, Rng};
use glam::Vec3;

/// First bounce at which Russian roulette may end a path.
pub const RR_START: u32 = 5;

fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 {
        a2 / (a2 + b2)
    } else {
        0.0
    }
}

/// Solid-angle density, as seen from a point at distance² `dist2`, of the emitter sampling
/// strategy choosing the emitter point `y` with normal cosine `cos_light`.
fn light_pdf_solid_angle(pdf_area: f64, dist2: f32, cos_light: f32) -> f32 {
    (pdf_area * dist2 as f64 / cos_light as f64) as f32
}

/// One path-traced estimate of the radiance arriving along `ray`, with at most `max_bounces`
/// scattering events.
pub fn radiance(
    view: &SceneView,
    ray: &Ray,
    max_bounces: u32,
    rng: &mut Rng,
    counts: &mut RayCounts,
) -> Vec3 {
    radiance_guided(view, ray, max_bounces, rng, counts, None, None)
}

/// [`radiance`], with directions drawn from `guide` where it has samplers (see the module
/// documentation); `None` is plain path tracing, with the same random numbers. With a
/// `recorder`, every non-delta vertex records the incident light along the light sample's
/// and the sampled direction, for training a spatial guide.
#[allow(clippy::too_many_arguments)]
pub fn radiance_guided(
    view: &SceneView,
    ray: &Ray,
    max_bounces: u32,
    rng: &mut Rng,
    counts: &mut RayCounts,
    guide: Option<&Guide>,
    mut recorder: Option<&mut PathSegmentStorage>,
) -> Vec3 {
    let scene = view.scene;
    let Some(mut x) = view.trace(ray, counts) else {
        return Vec3::ZERO;
    };
    let mut wo = -ray.dir;
    let mut radiance = emitted(view.material(x.prim), &x, wo);
    let mut beta = Vec3::ONE;
    // Non-delta vertices so far: the guide's level.
    let mut k = 0;
    for bounce in 1..=max_bounces {
        let material = view.material(x.prim);
        if !material.scatters() {
            break;
        }
        let n = brdf::facing_normal(x.ng, wo);
        let last = bounce == max_bounces;
        // At a diffuse vertex the spatial guide's records leave out the direct light, which
        // next-event estimation samples well there (see `guiding::field`).
        let diffuse = !material.mirror && material.ks.max_element() <= 0.0;
        let vertex = guide
            .filter(|g| !material.mirror && g.guides(k))
            .map(|g| g.at(k, x.p, n, last));
        // Next-event estimation runs with this probability: its density is the light
        // sample's times it.
        let light_share = vertex.map_or(1.0, |v| v.light_share());
        let guide = vertex.filter(|v| v.guides());
        if let Some(v) = guide {
            // The light sample's and the guided sample's densities.
            counts.densities += 2 * v.samplers() as u64;
        }

        // Next-event estimation (impossible through a mirror's delta), where it runs.
        if !material.mirror && (light_share >= 1.0 || f64::from(uniform(rng)) < light_share) {
            let mut reached = false;
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
            if cos_x > 0.0 && cos_light > 0.0 && dist2 > 0.0 {
                let le = view.material(y.prim).ke;
                let f = brdf::eval(material, n, wo, wi);
                if le.max_element() > 0.0
                    && f.max_element() > 0.0
                    && view.unoccluded(&x, &y, counts)
                {
                    reached = true;
                    let pdf_light =
                        light_share as f32 * light_pdf_solid_angle(ls.pdf_area, dist2, cos_light);
                    let pdf_brdf = match guide {
                        Some(g) => g.pdf(material, wo, wi),
                        None => brdf::pdf(material, n, wo, wi),
                    } as f32;
                    let weight = power_heuristic(pdf_light, pdf_brdf);
                    radiance += beta * f * le * (cos_x * weight / pdf_light);
                    if let Some(r) = recorder.as_deref_mut().filter(|_| !diffuse) {
                        r.light(x.p, n, wi, le * (cos_x * weight / pdf_light));
                    }
                }
            }
            if let Some(r) = recorder.as_deref_mut() {
                r.light_try(x.p, n, reached);
            }
        }

        // BRDF (or guide) sampling.
        let bs = match guide {
            Some(g) => {
                let u = std::array::from_fn(|_| uniform(rng) as f64);
                g.sample(material, wo, u).map(|s| brdf::BrdfSample {
                    wi: s.wi,
                    pdf: s.pdf,
                    weight: s.weight,
                    delta: false,
                })
            }
            None => {
                let u = [
                    uniform(rng) as f64,
                    uniform(rng) as f64,
                    uniform(rng) as f64,
                ];
                brdf::sample(material, n, wo, u)
            }
        };
        let Some(bs) = bs else {
            break;
        };
        if !material.mirror {
            k += 1;
        }
        beta *= bs.weight;
        let wi = bs.wi;
        if let Some(r) = recorder.as_deref_mut().filter(|_| !bs.delta) {
            let cos_over_pdf = (n.dot(wi).abs() as f64 / bs.pdf) as f32;
            r.sampled(x.p, n, wi, cos_over_pdf, beta, radiance);
        }
        let next_ray = view.spawn(&x, wi);
        let Some(y) = view.trace(&next_ray, counts) else {
            break;
        };
        let y_material = view.material(y.prim);
        if y_material.is_emitter() {
            let cos_light = y.ng.dot(-wi);
            if cos_light > 0.0 {
                let weight = if bs.delta {
                    1.0
                } else {
                    let dist2 = (y.p - x.p).length_squared();
                    let pdf_light = light_share as f32
                        * light_pdf_solid_angle(
                            scene.emitters.total_area.recip(),
                            dist2,
                            cos_light,
                        );
                    power_heuristic(bs.pdf as f32, pdf_light)
                };
                radiance += beta * emitted(y_material, &y, -wi) * weight;
                if let Some(r) = recorder.as_deref_mut().filter(|_| diffuse && !bs.delta) {
                    r.emission_seen(radiance);
                }
            }
        }
        if bounce >= RR_START {
            let q = (1.0 - beta.max_element()).max(0.05);
            if uniform(rng) < q {
                break;
            }
            beta /= 1.0 - q;
        }
        x = y;
        wo = -wi;
    }
    if let Some(r) = recorder {
        r.finish(radiance);
    }
    radiance
}
