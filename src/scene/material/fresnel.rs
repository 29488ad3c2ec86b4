//! The Fresnel equations of the interfaces genpath's materials model: a conductor's, of a
//! complex index of refraction, a dielectric's, and Mitsuba's fit of a dielectric's diffuse
//! reflectance: what a smooth conductor's mirror, the microfacet lobes, the smooth plastic
//! and the delta sampler ([`super::specular`]) share.

use glam::Vec3;

/// The unpolarised Fresnel reflectance of a conductor of complex index `eta + i k` per
/// channel (Mitsuba's `fresnel_conductor`, after Moeller, "Optics").
pub fn fresnel_conductor(cos_theta: f32, eta: Vec3, k: Vec3) -> Vec3 {
    let c2 = cos_theta * cos_theta;
    let s2 = 1.0 - c2;
    let s4 = s2 * s2;
    let t1 = eta * eta - k * k - Vec3::splat(s2);
    let a2b2 = (t1 * t1 + 4.0 * k * k * eta * eta)
        .max(Vec3::ZERO)
        .powf(0.5);
    let a = (0.5 * (a2b2 + t1)).max(Vec3::ZERO).powf(0.5);
    let term1 = a2b2 + Vec3::splat(c2);
    let term2 = 2.0 * cos_theta * a;
    let r_s = (term1 - term2) / (term1 + term2);
    let term3 = a2b2 * c2 + Vec3::splat(s4);
    let term4 = term2 * s2;
    let r_p = r_s * (term3 - term4) / (term3 + term4);
    0.5 * (r_s + r_p)
}

/// The dielectric Fresnel reflectance for `cos_theta_i` (against the normal on the
/// exterior's side; negative from inside) at an interface of relative index `eta`
/// (interior / exterior): `(r, cos_theta_t, eta_it, eta_ti)`, Mitsuba's `fresnel`. `r` is 1
/// under total internal reflection; `cos_theta_t` has the sign opposite to `cos_theta_i`;
/// `eta_it` is the transmitted side's index over the incident side's, `eta_ti` its inverse.
pub fn fresnel_dielectric(cos_theta_i: f64, eta: f64) -> (f64, f64, f64, f64) {
    let outside = cos_theta_i >= 0.0;
    let (eta_it, eta_ti) = if outside {
        (eta, eta.recip())
    } else {
        (eta.recip(), eta)
    };
    let cos_t_sqr = 1.0 - (1.0 - cos_theta_i * cos_theta_i) * eta_ti * eta_ti;
    let cos_i = cos_theta_i.abs();
    let cos_t = cos_t_sqr.max(0.0).sqrt();
    let r = if eta == 1.0 {
        0.0
    } else if cos_i == 0.0 {
        1.0
    } else {
        let a_s = (cos_i - eta_it * cos_t) / (cos_i + eta_it * cos_t);
        let a_p = (cos_t - eta_it * cos_i) / (cos_t + eta_it * cos_i);
        0.5 * (a_s * a_s + a_p * a_p)
    };
    let cos_theta_t = if outside { -cos_t } else { cos_t };
    (r, cos_theta_t, eta_it, eta_ti)
}

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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fresnel_at_normal_incidence_and_beyond_the_critical_angle() {
        let (r, cos_t, eta_it, eta_ti) = fresnel_dielectric(1.0, 1.5);
        assert!((r - 0.04).abs() < 1e-12, "{r}");
        assert!((cos_t + 1.0).abs() < 1e-12 && eta_it == 1.5 && eta_ti == 1.0 / 1.5);
        // From inside, beyond asin(1 / 1.5) ≈ 41.8°: total internal reflection.
        let c = 45f64.to_radians().cos();
        assert_eq!(fresnel_dielectric(-c, 1.5).0, 1.0);
        assert!(fresnel_dielectric(c, 1.5).0 < 0.1);
        assert_eq!(fresnel_dielectric(0.3, 1.0).0, 0.0);
    }

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
}
