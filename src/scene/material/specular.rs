//! Delta BSDFs (Mitsuba 3's smooth `conductor`, `dielectric` and `thindielectric`, and the
//! ideal mirror): the dielectric Fresnel equations, refraction, and the one sampler of every
//! delta vertex, [`sample`], in Mitsuba's radiance mode.
//!
//! A dielectric reflects with probability `F` (its Fresnel reflectance; 1 under total
//! internal reflection) and refracts otherwise; the sample's weight is then
//! `specular_reflectance`, or `specular_transmittance · η_ti²` for radiance crossing the
//! interface (`η_ti` the index of refraction on `wo`'s side over that on `wi`'s: Mitsuba's
//! `eta_ti`, whose `si.wi` is genpath's `wo`). A thin dielectric reflects with
//! `R' = 2R / (1 + R)` (its internal reflections, `R + T²R / (1 − R²)`) and otherwise lets
//! the light through unbent, weighted by its transmittance. A path started at a light
//! ([`super::TransportMode::Importance`], [`sample_in`]) carries no `η_ti²`, and its weight
//! takes the shading-normal correction.
//!
//! # Densities
//!
//! The delta's direction has no density, and its discrete choice (reflect or refract, with
//! `F` or `1 − F`) is the material's, the same for every path generator, technique and
//! guide that reaches the vertex: like the delta itself, it is left out of every density
//! (the sampled `pdf` is 1, and `pdf_path` skips delta vertices) and out of the weight, from
//! which `F` cancels. Densities stay consistent between sampling and evaluation, and the
//! ratios that multiple importance sampling and the genetic algorithm's fitness take are
//! those of the full densities.

use super::fresnel::fresnel_dielectric;
use super::{facing_normal, reflect, BrdfSample};
use super::{Dielectric, Material, MaterialAt, TransportMode};
use glam::{DVec3, Vec3};

/// The probability that `d` reflects light arriving at `cos_theta_i` against its shading
/// normal (negative from inside): the Fresnel reflectance, with a thin sheet's internal
/// reflections.
pub fn reflect_probability(d: &Dielectric, cos_theta_i: f64) -> f64 {
    let eta = f64::from(d.eta);
    if d.thin {
        let r = fresnel_dielectric(cos_theta_i.abs(), eta).0;
        2.0 * r / (1.0 + r)
    } else {
        fresnel_dielectric(cos_theta_i, eta).0
    }
}

/// The direction a dielectric `d` sends light into when it does not reflect: refracted
/// through the interface (shading normal `ns`, unit `wo`), or straight through a thin sheet;
/// with the weight's factor `η_ti²` (1 for a thin sheet).
fn transmitted(d: &Dielectric, ns: DVec3, wo: DVec3) -> (DVec3, f64) {
    if d.thin {
        return (-wo, 1.0);
    }
    let cos_i = ns.dot(wo);
    let (_, cos_t, _, eta_ti) = fresnel_dielectric(cos_i, f64::from(d.eta));
    let wi = -eta_ti * wo + (eta_ti * cos_i + cos_t) * ns;
    (wi.normalize(), eta_ti * eta_ti)
}

/// The factor `η_ti²` by which `m`'s weight scales radiance that crossed its interface
/// from `wi` to `wo` (shading normal `ns`): for a refraction through a smooth dielectric or
/// a rough one (whose transmission carries the same `1/η²`,
/// [`super::microfacet::RoughDielectric`]), 1 otherwise. A path tracer's Russian
/// roulette undoes it (as Mitsuba's does with its `eta`), so that a path inside glass is
/// not ended for the compression alone.
pub fn radiance_scale(m: &Material, ns: Vec3, wo: Vec3, wi: Vec3) -> f32 {
    match m.interface_eta() {
        Some(eta) if ns.dot(wo) * ns.dot(wi) < 0.0 => {
            let eta_ti = if ns.dot(wo) >= 0.0 { eta.recip() } else { eta };
            eta_ti * eta_ti
        }
        _ => 1.0,
    }
}

/// Samples the delta BSDF of `m` (a mirror: [`Material::mirror`]) at a vertex of shading
/// normal `ns` (as stored, either orientation for a mirror; a dielectric tells its sides
/// apart by it, as Mitsuba's in its shading frame) seen from unit `wo`. `u` (uniform in [0, 1)) picks a dielectric's
/// reflection (`u < F`) or transmission; a mirror does not use it. The sample's `pdf` is 1
/// (see the module documentation); `None` where it carries nothing.
pub fn sample<'a>(m: impl Into<MaterialAt<'a>>, ns: Vec3, wo: Vec3, u: f64) -> Option<BrdfSample> {
    sample_in(m, ns, wo, u, TransportMode::Radiance, Vec3::ZERO)
}

/// [`sample`] for a path that carries light in `mode`, at a point of geometric normal `ng`
/// (zero: none apart from `ns`): in [`TransportMode::Importance`] the weight is the
/// adjoint's — no `η_ti²` through a refraction, and the shading-normal correction
/// ([`TransportMode::correction`]).
pub fn sample_in<'a>(
    m: impl Into<MaterialAt<'a>>,
    ns: Vec3,
    wo: Vec3,
    u: f64,
    mode: TransportMode,
    ng: Vec3,
) -> Option<BrdfSample> {
    let m = m.into();
    let n = facing_normal(ns, wo);
    let Some(d) = &m.dielectric else {
        return (m.ks().max_element() > 0.0).then(|| {
            let wi = reflect(wo, n).normalize();
            let weight = m.mirror_reflectance(n.dot(wo));
            BrdfSample {
                wi,
                pdf: 1.0,
                weight: adjoint(weight, mode, (n, ng), wo, wi),
                delta: true,
            }
        });
    };
    let (ns64, wo64) = (ns.as_dvec3().normalize(), wo.as_dvec3().normalize());
    let (wi, weight) = if u < reflect_probability(d, ns64.dot(wo64)) {
        (reflect(wo, n).normalize(), m.ks())
    } else {
        let (wi, scale) = transmitted(d, ns64, wo64);
        let weight = match mode {
            TransportMode::Radiance => m.transmittance() * scale as f32,
            TransportMode::Importance => m.transmittance(),
        };
        (wi.as_vec3(), weight)
    };
    (weight.max_element() > 0.0).then_some(BrdfSample {
        wi,
        pdf: 1.0,
        weight: adjoint(weight, mode, (n, ng), wo, wi),
        delta: true,
    })
}

/// `weight` with the shading-normal correction of `mode` at normals `(ns, ng)`; untouched in
/// [`TransportMode::Radiance`].
fn adjoint(weight: Vec3, mode: TransportMode, (ns, ng): (Vec3, Vec3), wo: Vec3, wi: Vec3) -> Vec3 {
    match mode {
        TransportMode::Radiance => weight,
        TransportMode::Importance => weight * mode.correction(ns, ng, wo, wi),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refraction_obeys_snell_and_crosses_the_surface() {
        let d = Dielectric {
            eta: 1.5,
            transmittance: Vec3::ONE,
            thin: false,
        };
        let ng = DVec3::Z;
        for (wo, inside) in [
            (DVec3::new(0.6, 0.0, 0.8), false),
            (DVec3::new(0.3, 0.1, -0.9).normalize(), true),
        ] {
            let (wi, scale) = transmitted(&d, ng, wo);
            assert!((wi.length() - 1.0).abs() < 1e-12);
            assert!(wi.z * wo.z < 0.0, "it leaves on the other side");
            let (sin_o, sin_i) = (wo.truncate().length(), wi.truncate().length());
            let (eta_o, eta_i) = if inside { (1.5, 1.0) } else { (1.0, 1.5) };
            assert!((eta_o * sin_o - eta_i * sin_i).abs() < 1e-12);
            // The tangential parts point opposite ways.
            assert!(wi.truncate().dot(wo.truncate()) < 0.0);
            assert!((scale - (eta_o / eta_i) * (eta_o / eta_i)).abs() < 1e-12);
        }
    }
}
