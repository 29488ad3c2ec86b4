//! `lt`: light tracing (particle tracing). A path starts at a light — an emitter picked by
//! its power, a point and a direction drawn by the light interface
//! ([`crate::scene::Scene::sample_emission`]) — and scatters through the adjoint BSDF
//! ([`TransportMode::Importance`]); every vertex with a non-delta part is connected to the
//! pinhole camera and splatted onto the pixel that sees it, weighed by the camera's
//! importance over its density ([`crate::scene::Camera::connect`], after pbrt-v4's
//! `LightPathIntegrator` and Mitsuba 3's `ptracer`). The light the camera sees directly
//! (an emitter, or the environment where a camera ray escapes) is a separate term, taken
//! along the pixel's own camera ray ([`LightTracer::seen_directly`]): a light path reaches
//! the pinhole with probability zero.
//!
//! What a light tracer cannot reach: a camera path's first vertex on a delta lobe (a mirror
//! or smooth glass seen directly, a smooth plastic's coat), which no connection to a
//! pinhole passes through. Its image is `pt`'s with those paths left out
//! ([`super::pt::NoDeltaFirst`]).

use super::pt::{Bsdf, VertexBsdf};
use super::{EndPoint, RayCounts, SceneView};
use crate::accel::Ray;
use crate::sampling::{uniform, Rng};
use crate::scene::material::bsdf::{self, Frame};
use crate::scene::material::TransportMode;
use crate::scene::{MaterialAt, SurfacePoint, RR_START};
use glam::{DVec3, Vec3};

/// Deliberately wrong light tracing, for the statistical tests' twins (injected only with
/// feature `testing`, [`LightTracer::fault`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fault {
    /// The camera's importance without its `1 / cos⁴ θ`.
    NoCos4,
    /// The light path scatters through the BSDF in radiance mode: no shading-normal
    /// correction, and refraction scaled by `1/η²`.
    NoAdjoint,
    /// The emitter's pick probability taken as the next emitter's (in the power table's
    /// order).
    WrongEmitterPick,
}

/// Light tracing to at most `max_bounces` scattering events.
#[derive(Clone, Copy, Debug)]
pub struct LightTracer {
    pub max_bounces: u32,
    #[cfg(feature = "testing")]
    pub fault: Option<Fault>,
}

impl LightTracer {
    /// Light tracing to at most `max_bounces` scattering events.
    pub fn new(max_bounces: u32) -> Self {
        Self {
            max_bounces,
            #[cfg(feature = "testing")]
            fault: None,
        }
    }

    #[cfg(feature = "testing")]
    fn faulty(&self, fault: Fault) -> bool {
        self.fault == Some(fault)
    }

    #[cfg(not(feature = "testing"))]
    fn faulty(&self, _: Fault) -> bool {
        false
    }

    /// What camera ray `ray` sees directly: the emission of its first hit, or the
    /// environment where it escapes (masks passed at random).
    pub fn seen_directly(
        &self,
        view: &SceneView,
        ray: &Ray,
        rng: &mut Rng,
        counts: &mut RayCounts,
    ) -> Vec3 {
        let x = view.trace_through(ray, rng, counts);
        view.seen_directly(x.as_ref(), ray.dir)
    }

    /// One light path from the next uniform numbers of `rng`: each connection to the camera
    /// calls `splat(pixel index, value)`, `value` the path's contribution to that pixel
    /// (the film divides the splats by the number of light paths). Returns the number of
    /// vertices it scattered at.
    pub fn trace(
        &self,
        view: &SceneView,
        rng: &mut Rng,
        counts: &mut RayCounts,
        splat: &mut impl FnMut(u32, DVec3),
    ) -> u32 {
        let scene = view.scene;
        let u = std::array::from_fn(|_| f64::from(uniform(rng)));
        let Some(emission) = scene.sample_emission(u) else {
            return 0;
        };
        let mut power = emission.weight();
        if self.faulty(Fault::WrongEmitterPick) {
            power *= emission.pick / wrong_pick(view, emission.emitter);
        }
        let offset = emission.normal * view.epsilon;
        let offset = offset * emission.normal.dot(emission.dir).signum();
        let mut ray = Ray::new(emission.origin + offset, emission.dir, 0.0, f32::INFINITY);
        let mode = match self.faulty(Fault::NoAdjoint) {
            true => TransportMode::Radiance,
            false => TransportMode::Importance,
        };
        // The throughput since the light, `power` apart (Russian roulette reads it).
        let mut beta = Vec3::ONE;
        for bounce in 1..=self.max_bounces {
            let Some(x) = view.trace_through(&ray, rng, counts) else {
                return bounce - 1;
            };
            let wo = -ray.dir;
            let material = view.scattering_material(&x, wo);
            if !material.scatters() {
                return bounce - 1;
            }
            let frame = Frame::facing(&x, wo).with_mode(mode);
            if !material.mirror {
                let at = (&x, material, frame, wo);
                if let Some((index, value)) = self.connect(view, at, rng, counts) {
                    splat(index, power * (beta * value).as_dvec3());
                }
            }
            if bounce == self.max_bounces {
                return bounce;
            }
            let bsdf = Bsdf {
                material,
                frame,
                wo,
                ns: x.ns,
            };
            let Some(bs) = bsdf.sample(rng) else {
                return bounce;
            };
            beta *= match x.np != Vec3::ZERO && !bs.delta && mode == TransportMode::Importance {
                true => mapped_adjoint(view, &x, wo, bs.wi) / bs.pdf as f32,
                false => bs.weight,
            };
            if bounce >= RR_START {
                let q = (1.0 - beta.max_element()).max(0.05);
                if uniform(rng) < q {
                    return bounce;
                }
                beta /= 1.0 - q;
            }
            ray = view.spawn(&x, bs.wi);
        }
        self.max_bounces
    }

    /// The connection of vertex `x` (its material, shading frame and the direction `wo`
    /// the light came from) to the camera: the pixel, and `f · |cos| · W_e / pdf` (the
    /// adjoint BSDF towards the camera, the cosine at `x`, the camera's importance over the
    /// pinhole's density in solid angle at `x`); `None` where nothing reaches the camera.
    fn connect(
        &self,
        view: &SceneView,
        (x, material, frame, wo): (&SurfacePoint, MaterialAt, Frame, Vec3),
        rng: &mut Rng,
        counts: &mut RayCounts,
    ) -> Option<(u32, Vec3)> {
        let camera = view.scene.camera.connect(x.p)?;
        let f_cos = match x.np != Vec3::ZERO && frame.mode == TransportMode::Importance {
            true => mapped_adjoint(view, x, wo, camera.wi),
            false => {
                let cos_x = bsdf::cosine(&material, frame, camera.wi)?;
                bsdf::eval(material, frame, wo, camera.wi) * cos_x
            }
        };
        if f_cos.max_element() <= 0.0 {
            return None;
        }
        let end = EndPoint {
            p: camera.end,
            ng: Vec3::ZERO,
        };
        if !view.unoccluded(x, &end, rng, counts) {
            return None;
        }
        let mut importance = camera.importance;
        if self.faulty(Fault::NoCos4) {
            importance *= camera.cos.powi(4);
        }
        Some((camera.index, f_cos * (importance / camera.pdf) as f32))
    }
}

/// The adjoint BSDF times its cosine, `f*(wo, wi) |cos θ_i|`, at a point `x` whose normal
/// or bump map perturbs its shading normal by the direction it is seen from
/// ([`crate::scene::normals::resolve`]). The adjoint of the kernel `pt` uses,
/// `K(wo, wi) = f(wo, wi) |wi · n(wo)|` (`n(wo)`: the perturbed normal seen from `wo`),
/// is `K*(wo, wi) = K(wi, wo) |wi · ng| / |wo · ng|`: the map's frame and its shadowing
/// term as seen from `wi`, where [`TransportMode::Importance`]'s correction, made for one
/// fixed shading normal, would take them from `wo`.
fn mapped_adjoint(view: &SceneView, x: &SurfacePoint, wo: Vec3, wi: Vec3) -> Vec3 {
    let material = view.scattering_material(x, wi);
    let frame = Frame::facing(x, wi);
    let Some(cos_o) = bsdf::cosine(&material, frame, wo) else {
        return Vec3::ZERO;
    };
    let (wi_ng, wo_ng) = (wi.dot(x.ng).abs(), wo.dot(x.ng).abs());
    if wo_ng <= 0.0 {
        return Vec3::ZERO;
    }
    bsdf::eval(material, frame, wi, wo) * (cos_o * wi_ng / wo_ng)
}

/// The pick probability of the emitter after `emitter` in the power table (the twin of
/// [`Fault::WrongEmitterPick`]).
fn wrong_pick(view: &SceneView, emitter: crate::scene::Emitter) -> f64 {
    let scene = view.scene;
    let all = scene.all_emitters();
    let i = scene.emitter_index(emitter).unwrap_or(0);
    let other = all[(i + 1) % all.len()];
    let pdf = scene.pdf_emission(other, Vec3::ZERO, Vec3::Z);
    pdf.map_or(1.0, |p| p.pick)
}
