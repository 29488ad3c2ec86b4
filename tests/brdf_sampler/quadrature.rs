//! `∫ pdf` by quadrature, without the samplers.

use super::mixture::Mixture;
use super::vertex::*;
use super::*;

/// A spherical cap, given by its unit axis and half-angle.
#[derive(Clone, Copy)]
pub(crate) struct Cap {
    pub(crate) axis: DVec3,
    pub(crate) half_angle: f64,
}

/// The upper hemisphere of the surface with normal `n`, as a cap: its edge is the horizon.
pub(crate) fn hemisphere(n: DVec3) -> Cap {
    Cap {
        axis: n,
        half_angle: FRAC_PI_2,
    }
}

/// `∫ f dω` over the sphere, for an `f` that is smooth except on the edges of `caps` and on
/// the rings `θ ∈ theta_splits` about `axis` (put a sharp lobe on `axis`). Polar coordinates
/// about `axis`: θ is cut into panels at the splits and where a ring touches a cap's edge,
/// each ring's φ into arcs where it crosses a cap's edge, so that every Gauss–Legendre panel
/// sees a smooth integrand; θ panels cluster their nodes at both ends, where an arc's length
/// grows like a square root. Shares nothing with the χ² harness or the samplers.
pub(crate) fn sphere_integral(
    f: impl Fn(DVec3) -> f64,
    axis: DVec3,
    theta_splits: &[f64],
    caps: &[Cap],
) -> f64 {
    const NODES: usize = 48;
    let nodes = gauss_legendre(NODES);
    let (t, b) = frame(axis);
    // Each cap's axis in polar coordinates (θa, φa), with its half-angle.
    let polar: Vec<(f64, f64, f64)> = caps
        .iter()
        .map(|c| {
            let (x, y, z) = (c.axis.dot(t), c.axis.dot(b), c.axis.dot(axis));
            (x.hypot(y).atan2(z), y.atan2(x), c.half_angle)
        })
        .collect();
    let mut edges = vec![0.0, PI];
    edges.extend_from_slice(theta_splits);
    for &(ta, _, tc) in &polar {
        edges.extend([(ta - tc).abs(), ta + tc, 2.0 * PI - ta - tc]);
    }
    edges.retain(|e| (0.0..=PI).contains(e));
    edges.sort_by(f64::total_cmp);
    edges.dedup_by(|a, b| (*a - *b).abs() < 1e-15);
    let gauss = |a: f64, b: f64, g: &dyn Fn(f64) -> f64| -> f64 {
        let half = 0.5 * (b - a);
        nodes
            .iter()
            .map(|&(x, w)| w * half * g(a + half * (1.0 + x)))
            .sum()
    };
    let ring = |theta: f64| -> f64 {
        let (st, ct) = theta.sin_cos();
        let mut cuts = vec![0.0, 2.0 * PI];
        for &(ta, pa, tc) in &polar {
            // The ring meets the cap's edge where d·a = cos θc.
            let arg = (tc.cos() - ct * ta.cos()) / (st * ta.sin());
            if arg.abs() < 1.0 {
                let half = arg.acos();
                cuts.extend([
                    (pa - half).rem_euclid(2.0 * PI),
                    (pa + half).rem_euclid(2.0 * PI),
                ]);
            }
        }
        cuts.sort_by(f64::total_cmp);
        let at = |phi: f64| {
            let (sp, cp) = phi.sin_cos();
            f(t * (st * cp) + b * (st * sp) + axis * ct)
        };
        st * cuts.windows(2).map(|w| gauss(w[0], w[1], &at)).sum::<f64>()
    };
    // θ = a + (b − a)(1 − cos πs)/2 over s ∈ [0, 1] turns √(θ − a) into sin(πs/2).
    let clustered = |a: f64, b: f64| {
        gauss(0.0, 1.0, &|s| {
            let theta = a + 0.5 * (b - a) * (1.0 - (PI * s).cos());
            ring(theta) * 0.5 * (b - a) * PI * (PI * s).sin()
        })
    };
    edges.windows(2).map(|w| clustered(w[0], w[1])).sum()
}

/// θ splits for a lobe `cos^ns` on the axis: at 1, 2, 4, … its width `1/√ns`, and at 90°
/// where it is cut off.
pub(crate) fn lobe_splits(ns: f64) -> Vec<f64> {
    let mut s: Vec<f64> = (0..6)
        .map(|k| (1 << k) as f64 / ns.sqrt())
        .filter(|&t| t < 3.0)
        .collect();
    s.push(FRAC_PI_2);
    s
}

/// For diffuse and diffuse + Phong at normal and grazing incidence, asserts:
/// * the quadrature is exact for the f64 model: `∫ model = 1` to 1e-12;
/// * `∫ bsdf::pdf = 1` over the sphere, to 1e-7 (both lobes are normalised over the sphere);
/// * `∫ bsdf::pdf` over the upper hemisphere `= 1 − P(Phong)·B` to 1e-7, `B` the mass of the
///   normalised lobe `(ns+1)/(2π) cos^ns` below the surface, integrated on its own from the
///   model (so the upper and lower parts add up to 1 from two different integrands);
/// * the same quadrature sees the `(ns+2)/(2π)` normalisation: `∫ = 1 + P(Phong)/(ns+1)`,
///   more than 100 × 1e-7 off even at ns = 1e4.
#[test]
pub(crate) fn brdf_pdf_integrates_to_one() {
    // `bsdf::pdf` takes f32 directions: rounding one by 6e-8 rad moves `cos^ns` by up to
    // ~1e-5 relative at ns = 1e4, noise that leaves ~1e-8 on the integral (the f64 model's
    // integral is exact to 1e-13 with the same nodes).
    const TOL: f64 = 1e-7;
    const EXACT: f64 = 1e-12;
    let diffuse = Vertex::new(material(KD, Vec3::ZERO, 1.0), 0.7);
    let total = sphere_integral(
        |d| diffuse.pdf(d),
        diffuse.nd(),
        &[],
        &[hemisphere(diffuse.nd())],
    );
    println!("diffuse: ∫pdf − 1 = {:.2e}", total - 1.0);
    assert!((total - 1.0).abs() < TOL, "{total}");

    let mut checked_below = false;
    for (kd, ns) in [
        (KD, 10.0),
        (KD, 100.0),
        (KD, 1000.0),
        (KD, 1e4),
        (Vec3::ZERO, 100.0),
    ] {
        for theta_o in [0.0, GRAZING] {
            let v = Vertex::new(material(kd, KS, ns), theta_o);
            let model = Model::of(&v.m);
            let p_phong = 1.0 - model.p_diffuse;
            let (n, axis) = (v.nd(), v.lobe_axis());
            let splits = lobe_splits(ns as f64);
            let caps = [hemisphere(n)];
            let integral = |f: &dyn Fn(DVec3) -> f64| sphere_integral(f, axis, &splits, &caps);
            let exact = integral(&|d| model.pdf(&v, d));
            assert!((exact - 1.0).abs() < EXACT, "{exact}");
            let total = integral(&|d| v.pdf(d));
            let upper = integral(&|d| if n.dot(d) > 0.0 { v.pdf(d) } else { 0.0 });
            let lobe_below = integral(&|d| {
                if n.dot(d) <= 0.0 {
                    model.lobe(&v, d)
                } else {
                    0.0
                }
            });
            println!(
                "kd={kd} ns={ns} θo={theta_o:.3}: ∫pdf − 1 = {:.2e}, lobe mass below B = {lobe_below:.6e}, \
                 ∫upper − (1 − P·B) = {:.2e}",
                total - 1.0,
                upper - (1.0 - p_phong * lobe_below)
            );
            assert!((total - 1.0).abs() < TOL, "{total}");
            assert!(
                (upper - (1.0 - p_phong * lobe_below)).abs() < TOL,
                "{upper} {lobe_below}"
            );
            if theta_o == 0.0 {
                // About the normal the lobe's cut-off is the horizon: nothing below.
                assert!(lobe_below.abs() < EXACT, "{lobe_below}");
            } else if ns <= 100.0 {
                // Where the lobe does reach below, the check above is not vacuous.
                assert!(lobe_below > 1e-3, "{lobe_below}");
                checked_below = true;
            }
            let brdf_norm = Model {
                norm: model.exponent + 2.0,
                ..model
            };
            let wrong = integral(&|d| brdf_norm.pdf(&v, d));
            let expected = 1.0 + p_phong / (ns as f64 + 1.0);
            assert!(
                (wrong - expected).abs() < EXACT && expected - 1.0 > 100.0 * TOL,
                "{wrong}"
            );
        }
    }
    assert!(checked_below);
}

/// `∫ Σ w_k p_k = 1` over the sphere, to 1e-8, with every cone edge and the horizon cut out
/// of the quadrature's panels; the same quadrature sees weights summing to 1.05 and an
/// omitted component.
#[test]
pub(crate) fn mixture_pdf_integrates_to_one() {
    const TOL: f64 = 1e-8;
    let mix = Mixture::new();
    let caps = [
        hemisphere(mix.v.nd()),
        Cap {
            axis: mix.anchors[0].axis(mix.x),
            half_angle: mix.anchors[0].theta_c,
        },
        Cap {
            axis: mix.tiny_axis(),
            half_angle: mix.anchors[1].theta_c,
        },
    ];
    let splits = lobe_splits(phong(&mix.v.m).1 as f64);
    let integral =
        |w: [f64; 3]| sphere_integral(|d| mix.pdf_with(w, d), mix.v.lobe_axis(), &splits, &caps);
    let total = integral(mix.w);
    println!("mixture: ∫pdf − 1 = {:.2e}", total - 1.0);
    assert!((total - 1.0).abs() < TOL, "{total}");
    for (w, expected) in [
        ([0.3, 0.5, 0.25], 1.05),
        ([0.3, 0.5, 0.0], 0.8),
        ([0.0, 0.5, 0.2], 0.7),
    ] {
        let wrong = integral(w);
        assert!((wrong - expected).abs() < TOL, "{w:?}: {wrong}");
    }
}
