//! Mitsuba 3's smooth `plastic` (`src/bsdfs/plastic.cpp`): a smooth dielectric coating
//! (relative index `η` = `int_ior / ext_ior`) over a Lambertian base. Light seen from `wo`
//! reflects off the coating by the dielectric Fresnel reflectance `F(cos θ_o)`, a delta
//! reflection times `specular_reflectance`, or enters it and leaves diffusely:
//! `f_d(wo, wi) = ρ / (1 − F_dr,int) · (1 − F(cos θ_o)) (1 − F(cos θ_i)) / (π η²)`, with
//! `ρ / (1 − ρ F_dr,int)` under `nonlinear` (`F_dr,int` the coating's diffuse reflectance
//! from inside, Mitsuba's fit [`fresnel_diffuse_reflectance`] of `1/η`).
//!
//! # A vertex that chooses its lobe
//!
//! Mitsuba samples the delta reflection with probability
//! `P_s = F w_s / (F w_s + (1 − F)(1 − w_s))` (`w_s` the specular reflectance's mean over
//! both means, [`SmoothPlastic::specular_probability`]) and the diffuse lobe otherwise. In
//! genpath that choice is taken where a ray meets the plastic, with one uniform number per
//! hit (`SurfacePoint::lobe_u`, drawn by `SceneView::trace_through`), and the vertex is
//! then either a delta vertex — a mirror of reflectance `specular_reflectance · F / P_s`
//! ([`SmoothPlastic::specular`]) — or an ordinary non-delta vertex whose BSDF is the
//! diffuse lobe over its probability, `f_d / (1 − P_s)` ([`SmoothPlastic::eval_chosen`]),
//! sampled by its cosine. Every method looks a material up at a vertex through
//! `SceneView::scattering_material`, which makes the choice, so every method sees the same
//! choice at the same vertex, as it sees glass's choice between reflection and refraction:
//! a delta choice has no light sample, no generator step and no guide, and the emission its
//! direction finds counts in full; a diffuse choice takes its light sample, its generator's
//! step or its guide with the diffuse lobe's value and density. The choice's probability is
//! the same for every generator and technique that reaches the vertex (it depends on `wo`
//! alone), so it is left out of every density, as glass's Fresnel choice is, and only its
//! weight (`1 / P_s` or `1 / (1 − P_s)`) enters the path's value.

use super::specular::fresnel_dielectric;
use crate::scene::{Glossy, Material};
use glam::Vec3;
use std::f64::consts::FRAC_1_PI;

/// Mitsuba's `fresnel_diffuse_reflectance(eta)`: the hemispherical, cosine-weighted Fresnel
/// reflectance of an interface of relative index `eta`, by Egan and Hilgeman's fit below 1
/// and d'Eon and Irving's above.
pub fn fresnel_diffuse_reflectance(eta: f64) -> f64 {
    let inv = eta.recip();
    if eta < 1.0 {
        0.0636 * inv + eta * (eta * -1.4399 + 0.7099) + 0.6681
    } else {
        let (i2, i3, i4, i5) = (inv * inv, inv.powi(3), inv.powi(4), inv.powi(5));
        0.919317 - 3.4793 * inv + 6.75335 * i2 - 7.80989 * i3 + 4.98554 * i4 - 1.36881 * i5
    }
}

/// Mitsuba's smooth `plastic` (see the module documentation).
#[derive(Clone, Debug, PartialEq)]
pub struct SmoothPlastic {
    /// `int_ior / ext_ior`, in single precision as Mitsuba computes it.
    pub eta: f32,
    /// The base's reflectance and the coating's specular one (constants; a texture's mean).
    pub diffuse_reflectance: Vec3,
    pub specular_reflectance: Vec3,
    pub nonlinear: bool,
    /// `w_s`: the specular reflectance's mean over both means.
    specular_sampling_weight: f64,
    /// The coating's diffuse reflectance from inside, `F_dr(1/η)`.
    fdr_int: f64,
    /// The delta choice as a material: a one-sided mirror, whose reflectance at a hit is
    /// `specular_reflectance · F / P_s` (set there: `Material::scattering_at`).
    pub specular: Material,
}

impl SmoothPlastic {
    /// The plastic of relative index `eta`, base reflectance `diffuse` and coating
    /// reflectance `specular` (for textures, their means: what Mitsuba's `w_s` is made of).
    pub fn new(eta: f32, diffuse: Vec3, specular: Vec3, nonlinear: bool) -> Self {
        let mean = |c: Vec3| c.as_dvec3().element_sum() / 3.0;
        let s_mean = mean(specular);
        Self {
            eta,
            diffuse_reflectance: diffuse,
            specular_reflectance: specular,
            nonlinear,
            specular_sampling_weight: s_mean / (mean(diffuse) + s_mean),
            fdr_int: fresnel_diffuse_reflectance(1.0 / f64::from(eta)),
            specular: Material {
                name: "smooth plastic's specular reflection".into(),
                kd: Vec3::ZERO,
                ks: specular,
                glossy: Glossy::None,
                mirror: true,
                ke: Vec3::ZERO,
                two_sided: false,
                conductor: None,
                dielectric: None,
                textures: None,
            },
        }
    }

    /// `F_dr,int`, the coating's diffuse reflectance from inside (Mitsuba's fit of `1/η`,
    /// which reaches 1 near `η` = 3.85 and grows beyond: the diffuse lobe would be negative).
    pub fn internal_reflectance(&self) -> f64 {
        self.fdr_int
    }

    /// The coating's Fresnel reflectance at `cos θ` (above the surface).
    pub fn fresnel(&self, cos_theta: f64) -> f64 {
        fresnel_dielectric(cos_theta, f64::from(self.eta)).0
    }

    /// `P_s`, the probability of the delta choice seen from `wo` at `cos θ_o` (Mitsuba's
    /// `prob_specular`); 0 where neither lobe can be chosen.
    pub fn specular_probability(&self, cos_theta_o: f64) -> f64 {
        let f = self.fresnel(cos_theta_o);
        let w = self.specular_sampling_weight;
        let (s, d) = (f * w, (1.0 - f) * (1.0 - w));
        if s + d > 0.0 {
            s / (s + d)
        } else {
            0.0
        }
    }

    /// The delta choice's weight at `cos θ_o` for the coating reflectance `specular`:
    /// `specular · F / P_s` (Mitsuba's sampled value).
    pub fn specular_weight(&self, specular: Vec3, cos_theta_o: f64) -> Vec3 {
        let p = self.specular_probability(cos_theta_o);
        if p > 0.0 {
            specular * (self.fresnel(cos_theta_o) / p) as f32
        } else {
            Vec3::ZERO
        }
    }

    /// The diffuse lobe `f_d(wo, wi)` (no cosine) for the base reflectance `diffuse`, both
    /// directions above the surface at `cos θ_o` and `cos θ_i`: Mitsuba's `eval` over
    /// `cos θ_i`.
    pub fn eval_diffuse(&self, diffuse: Vec3, cos_theta_o: f64, cos_theta_i: f64) -> Vec3 {
        let d = diffuse.as_dvec3();
        let d = match self.nonlinear {
            true => d / (1.0 - d * self.fdr_int),
            false => d / (1.0 - self.fdr_int),
        };
        let eta = f64::from(self.eta);
        let t = (1.0 - self.fresnel(cos_theta_o)) * (1.0 - self.fresnel(cos_theta_i));
        (d * (FRAC_1_PI * t / (eta * eta))).as_vec3()
    }

    /// The BSDF of the diffuse choice: `f_d / (1 − P_s)`, `P_s` seen from `wo`.
    pub fn eval_chosen(&self, diffuse: Vec3, cos_theta_o: f64, cos_theta_i: f64) -> Vec3 {
        let p_diffuse = 1.0 - self.specular_probability(cos_theta_o);
        if p_diffuse <= 0.0 {
            return Vec3::ZERO;
        }
        self.eval_diffuse(diffuse, cos_theta_o, cos_theta_i) / p_diffuse as f32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_diffuse_fresnel_fits_meet_a_quadrature_of_the_fresnel_reflectance() {
        // `∫ 2 F(cos θ) cos θ dcos θ` by the midpoint rule, from outside (η) and inside (1/η).
        let n = 100_000;
        for eta in [1.49, 1.0 / 1.49, 1.33, 1.0 / 1.33, 2.0, 0.5] {
            let exact: f64 = (0..n)
                .map(|i| {
                    let c = (i as f64 + 0.5) / n as f64;
                    2.0 * c * fresnel_dielectric(c, eta).0 / n as f64
                })
                .sum();
            let fit = fresnel_diffuse_reflectance(eta);
            // The fits agree to 0.1 % here (Mitsuba documents 0.6 % at worst below η = 2).
            assert!(
                (fit / exact - 1.0).abs() < 2e-3,
                "η {eta}: fit {fit}, exact {exact}"
            );
        }
    }

    #[test]
    fn the_choice_probabilities_and_weights_make_mitsubas_expectation() {
        let p = SmoothPlastic::new(1.5, Vec3::splat(0.5), Vec3::ONE, false);
        for c in [1.0, 0.6, 0.1] {
            let ps = p.specular_probability(c);
            assert!(ps > 0.0 && ps < 1.0);
            // P_s × the delta's weight is the Fresnel reflectance.
            let w = p.specular_weight(Vec3::ONE, c);
            assert!((ps * f64::from(w.x) - p.fresnel(c)).abs() < 1e-6);
            // (1 − P_s) × the chosen lobe is the lobe.
            let (a, b) = (
                p.eval_chosen(Vec3::ONE, c, 0.7),
                p.eval_diffuse(Vec3::ONE, c, 0.7),
            );
            assert!(((1.0 - ps) * f64::from(a.x) - f64::from(b.x)).abs() < 1e-6);
        }
        // Grazing: the coating reflects more, and is chosen more often.
        assert!(p.specular_probability(0.05) > p.specular_probability(1.0));
    }
}
