//! The delta BSDFs of glass (`genpath::scene::material::specular`): the frequency with which a
//! smooth and a thin dielectric reflect is the Fresnel reflectance of an independent
//! implementation (Snell's law and the Fresnel amplitudes by angles), by a binomial z-test
//! at several angles from both sides, paired with an index of refraction 3 % off that the
//! same counts must reject; the directions (the law of reflection, Snell's law, the other
//! side); and energy: with reflectance = transmittance = 1 every sample scatters, with the
//! weight 1 for reflection and `η_ti²` for refraction (radiance's compression), so that the
//! weights with that compression undone sum to the number of samples, which a
//! transmittance of 0.97 must fail. And the smooth plastic's choice of its delta reflection
//! where a ray meets it, by the same binomial test (an index 3 % off rejected), with its
//! weights. Run with `cargo test --profile release-tests --test dielectric`.

use genpath::scene::material::specular;
use genpath::scene::{Dielectric, Material};
use glam::{DVec3, Vec3};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use statrs::distribution::{ContinuousCDF, Normal};

const SAMPLES: u64 = 400_000;
const NG: Vec3 = Vec3::Z;

fn glass(eta: f32, thin: bool, reflectance: f32, transmittance: f32) -> Material {
    Material {
        name: "glass".into(),
        kd: Vec3::ZERO,
        ks: Vec3::splat(reflectance),
        glossy: genpath::scene::Glossy::None,
        mirror: true,
        ke: Vec3::ZERO,
        two_sided: true,
        conductor: None,
        dielectric: Some(Dielectric {
            eta,
            transmittance: Vec3::splat(transmittance),
            thin,
        }),
        textures: None,
    }
}

/// The Fresnel reflectance of unpolarised light at `theta_i` (radians from the normal) from
/// a medium of index `n_i` into one of `n_t`: `(sin²(i−t)/sin²(i+t) + tan²(i−t)/tan²(i+t))/2`,
/// 1 beyond the critical angle.
fn fresnel_by_angles(theta_i: f64, n_i: f64, n_t: f64) -> f64 {
    let sin_t = n_i / n_t * theta_i.sin();
    if sin_t >= 1.0 {
        return 1.0;
    }
    let theta_t = sin_t.asin();
    let (d, s) = (theta_i - theta_t, theta_i + theta_t);
    0.5 * ((d.sin() / s.sin()).powi(2) + (d.tan() / s.tan()).powi(2))
}

/// What the glass of index `eta` reflects of light at `theta_i` seen from the outside (the
/// normal's side) or inside: a smooth interface's Fresnel reflectance, or a thin sheet's
/// `R + T²R / (1 − R²)` (its two faces and the reflections between them).
fn expected_reflectance(eta: f64, thin: bool, theta_i: f64, outside: bool) -> f64 {
    if thin {
        let r = fresnel_by_angles(theta_i, 1.0, eta);
        let t = 1.0 - r;
        return r + t * t * r / (1.0 - r * r);
    }
    match outside {
        true => fresnel_by_angles(theta_i, 1.0, eta),
        false => fresnel_by_angles(theta_i, eta, 1.0),
    }
}

/// `wo` at `theta_i` from the normal, outside (`+z`) or inside.
fn wo_at(theta_i: f64, outside: bool) -> Vec3 {
    let (s, c) = theta_i.sin_cos();
    let z = if outside { c } else { -c };
    DVec3::new(s * 0.8, s * 0.6, z).normalize().as_vec3()
}

/// The reflections among [`SAMPLES`] draws of `m`'s delta BSDF at `wo`, checking each
/// direction on the way.
fn count_reflections(m: &Material, wo: Vec3, seed: u64) -> u64 {
    let mut rng = Pcg64::seed_from_u64(seed);
    let d = m.dielectric.unwrap();
    let mut reflected = 0;
    for _ in 0..SAMPLES {
        let s = specular::sample(m, NG, wo, rng.random::<f64>()).expect("glass of 1, 1 scatters");
        assert!(s.delta && s.pdf == 1.0);
        let (wi, wo) = (s.wi.as_dvec3(), wo.as_dvec3());
        assert!((wi.length() - 1.0).abs() < 1e-6);
        if wi.z * wo.z > 0.0 {
            reflected += 1;
            let mirror = DVec3::new(-wo.x, -wo.y, wo.z);
            assert!(
                (wi - mirror).length() < 1e-6,
                "{wi} is not the mirror of {wo}"
            );
        } else if d.thin {
            assert!(
                (wi + wo).length() < 1e-6,
                "{wi} is not straight through from {wo}"
            );
        } else {
            // Snell: the tangential parts, scaled by the indices, cancel.
            let (n_o, n_i) = if wo.z > 0.0 {
                (1.0, f64::from(d.eta))
            } else {
                (f64::from(d.eta), 1.0)
            };
            let t = n_o * wo.truncate() + n_i * wi.truncate();
            assert!(t.length() < 1e-5, "{wi} breaks Snell's law from {wo}");
        }
    }
    reflected
}

/// The binomial z of `k` reflections in [`SAMPLES`] against probability `p` (counts of 0 or
/// all where `p` is 0 or 1 give z = 0, any other count infinity).
fn z(k: u64, p: f64) -> f64 {
    let n = SAMPLES as f64;
    let var = n * p * (1.0 - p);
    let diff = k as f64 - n * p;
    if var > 0.0 {
        diff.abs() / var.sqrt()
    } else if diff.abs() < 0.5 {
        0.0
    } else {
        f64::INFINITY
    }
}

#[test]
fn glass_reflects_with_the_fresnel_probability_and_a_3_percent_index_error_is_seen() {
    let cases: Vec<(bool, f64, bool)> = [false, true]
        .into_iter()
        .flat_map(|thin| {
            [
                (5.0, true),
                (40.0, true),
                (75.0, true),
                (20.0, false),
                (40.0, false),
            ]
            .map(|(deg, outside)| (thin, deg, outside))
        })
        .collect();
    // Two-sided 99.9 % over the accepted tests, Šidák-corrected.
    let alpha = 1.0 - 0.999f64.powf(1.0 / cases.len() as f64);
    let critical = Normal::new(0.0, 1.0)
        .unwrap()
        .inverse_cdf(1.0 - alpha / 2.0);
    let eta = 1.5;
    let mut wrong_max = 0.0f64;
    for (i, &(thin, deg, outside)) in cases.iter().enumerate() {
        let theta = f64::to_radians(deg);
        let m = glass(eta as f32, thin, 1.0, 1.0);
        let k = count_reflections(&m, wo_at(theta, outside), 7 + i as u64);
        let right = z(k, expected_reflectance(eta, thin, theta, outside));
        let wrong = z(k, expected_reflectance(1.03 * eta, thin, theta, outside));
        eprintln!(
            "thin {thin}, {deg}° {}: {k} reflections, z {right:.2} (index 3 % off: {wrong:.2})",
            if outside { "outside" } else { "inside" }
        );
        assert!(
            right < critical,
            "thin {thin} at {deg}° (outside {outside}): z {right:.2} ≥ {critical:.2}"
        );
        wrong_max = wrong_max.max(wrong);
    }
    assert!(
        wrong_max > critical,
        "an index 3 % off passes (max z {wrong_max:.2} < {critical:.2}): the test cannot see it"
    );
}

/// Beyond the critical angle from inside, everything reflects.
#[test]
fn total_internal_reflection_reflects_everything() {
    let m = glass(1.5, false, 1.0, 1.0);
    let theta = f64::to_radians(50.0); // the critical angle is 41.8°
    assert_eq!(count_reflections(&m, wo_at(theta, false), 1), SAMPLES);
    assert_eq!(expected_reflectance(1.5, false, theta, false), 1.0);
}

/// The weights of [`SAMPLES`] draws at each of many directions (both sides) with radiance's
/// compression `η_ti²` undone, over the number of draws: 1 where nothing is lost.
fn scattered_fraction(m: &Material) -> f64 {
    let mut rng = Pcg64::seed_from_u64(11);
    let d = m.dielectric.unwrap();
    let (mut sum, mut n) = (0.0, 0u64);
    for _ in 0..SAMPLES {
        let z: f64 = rng.random_range(-1.0..1.0);
        let phi = rng.random_range(0.0..std::f64::consts::TAU);
        let r = (1.0 - z * z).sqrt();
        let wo = DVec3::new(r * phi.cos(), r * phi.sin(), z).as_vec3();
        n += 1;
        let Some(s) = specular::sample(m, NG, wo, rng.random()) else {
            continue;
        };
        let crossed = s.wi.z * wo.z < 0.0;
        let compression = if crossed && !d.thin {
            // η on wo's side over η on wi's.
            let eta = f64::from(d.eta);
            if wo.z > 0.0 {
                1.0 / (eta * eta)
            } else {
                eta * eta
            }
        } else {
            1.0
        };
        let w = f64::from(s.weight.x);
        assert!(w.is_finite() && w >= 0.0);
        assert!(
            (w - compression * f64::from(if crossed { d.transmittance.x } else { m.ks.x })).abs()
                < 1e-5 * compression.max(1.0),
            "weight {w} for compression {compression}"
        );
        sum += w / compression;
    }
    sum / n as f64
}

#[test]
fn lossless_glass_scatters_everything_and_a_lossy_one_does_not() {
    for thin in [false, true] {
        let all = scattered_fraction(&glass(1.5, thin, 1.0, 1.0));
        assert!((all - 1.0).abs() < 1e-6, "thin {thin}: {all}");
        let lossy = scattered_fraction(&glass(1.5, thin, 1.0, 0.97));
        assert!(
            lossy < 1.0 - 1e-3,
            "thin {thin}: transmittance 0.97 keeps {lossy}"
        );
    }
    // Index-matched glass lets everything through unbent.
    let matched = glass(1.0, false, 1.0, 1.0);
    let wo = wo_at(0.7, true);
    let s = specular::sample(&matched, NG, wo, 0.0).unwrap();
    assert!((s.wi + wo).length() < 1e-6 && s.weight == Vec3::ONE);
}

/// A smooth plastic plane (`plastic`, `ext_ior` 1, coloured base) at `z = 0` facing `+z`,
/// of interior index `eta`, under a light, as a Mitsuba XML scene in `dir`.
fn plastic_plane(dir: &std::path::Path, eta: f64) -> genpath::scene::Scene {
    let text = format!(
        r#"<scene version="3.0.0">
<sensor type="perspective"><film type="hdrfilm"><rfilter type="box"/></film></sensor>
<shape type="rectangle"><transform name="to_world"><translate z="5"/></transform>
<emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>
<shape type="rectangle"><transform name="to_world"><scale value="100"/></transform>
<bsdf type="plastic"><float name="int_ior" value="{eta}"/><float name="ext_ior" value="1"/>
<rgb name="diffuse_reflectance" value="0.6, 0.3, 0.2"/></bsdf></shape>
</scene>
"#
    );
    let path = dir.join(format!("plastic-{eta}.xml"));
    std::fs::write(&path, text).unwrap();
    genpath::scene::Scene::load(&path).unwrap()
}

/// Mitsuba's probability of a smooth plastic's delta reflection seen at `theta_o` (base
/// reflectance of mean `d_mean`, specular reflectance 1), from [`fresnel_by_angles`].
fn plastic_specular_probability(eta: f64, theta_o: f64, d_mean: f64) -> f64 {
    let f = fresnel_by_angles(theta_o, 1.0, eta);
    let w = 1.0 / (1.0 + d_mean);
    f * w / (f * w + (1.0 - f) * (1.0 - w))
}

/// A smooth plastic chooses its lobe where a ray meets it (`SceneView::trace_through`, then
/// `scattering_material`): the delta reflection with Mitsuba's probability (the Fresnel
/// reflectance weighed by the reflectances' means) by a binomial z-test at several angles,
/// which an index 3 % off must fail; the delta's weight `F / P_s` and the diffuse choice's
/// value `f_d / (1 − P_s)` from independent formulas.
#[test]
fn plastic_chooses_its_delta_reflection_with_mitsubas_probability_and_a_3_percent_index_error_is_seen(
) {
    use genpath::accel::{self, AccelKind};
    use genpath::path::{RayCounts, SceneView};
    use genpath::scene::material::bsdf::{self, Frame};
    let dir = tempfile::tempdir().unwrap();
    let eta = 1.5;
    let scene = plastic_plane(dir.path(), eta);
    let accel = accel::build(AccelKind::default_available(), &scene.mesh).unwrap();
    let view = SceneView::new(&scene, accel.as_ref());
    let degrees = [5.0, 30.0, 55.0, 75.0, 85.0];
    let alpha = 1.0 - 0.999f64.powf(1.0 / degrees.len() as f64);
    let critical = Normal::new(0.0, 1.0)
        .unwrap()
        .inverse_cdf(1.0 - alpha / 2.0);
    let d_mean = (0.6 + 0.3 + 0.2) / 3.0;
    let mut wrong_max = 0.0f64;
    let mut counts = RayCounts::default();
    for (i, deg) in degrees.into_iter().enumerate() {
        let theta = f64::to_radians(deg);
        let wo = wo_at(theta, true);
        let ray = genpath::accel::Ray::new(wo * 2.0, -wo, 0.0, f32::INFINITY);
        let mut rng = genpath::sampling::sample_rng(17, i as u64, 0);
        let p = plastic_specular_probability(eta, theta, d_mean);
        let mut chosen = 0;
        for _ in 0..SAMPLES {
            let x = view.trace_through(&ray, &mut rng, &mut counts).unwrap();
            let m = view.scattering_material(&x, wo);
            if m.mirror {
                chosen += 1;
                let s = specular::sample(m, x.ns, wo, 0.0).unwrap();
                let f = fresnel_by_angles(theta, 1.0, eta);
                assert!(
                    (f64::from(s.weight.y) / (f / p) - 1.0).abs() < 1e-4,
                    "{s:?}"
                );
            } else {
                // The diffuse choice at one `wi`, 40° off the normal.
                let wi = wo_at(f64::to_radians(40.0), true) * Vec3::new(-1.0, 1.0, 1.0);
                let value = bsdf::eval(m, Frame::facing(&x, wo), wo, wi).x;
                let fdr = genpath::scene::material::fresnel::fresnel_diffuse_reflectance(1.0 / eta);
                let t = |th: f64| 1.0 - fresnel_by_angles(th, 1.0, eta);
                let expected = 0.6 / (1.0 - fdr) * t(theta) * t(f64::to_radians(40.0))
                    / (std::f64::consts::PI * eta * eta)
                    / (1.0 - p);
                assert!(
                    (f64::from(value) / expected - 1.0).abs() < 1e-4,
                    "{value} {expected}"
                );
            }
        }
        let right = z(chosen, p);
        let wrong = z(
            chosen,
            plastic_specular_probability(1.03 * eta, theta, d_mean),
        );
        eprintln!("plastic at {deg}°: {chosen} delta choices (p {p:.4}), z {right:.2} (index 3 % off: {wrong:.2})");
        assert!(right < critical, "{deg}°: z {right:.2} ≥ {critical:.2}");
        wrong_max = wrong_max.max(wrong);
    }
    assert!(
        wrong_max > critical,
        "an index 3 % off passes (max z {wrong_max:.2} < {critical:.2}): the test cannot see it"
    );
}
