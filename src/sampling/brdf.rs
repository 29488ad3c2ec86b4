//! The BRDF of genpath's materials and its sampler: a two-sided Lambertian lobe plus a
//! normalised modified-Phong lobe (chosen by albedo), or a delta BSDF (an ideal mirror or
//! conductor here; dielectrics, which tell their sides apart, in [`super::specular`]).
//!
//! Directions are unit vectors pointing away from the surface; `n` is the shading normal (the
//! geometric one where a mesh has no vertex normals) turned to the side of `wo`
//! ([`facing_normal`]). Densities are solid-angle densities over
//! the full sphere (zero below the surface for the Lambertian lobe), in `f64`.

use super::specular;
use crate::scene::Material;
use glam::{DVec3, Vec3};
use std::f64::consts::{FRAC_1_PI, PI};

/// The (shading) normal `ns` turned towards `wo`: the side a two-sided surface scatters on.
pub fn facing_normal(ns: Vec3, wo: Vec3) -> Vec3 {
    if ns.dot(wo) >= 0.0 {
        ns
    } else {
        -ns
    }
}

/// Mirror reflection of `wo` about `n`.
pub fn reflect(wo: Vec3, n: Vec3) -> Vec3 {
    2.0 * n.dot(wo) * n - wo
}

fn channel_sum(c: Vec3) -> f64 {
    (c.x + c.y + c.z) as f64
}

/// Probability of sampling the Lambertian lobe rather than the Phong lobe.
fn diffuse_probability(m: &Material) -> f64 {
    let (d, s) = (channel_sum(m.kd), channel_sum(m.ks));
    if d + s > 0.0 {
        d / (d + s)
    } else {
        1.0
    }
}

/// `cos α` between `wi` and the mirror direction of `wo`, in f64. `wi` is renormalised too:
/// an f32 unit vector is off by up to ~1e-7 in length, which `cos^ns` would multiply by `ns`
/// (a 3e-4 relative error of the density at `ns = 1e4`).
fn cos_lobe(n: Vec3, wo: Vec3, wi: Vec3) -> f64 {
    reflect(wo, n)
        .as_dvec3()
        .normalize()
        .dot(wi.as_dvec3().normalize())
}

/// BRDF value `f(wo, wi)` (no cosine); zero for mirrors (a delta) and below the surface.
pub fn eval(m: &Material, n: Vec3, wo: Vec3, wi: Vec3) -> Vec3 {
    if m.mirror || n.dot(wi) <= 0.0 || n.dot(wo) <= 0.0 {
        return Vec3::ZERO;
    }
    let mut f = m.kd * std::f32::consts::FRAC_1_PI;
    if m.is_glossy() {
        let c = cos_lobe(n, wo, wi);
        if c > 0.0 {
            let ns = m.ns as f64;
            f += m.ks * ((ns + 2.0) * 0.5 * FRAC_1_PI * c.powf(ns)) as f32;
        }
    }
    f
}

/// Solid-angle density of [`sample`] for `wi`; zero for mirrors (a delta is no density).
pub fn pdf(m: &Material, n: Vec3, wo: Vec3, wi: Vec3) -> f64 {
    if m.mirror {
        return 0.0;
    }
    let p_diffuse = diffuse_probability(m);
    let cos = n.as_dvec3().normalize().dot(wi.as_dvec3().normalize());
    let mut pdf = if cos > 0.0 {
        p_diffuse * cos * FRAC_1_PI
    } else {
        0.0
    };
    if m.is_glossy() {
        let c = cos_lobe(n, wo, wi);
        if c > 0.0 {
            let ns = m.ns as f64;
            pdf += (1.0 - p_diffuse) * (ns + 1.0) * 0.5 * FRAC_1_PI * c.powf(ns);
        }
    }
    pdf
}

/// A sampled direction.
#[derive(Clone, Copy, Debug)]
pub struct BrdfSample {
    pub wi: Vec3,
    /// Solid-angle density; 1 for a delta (it then cancels in `weight`).
    pub pdf: f64,
    /// `f · |cos| / pdf` (for a mirror: its reflectance).
    pub weight: Vec3,
    pub delta: bool,
}

/// A unit direction around unit `axis` with `cos θ = c` and azimuth `phi`.
fn around(axis: DVec3, c: f64, phi: f64) -> DVec3 {
    let s = (1.0 - c * c).max(0.0).sqrt();
    let (t, b) = crate::sampling::basis(axis);
    (t * (s * phi.cos()) + b * (s * phi.sin()) + axis * c).normalize()
}

/// The direction [`sample`] draws from `u` for a non-mirror material (`None` for one that
/// does not scatter), without its density and weight: for callers that evaluate both for a
/// mixture anyway.
pub fn sample_direction(m: &Material, n: Vec3, wo: Vec3, u: [f64; 3]) -> Option<Vec3> {
    if !m.scatters() {
        return None;
    }
    let phi = 2.0 * PI * u[2];
    let wi = if u[0] < diffuse_probability(m) {
        around(n.as_dvec3(), (1.0 - u[1]).max(0.0).sqrt(), phi)
    } else {
        let c = u[1].powf(1.0 / (m.ns as f64 + 1.0));
        around(reflect(wo, n).as_dvec3().normalize(), c, phi)
    };
    Some(wi.as_vec3())
}

/// Samples `wi` from three uniform numbers; `None` when the sample carries no energy
/// (below the surface, or a black material), and for a dielectric, whose sampling needs the
/// stored (not facing) normal's side: [`specular::sample`] samples every delta BSDF.
pub fn sample(m: &Material, n: Vec3, wo: Vec3, u: [f64; 3]) -> Option<BrdfSample> {
    if m.mirror {
        return match m.dielectric {
            Some(_) => None,
            None => specular::sample(m, n, wo, u[0]),
        };
    }
    let wi = sample_direction(m, n, wo, u)?;
    let pdf = pdf(m, n, wo, wi);
    let cos = n.dot(wi);
    if cos <= 0.0 || pdf <= 0.0 {
        return None;
    }
    let weight = eval(m, n, wo, wi) * (cos as f64 / pdf) as f32;
    Some(BrdfSample {
        wi,
        pdf,
        weight,
        delta: false,
    })
}
