//! The materials' unit tests: the smooth plastic's choice against Mitsuba's expectation;
//! `eval_pdf` against `eval` and `pdf`, bit for bit, for every kind of material; the adjoint
//! ([`TransportMode::Importance`]) — reciprocity where it holds, the shading-normal
//! correction and the `1/η²` of refraction where it does not —, each check paired with a
//! deliberately wrong input it must reject; and χ² (the shared harness,
//! `src/sampling/chi2.rs`) of a smooth plastic's sampling with its choice at the hit, for a
//! path that arrives from either direction, with must-reject twins that take the choice's
//! probability from the wrong direction.

use super::bsdf::{self, Frame};
use super::microfacet::{Distribution, Microfacet, RoughConductor, RoughDielectric, RoughPlastic};
use super::specular;
use super::*;
use glam::DVec3;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use std::f64::consts::FRAC_PI_2;

#[allow(dead_code)]
#[path = "../../sampling/chi2.rs"]
mod chi2;

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

/// A material of `kd`, `glossy` and nothing else (two-sided, no delta part).
fn with_glossy(kd: Vec3, glossy: Glossy) -> Material {
    Material {
        kd,
        glossy,
        ..BLACK.clone()
    }
}

fn rough_dielectric(eta: f32, alpha: f64, visible: bool) -> Material {
    with_glossy(
        Vec3::ZERO,
        Glossy::RoughDielectric(RoughDielectric {
            microfacet: Microfacet::new(Distribution::Ggx, alpha, alpha, visible),
            eta,
            specular_reflectance: Vec3::ONE,
            specular_transmittance: Vec3::new(0.9, 0.8, 0.7),
        }),
    )
}

fn smooth_plastic() -> Material {
    let p = SmoothPlastic::new(1.5, Vec3::new(0.6, 0.4, 0.3), Vec3::ONE, false);
    with_glossy(Vec3::ZERO, Glossy::Plastic(Box::new(p)))
}

/// One material of every kind, by name: Lambertian, Phong (wide and narrow), rough
/// conductors (isotropic and anisotropic, Beckmann with all normals), rough plastic,
/// rough dielectrics (visible normals or not), the smooth plastic's diffuse choice, an
/// ideal mirror and a smooth dielectric.
fn materials() -> Vec<(&'static str, Material)> {
    let kd = Vec3::new(0.5, 0.4, 0.3);
    let ks = Vec3::new(0.3, 0.3, 0.2);
    let conductor = |distribution, au, av, visible| {
        Glossy::RoughConductor(RoughConductor {
            microfacet: Microfacet::new(distribution, au, av, visible),
            eta: Vec3::new(0.2, 0.9, 1.1),
            k: Vec3::new(3.9, 2.4, 2.2),
            specular_reflectance: Vec3::ONE,
        })
    };
    let plastic = RoughPlastic::new(
        Microfacet::new(Distribution::Beckmann, 0.2, 0.2, true),
        1.5,
        kd,
        Vec3::ONE,
        true,
    );
    let mirror = Material {
        ks: Vec3::splat(0.9),
        mirror: true,
        ..with_glossy(Vec3::ZERO, Glossy::None)
    };
    let glass = Material {
        ks: Vec3::ONE,
        mirror: true,
        dielectric: Some(Dielectric {
            eta: 1.5,
            transmittance: Vec3::ONE,
            thin: false,
        }),
        ..with_glossy(Vec3::ZERO, Glossy::None)
    };
    vec![
        ("lambertian", with_glossy(kd, Glossy::None)),
        (
            "phong ns 10",
            with_glossy(kd, Glossy::Phong { ks, ns: 10.0 }),
        ),
        (
            "phong ns 1000",
            with_glossy(kd, Glossy::Phong { ks, ns: 1000.0 }),
        ),
        (
            "rough conductor ggx",
            with_glossy(Vec3::ZERO, conductor(Distribution::Ggx, 0.3, 0.3, true)),
        ),
        (
            "rough conductor anisotropic",
            with_glossy(Vec3::ZERO, conductor(Distribution::Ggx, 0.1, 0.4, true)),
        ),
        (
            "rough conductor beckmann, all normals",
            with_glossy(kd, conductor(Distribution::Beckmann, 0.2, 0.2, false)),
        ),
        (
            "rough plastic",
            with_glossy(Vec3::ZERO, Glossy::RoughPlastic(Box::new(plastic))),
        ),
        ("rough dielectric", rough_dielectric(1.5, 0.3, true)),
        (
            "rough dielectric, all normals",
            rough_dielectric(1.33, 0.2, false),
        ),
        ("smooth plastic", smooth_plastic()),
        ("mirror", mirror),
        ("smooth dielectric", glass),
    ]
}

/// A uniform direction on the sphere.
fn sphere(rng: &mut Pcg64) -> Vec3 {
    let z: f64 = rng.random_range(-1.0..1.0);
    let phi: f64 = rng.random_range(0.0..std::f64::consts::TAU);
    let r = (1.0 - z * z).sqrt();
    DVec3::new(r * phi.cos(), r * phi.sin(), z).as_vec3()
}

/// A uniform direction of `|cos θ| ≥ min` against `n`, on its side `sign`.
fn away_from_grazing(rng: &mut Pcg64, n: Vec3, sign: f32, min: f32) -> Vec3 {
    loop {
        let w = sphere(rng);
        if w.dot(n) * sign >= min {
            return w;
        }
    }
}

fn bits(v: Vec3) -> [u32; 3] {
    v.to_array().map(f32::to_bits)
}

/// `eval_pdf` is `(eval, pdf)` bit for bit, for every kind of material, in frames of random
/// normal and tangent, from the front and from behind, under a normal map's perturbation,
/// and in either transport mode; at random `wi` and at `wi` the BSDF samples (which find a
/// narrow lobe).
#[test]
fn eval_pdf_is_eval_and_pdf_bit_for_bit() {
    let mut rng = Pcg64::seed_from_u64(47);
    let mut nonzero = 0;
    for (name, m) in materials() {
        for i in 0..20_000 {
            let n = sphere(&mut rng);
            let s = n.any_orthonormal_vector();
            let mut frame = match i % 4 {
                0 => Frame::new(n, s),
                1 => Frame::behind(n, s),
                2 => Frame {
                    base: (n + 0.3 * sphere(&mut rng)).normalize(),
                    ..Frame::new(n, Vec3::ZERO)
                },
                _ => {
                    Frame::new(n, s).with_geometric_normal((n + 0.2 * sphere(&mut rng)).normalize())
                }
            };
            if i % 3 == 0 {
                frame = frame.with_mode(TransportMode::Importance);
            }
            let wo = away_from_grazing(&mut rng, n, 1.0, 0.0);
            let u = [rng.random(), rng.random(), rng.random()];
            let wi = match i % 2 {
                0 => bsdf::sample_direction(&m, frame, wo, u).unwrap_or_else(|| sphere(&mut rng)),
                _ => sphere(&mut rng),
            };
            let (f, pdf) = bsdf::eval_pdf(&m, frame, wo, wi);
            let (f_alone, pdf_alone) =
                (bsdf::eval(&m, frame, wo, wi), bsdf::pdf(&m, frame, wo, wi));
            assert_eq!(bits(f), bits(f_alone), "{name}: f at {frame:?} {wo} {wi}");
            assert_eq!(
                pdf.to_bits(),
                pdf_alone.to_bits(),
                "{name}: pdf at {frame:?} {wo} {wi}"
            );
            nonzero += usize::from(f.max_element() > 0.0 && pdf > 0.0);
        }
    }
    // Most pairs are not trivially zero.
    assert!(
        nonzero > 100_000,
        "{nonzero} pairs with a value and a density"
    );
}

/// The worst relative difference of `a` from `b` over the channels where `b` is not zero.
fn relative(a: Vec3, b: Vec3) -> f64 {
    (0..3)
        .filter(|&c| b[c] != 0.0)
        .map(|c| (f64::from(a[c]) - f64::from(b[c])).abs() / f64::from(b[c]).abs())
        .fold(0.0, f64::max)
}

/// Close enough for values computed along different roundings (`f32` results of `f64`
/// work): the right inputs stay far below it, the wrong ones far above.
const CLOSE: f64 = 1e-4;

/// The frame about `+z` (tangent `x`) facing `w`, whose geometric normal is the shading one,
/// in `mode`.
fn frame_facing(w: Vec3, mode: TransportMode) -> Frame {
    let frame = match w.z >= 0.0 {
        true => Frame::new(Vec3::Z, Vec3::X),
        false => Frame::behind(-Vec3::Z, Vec3::X),
    };
    frame.with_geometric_normal(Vec3::Z).with_mode(mode)
}

/// Reciprocity where the shading normal is the geometric one: the adjoint's value
/// `f(wo, wi)` in importance mode is `f(wi, wo)` in radiance mode, for every non-delta
/// lobe (a smooth plastic's the lobe before its choice, `eval_non_delta`; a rough
/// dielectric's reflection and transmission both: its radiance's `1/η²` is what importance
/// leaves out). Must reject: the radiance value standing in for the adjoint (the `1/η²`
/// kept in importance mode), which breaks reciprocity through the rough dielectric.
#[test]
fn the_adjoint_is_the_reverse_radiance_bsdf() {
    use TransportMode::{Importance, Radiance};
    let mut rng = Pcg64::seed_from_u64(48);
    let mut worst_twin = f64::INFINITY;
    for (name, m) in materials().into_iter().filter(|(_, m)| !m.mirror) {
        let mut worst = 0.0f64;
        for i in 0..5_000 {
            let wo = away_from_grazing(&mut rng, Vec3::Z, 1.0, 0.05);
            let sign = if m.transmits() && i % 2 == 1 {
                -1.0
            } else {
                1.0
            };
            let wi = away_from_grazing(&mut rng, Vec3::Z, sign, 0.05);
            let f = |mode, wo, wi| bsdf::eval_non_delta(&m, frame_facing(wo, mode), wo, wi);
            let (adjoint, reverse) = (f(Importance, wo, wi), f(Radiance, wi, wo));
            if reverse.max_element() <= 1e-6 {
                continue;
            }
            worst = worst.max(relative(adjoint, reverse));
            if sign < 0.0 {
                worst_twin = worst_twin.min(relative(f(Radiance, wo, wi), reverse));
            }
        }
        println!("{name}: adjoint against reverse radiance, worst relative difference {worst:.1e}");
        assert!(worst < CLOSE, "{name}: {worst}");
    }
    println!("twin (1/η² kept in importance mode): best relative difference {worst_twin:.2}");
    assert!(worst_twin > 0.1, "the twin was not rejected: {worst_twin}");
}

/// Where the shading normal is not the geometric one, the adjoint's value over the
/// radiance one is the correction `|wo·ns| |wi·ng| / (|wo·ng| |wi·ns|)`, computed here
/// apart; for the BSDF's value and for a mirror's sampled weight. Must reject: the
/// correction left out (a ratio of 1), and the correction with `wo` and `wi` swapped.
#[test]
fn the_adjoint_carries_the_shading_normal_correction() {
    use TransportMode::{Importance, Radiance};
    let mut rng = Pcg64::seed_from_u64(49);
    let ng = Vec3::Z;
    let ns = Vec3::new(0.3, -0.2, 1.0).normalize();
    let factor = |wo: Vec3, wi: Vec3| {
        let d = |a: Vec3, b: Vec3| f64::from(a.dot(b)).abs();
        d(wo, ns) * d(wi, ng) / (d(wo, ng) * d(wi, ns))
    };
    let mut worst = 0.0f64;
    let (mut left_out, mut swapped) = (f64::INFINITY, f64::INFINITY);
    let mut check = |ratio: f64, wo: Vec3, wi: Vec3| {
        let right = factor(wo, wi);
        worst = worst.max((ratio - right).abs() / right);
        left_out = left_out.min((ratio - 1.0).abs());
        swapped = swapped.min((ratio - factor(wi, wo)).abs() / factor(wi, wo));
    };
    let mut samples = 0;
    for (_, m) in materials().into_iter().filter(|(_, m)| !m.mirror) {
        for _ in 0..2_000 {
            let (wo, wi) = (
                away_from_grazing(&mut rng, ns, 1.0, 0.1),
                away_from_grazing(&mut rng, ns, 1.0, 0.1),
            );
            if wo.dot(ng) < 0.1 || wi.dot(ng) < 0.1 || (factor(wo, wi) - 1.0).abs() < 0.05 {
                continue;
            }
            let frame = Frame::new(ns, Vec3::X).with_geometric_normal(ng);
            let f = |mode| bsdf::eval(&m, frame.with_mode(mode), wo, wi);
            let (radiance, adjoint) = (f(Radiance), f(Importance));
            let c = (0..3)
                .max_by(|&a, &b| radiance[a].total_cmp(&radiance[b]))
                .unwrap();
            if radiance[c] > 1e-6 {
                check(f64::from(adjoint[c]) / f64::from(radiance[c]), wo, wi);
                samples += 1;
            }
        }
    }
    // A mirror's sampled weight.
    let (_, mirror) = materials()
        .into_iter()
        .find(|(n, _)| *n == "mirror")
        .unwrap();
    for _ in 0..2_000 {
        let wo = away_from_grazing(&mut rng, ns, 1.0, 0.1);
        let weight = |mode| specular::sample_in(&mirror, ns, wo, 0.5, mode, ng).unwrap();
        let (radiance, adjoint) = (weight(Radiance), weight(Importance));
        if adjoint.wi.dot(ng) < 0.1
            || wo.dot(ng) < 0.1
            || (factor(wo, adjoint.wi) - 1.0).abs() < 0.05
        {
            continue;
        }
        check(
            f64::from(adjoint.weight.x / radiance.weight.x),
            wo,
            adjoint.wi,
        );
        samples += 1;
    }
    println!(
        "{samples} ratios: worst relative difference {worst:.1e}; twins: correction left out \
         {left_out:.3}, wo and wi swapped {swapped:.3} (best)"
    );
    assert!(samples > 5_000 && worst < CLOSE, "{samples} {worst}");
    assert!(
        left_out > 0.01,
        "the correction left out was not rejected: {left_out}"
    );
    assert!(
        swapped > 0.01,
        "the swapped correction was not rejected: {swapped}"
    );
}

/// Through a dielectric interface, radiance's transmission over importance's is `1/η²`
/// (`η` the relative index `wo` meets: from the front `eta`, from behind `1/eta`), for a
/// rough dielectric's value and a smooth one's sampled weight; reflection is the same in
/// both modes. Must reject: `1/η²` applied in both modes (the radiance value standing in
/// for importance's).
#[test]
fn radiance_through_an_interface_is_scaled_by_one_over_eta_squared_and_importance_is_not() {
    use TransportMode::{Importance, Radiance};
    let mut rng = Pcg64::seed_from_u64(50);
    let eta = 1.5f64;
    let rough = rough_dielectric(eta as f32, 0.3, true);
    let (_, glass) = materials()
        .into_iter()
        .find(|(n, _)| *n == "smooth dielectric")
        .unwrap();
    let (mut worst, mut twin, mut transmissions) = (0.0f64, f64::INFINITY, 0);
    let mut check = |radiance: Vec3, importance: Vec3, twin_importance: Vec3, back: bool| {
        let eta_seen = if back { 1.0 / eta } else { eta };
        let right = 1.0 / (eta_seen * eta_seen);
        worst = worst.max((f64::from(radiance.y / importance.y) - right).abs() / right);
        twin = twin.min((f64::from(radiance.y / twin_importance.y) - right).abs() / right);
    };
    for i in 0..10_000 {
        let back = i % 2 == 1;
        let stored = Vec3::Z;
        let side = if back { -1.0 } else { 1.0 };
        let wo = away_from_grazing(&mut rng, stored, side, 0.05);
        let wi = away_from_grazing(&mut rng, stored, -side, 0.05);
        let f = |mode| bsdf::eval(&rough, frame_facing(wo, mode), wo, wi);
        let radiance = f(Radiance);
        if radiance.y > 1e-6 {
            check(radiance, f(Importance), radiance, back);
            transmissions += 1;
        }
        // The smooth dielectric's transmission (`u` above any Fresnel reflectance).
        let weight = |mode| specular::sample_in(&glass, stored, wo, 0.9999, mode, stored).unwrap();
        let (radiance, importance) = (weight(Radiance), weight(Importance));
        if radiance.wi.dot(stored) * side < 0.0 {
            check(radiance.weight, importance.weight, radiance.weight, back);
            transmissions += 1;
        }
        // Reflection: the same in both modes.
        let wr = away_from_grazing(&mut rng, stored, side, 0.05);
        let f = |mode| bsdf::eval(&rough, frame_facing(wo, mode), wo, wr);
        assert_eq!(bits(f(Radiance)), bits(f(Importance)));
    }
    println!(
        "{transmissions} transmissions: worst relative difference {worst:.1e}; twin (1/η² in \
         both modes): best {twin:.3}"
    );
    assert!(
        transmissions > 5_000 && worst < CLOSE,
        "{transmissions} {worst}"
    );
    assert!(twin > 0.1, "1/η² in both modes was not rejected: {twin}");
}

/// A smooth plastic's sampling at a hit, its choice included: the delta reflection, or a
/// direction of the diffuse lobe.
#[derive(Clone, Copy, Debug)]
enum Outcome {
    Delta,
    Direction(DVec3),
}

/// The sphere's bins and one more for the delta choice, whose "integral" is the claimed
/// probability of the choice (`pdf(Delta)`).
struct WithDelta(chi2::SphereBins);

impl chi2::Binning for WithDelta {
    type Point = Outcome;
    fn bins(&self) -> usize {
        self.0.bins() + 1
    }
    fn bin_of(&self, x: &Outcome) -> Option<usize> {
        match x {
            Outcome::Delta => Some(self.0.bins()),
            Outcome::Direction(d) => self.0.bin_of(d),
        }
    }
    fn integrate(&self, bin: usize, pdf: &dyn Fn(&Outcome) -> f64) -> f64 {
        match bin == self.0.bins() {
            true => pdf(&Outcome::Delta),
            false => self.0.integrate(bin, &|d| pdf(&Outcome::Direction(*d))),
        }
    }
}

/// χ² of a smooth plastic's sampling with its choice at the hit, for a path that arrives
/// from `w` (a light-started path arriving from what a camera path would leave along, at
/// grazing incidence and near the normal): the choice is `Material::scattering_at`'s from
/// `|ns · w|`, then the diffuse choice's direction; the claimed probabilities are
/// `bsdf::delta_choice(w)` for the delta and `bsdf::pdf_non_delta` from `w` for the
/// directions. Must reject: the choice's probability taken from the direction the path
/// leaves along, and from a camera's direction at the other incidence instead of `w`.
#[test]
fn chi2_plastic_choice_seen_from_either_direction() {
    use chi2::{chi2, chi2_test, Family, SphereBins};
    let family = Family { tests: 2 };
    let m = smooth_plastic();
    let ns = Vec3::Z;
    for (theta, seed) in [(1.4f64, 51), (0.3, 52)] {
        let w = DVec3::new(theta.sin(), 0.0, theta.cos()).as_vec3();
        let frame = Frame::new(ns, Vec3::X).with_mode(TransportMode::Importance);
        let p_delta = bsdf::delta_choice(&m, ns, w);
        let sample = |u: [f64; 3]| {
            let chosen = m.scattering_at(Vec2::ZERO, ns.dot(w).abs(), u[0] as f32);
            if chosen.mirror {
                return Outcome::Delta;
            }
            let rescaled = ((u[0] - p_delta) / (1.0 - p_delta)).clamp(0.0, 1.0);
            let wi = bsdf::sample_direction(chosen, frame, w, [rescaled, u[1], u[2]]);
            Outcome::Direction(
                wi.expect("the diffuse choice scatters")
                    .as_dvec3()
                    .normalize(),
            )
        };
        // The density that takes the choice's probability from `from(leaving direction)`.
        let m = &m;
        let claimed = |from: fn(Vec3) -> Vec3| {
            move |x: &Outcome| match *x {
                Outcome::Delta => bsdf::delta_choice(m, ns, from(reflect(w, ns))),
                Outcome::Direction(d) => {
                    let d = d.as_vec3();
                    (1.0 - bsdf::delta_choice(m, ns, from(d))) * bsdf::pdf(m, frame, w, d)
                }
            }
        };
        let bins = WithDelta(SphereBins::equal_area(DVec3::Z, 16, 32));
        let right = |x: &Outcome| match *x {
            Outcome::Delta => bsdf::delta_choice(m, ns, w),
            Outcome::Direction(d) => bsdf::pdf_non_delta(m, frame, ns, w, d.as_vec3()),
        };
        let name = format!("plastic's choice seen from θ {theta} (P_s {p_delta:.3})");
        let (hist, c) = chi2_test(&bins, 1_000_000, seed, sample, right);
        family.accept(&name, &hist, &c);
        let leaving = claimed(|d| d);
        family.reject(
            &format!("{name}, the choice from the leaving direction"),
            &chi2(&bins, &hist, leaving),
        );
        // A camera path's direction at the other incidence (normal for a grazing `w`,
        // grazing for a near-normal one).
        let other = DVec3::new(theta.cos(), 0.0, theta.sin()).as_vec3();
        let camera = |x: &Outcome| match *x {
            Outcome::Delta => bsdf::delta_choice(m, ns, other),
            Outcome::Direction(d) => {
                (1.0 - bsdf::delta_choice(m, ns, other)) * bsdf::pdf(m, frame, w, d.as_vec3())
            }
        };
        family.reject(
            &format!(
                "{name}, the choice from a camera's direction at θ {:.2}",
                FRAC_PI_2 - theta
            ),
            &chi2(&bins, &hist, camera),
        );
    }
}
