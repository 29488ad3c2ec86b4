//! Statistical tests of the anchor-point, patch and light-point samplers (design §10): χ² of sample
//! histograms against the samplers' own densities, each paired with deliberately wrong
//! densities that the same histogram must reject; and `∫ pdf = 1` by quadrature that does not
//! use the samplers, at the parameters' bounds. Run with `cargo test --profile release-tests --test samplers`
//! (`-- --nocapture` prints every statistic).

#[path = "../src/sampling/chi2.rs"]
mod chi2;

use chi2::{chi2, chi2_test, Binning, Chi2, Family, Histogram, SphereBins, TriangleBins};
use genpath::accel::TriangleMesh;
use genpath::math::gauss_legendre;
use genpath::sampling::anchor::{cone_solid_angle, AnchorSampler};
use genpath::sampling::light_point::{solid_angle_pdf, LightPointSampler, LightRegion};
use genpath::sampling::patch::PatchSampler;
use genpath::scene::Emitters;
use glam::{DVec3, Vec3};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use std::f64::consts::{FRAC_PI_2, PI};

/// The χ² tests in this file that must accept.
const FAMILY: Family = Family { tests: 27 };
const SAMPLES: u64 = 4_000_000;

// ---------------------------------------------------------------- anchor-point sampler

const FROM: DVec3 = DVec3::new(0.3, -0.2, 0.1);
const ANCHOR: DVec3 = DVec3::new(-1.0, 2.0, 0.5);

/// Bins about the smaller of the cone and its complement, with an edge on the cone's edge so
/// that even a cap of 1e-7 rad spans 8 × 16 bins.
fn cone_bins(axis: DVec3, theta_c: f64) -> SphereBins {
    let (s, c) = (0.5 * theta_c).sin_cos();
    if theta_c <= FRAC_PI_2 {
        SphereBins::split_at(axis, 2.0 * s * s, 8, 8, 16)
    } else {
        SphereBins::split_at(-axis, 2.0 * c * c, 8, 8, 16)
    }
}

fn anchor_chi2(s: &AnchorSampler, from: DVec3, bins: &SphereBins, seed: u64) -> (Histogram, Chi2) {
    chi2_test(
        bins,
        SAMPLES,
        seed,
        |u| s.sample(from, u),
        |d| s.pdf(from, *d),
    )
}

/// Accepts the sampler's pdf and rejects the pdf with 1 % more mass on the heavier of the
/// cone and its complement (`α·1.01` inside, or `(1−α)·1.01` outside). Returns what further
/// wrong densities need.
fn check_anchor(theta_c: f64, alpha: f64, seed: u64) -> (AnchorSampler, SphereBins, Histogram) {
    let s = AnchorSampler::new(ANCHOR, theta_c, alpha).unwrap();
    let bins = cone_bins((ANCHOR - FROM).normalize(), theta_c);
    let (hist, c) = anchor_chi2(&s, FROM, &bins, seed);
    let name = format!("anchor θc={theta_c:e} α={alpha}");
    FAMILY.accept(&name, &hist, &c);
    let (p1, p2) = s.densities();
    let (w1, w2) = if alpha >= 0.5 {
        (1.01, 1.0)
    } else {
        (1.0, 1.01)
    };
    let heavier = |d: &DVec3| {
        if s.inside(FROM, *d) {
            w1 * p1
        } else {
            w2 * p2
        }
    };
    FAMILY.reject(
        &format!("{name} with 1 % more mass on the heavier side"),
        &chi2(&bins, &hist, heavier),
    );
    (s, bins, hist)
}

/// The cone's solid angle as `2π(1 − cos θc)` in `f32`, the formula `Ωc` must not use.
fn naive_f32_densities(s: &AnchorSampler) -> (f64, f64) {
    let omega = 2.0 * std::f32::consts::PI * (1.0 - (s.theta_c as f32).cos());
    let rest = 4.0 * std::f32::consts::PI - omega;
    (
        (s.alpha as f32 / omega) as f64,
        ((1.0 - s.alpha) as f32 / rest) as f64,
    )
}

fn naive_f32_pdf(s: &AnchorSampler) -> impl Fn(&DVec3) -> f64 + '_ {
    let (p1, p2) = naive_f32_densities(s);
    move |d| if s.inside(FROM, *d) { p1 } else { p2 }
}

#[test]
fn anchor_cone_1e_4_stable_solid_angle() {
    for (alpha, seed) in [(0.01, 1), (0.5, 2), (0.99, 3)] {
        let (s, bins, hist) = check_anchor(1e-4, alpha, seed);
        if alpha == 0.5 {
            // In f32, cos(1e-4) rounds to 1: the cone gets zero solid angle, infinite density.
            assert!(naive_f32_densities(&s).0.is_infinite());
            FAMILY.reject(
                "anchor θc=1e-4 with Ωc = 2π(1−cos θc) in f32",
                &chi2(&bins, &hist, naive_f32_pdf(&s)),
            );
        }
    }
}

#[test]
fn anchor_cone_1e_3_rejects_finite_f32_solid_angle() {
    let (s, bins, hist) = check_anchor(1e-3, 0.5, 4);
    let (p1, _) = naive_f32_densities(&s);
    let (good, _) = s.densities();
    println!("f32 p1 / f64 p1 at θc = 1e-3: {}", p1 / good);
    FAMILY.reject(
        "anchor θc=1e-3 with Ωc = 2π(1−cos θc) in f32",
        &chi2(&bins, &hist, naive_f32_pdf(&s)),
    );
}

#[test]
fn anchor_cone_0_3_including_p1_below_p2() {
    for (alpha, seed) in [(0.01, 5), (0.5, 6), (0.99, 7)] {
        let (s, _, _) = check_anchor(0.3, alpha, seed);
        let (p1, p2) = s.densities();
        assert_eq!(p1 < p2, alpha == 0.01, "{p1} {p2}");
    }
}

#[test]
fn anchor_cone_1_0_rejects_outside_density_ignoring_the_cone() {
    for (alpha, seed) in [(0.01, 8), (0.5, 9), (0.99, 10)] {
        let (s, bins, hist) = check_anchor(1.0, alpha, seed);
        if alpha == 0.5 {
            let (p1, _) = s.densities();
            let whole_sphere = (1.0 - alpha) / (4.0 * PI);
            let wrong = |d: &DVec3| if s.inside(FROM, *d) { p1 } else { whole_sphere };
            FAMILY.reject("anchor θc=1 with p2 = (1−α)/4π", &chi2(&bins, &hist, wrong));
        }
    }
}

#[test]
fn anchor_cone_2_5() {
    for (alpha, seed) in [(0.01, 11), (0.5, 12), (0.99, 13)] {
        let (s, _, _) = check_anchor(2.5, alpha, seed);
        let (p1, p2) = s.densities();
        // A wide cone with half the mass is sparser than its small complement.
        assert_eq!(p1 < p2, alpha <= 0.5, "{p1} {p2}");
    }
}

#[test]
fn anchor_extreme_cones() {
    check_anchor(1e-7, 0.5, 14);
    let (s, bins, hist) = check_anchor(PI - 1e-4, 0.5, 15);
    // 4π − Ωc in f32 has no significant digit left for a cone this wide.
    FAMILY.reject(
        "anchor θc=π−1e-4 with 4π − 2π(1−cos θc) in f32",
        &chi2(&bins, &hist, naive_f32_pdf(&s)),
    );
}

/// Bins about an axis unrelated to the cone: the cone's edge crosses bins, which the adaptive
/// quadrature must resolve.
#[test]
fn anchor_off_axis_binning() {
    let bins = SphereBins::equal_area(DVec3::new(0.2, -0.9, 0.4), 16, 32);
    for (theta_c, alpha, seed) in [(1.0, 0.5, 16), (2.5, 0.99, 17)] {
        let s = AnchorSampler::new(ANCHOR, theta_c, alpha).unwrap();
        let (hist, c) = anchor_chi2(&s, FROM, &bins, seed);
        let name = format!("anchor θc={theta_c} α={alpha}, off-axis bins");
        // Quadrature error only matters against the bins' noise, 1/√(expected) ≈ 1e-2.
        assert!((c.pdf_total - 1.0).abs() < 1e-4, "{name}: quadrature {c}");
        FAMILY.accept(&name, &hist, &c);
        let (p1, p2) = s.densities();
        let wrong = |d: &DVec3| if s.inside(FROM, *d) { 1.01 * p1 } else { p2 };
        FAMILY.reject(&format!("{name} with α·1.01"), &chi2(&bins, &hist, wrong));
    }
}

/// From the anchor itself the axis is +z (documented); a pdf that picked another axis there
/// must be rejected.
#[test]
fn anchor_from_the_anchor_point() {
    let s = AnchorSampler::new(ANCHOR, 0.3, 0.9).unwrap();
    let bins = cone_bins(DVec3::Z, 0.3);
    let (hist, c) = anchor_chi2(&s, ANCHOR, &bins, 18);
    FAMILY.accept("anchor from the anchor point", &hist, &c);
    let (p1, p2) = s.densities();
    let minus_z = |d: &DVec3| {
        if d.angle_between(-DVec3::Z) < 0.3 {
            p1
        } else {
            p2
        }
    };
    FAMILY.reject(
        "anchor from the anchor point, cone about −z",
        &chi2(&bins, &hist, minus_z),
    );
}

// ---------------------------------------------------------------- light-point sampler

/// Emitter A (prim 0), a non-emitter (prim 1), emitter B (prim 2) of a fifth of A's area; no
/// two coplanar or axis-aligned.
fn light_scene() -> (TriangleMesh, Emitters) {
    let positions = vec![
        Vec3::new(-0.5, 2.0, -0.3),
        Vec3::new(0.7, 2.1, -0.2),
        Vec3::new(0.1, 1.9, 0.8),
        Vec3::new(-1.0, 0.0, -1.0),
        Vec3::new(1.0, 0.0, -1.0),
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(1.5, 1.0, 0.0),
        Vec3::new(1.9, 1.2, 0.1),
        Vec3::new(1.6, 1.4, 0.5),
    ];
    let mesh = TriangleMesh::new(positions, vec![[0, 1, 2], [3, 4, 5], [6, 7, 8]]);
    let emitters = Emitters::new(&mesh, |prim| prim != 1);
    (mesh, emitters)
}

fn emitter_bins(mesh: &TriangleMesh, emitters: &Emitters, n: usize) -> TriangleBins {
    let tris = emitters
        .prims
        .iter()
        .map(|&p| (p, mesh.vertices(p).map(|v| v.as_dvec3())))
        .collect();
    TriangleBins::new(tris, n)
}

fn light_pdf<'a>(
    s: &'a LightPointSampler,
    mesh: &'a TriangleMesh,
    emitters: &'a Emitters,
) -> impl Fn(&(u32, DVec3)) -> f64 + Copy + 'a {
    move |&(prim, p)| s.pdf_area(mesh, emitters, p, prim)
}

/// Accepts the sampler's pdf; rejects the region's (or, for β = 0, all emitters') area off by
/// 1 %, and for β > 0 the region one level finer.
fn check_light(region: LightRegion, beta: f64, seed: u64) {
    let (mesh, emitters) = light_scene();
    let s = LightPointSampler::new(region, beta, &emitters).unwrap();
    // 8 divisions per edge: cells of level 3, finer than every region tested.
    let bins = emitter_bins(&mesh, &emitters, 8);
    let (hist, c) = chi2_test(
        &bins,
        SAMPLES,
        seed,
        |u| {
            let (p, prim) = s.sample(&mesh, &emitters, u);
            (prim, p)
        },
        light_pdf(&s, &mesh, &emitters),
    );
    let name = format!("light k={} β={beta}", region.level);
    FAMILY.accept(&name, &hist, &c);

    let (a_region, a_total) = (region.area(&mesh), emitters.total_area);
    let off_area = |&(prim, p): &(u32, DVec3)| {
        let inside = region.contains(&mesh, prim, p);
        if beta > 0.0 {
            (1.0 - beta) / a_total
                + if inside {
                    beta / (1.01 * a_region)
                } else {
                    0.0
                }
        } else {
            1.0 / (1.01 * a_total)
        }
    };
    FAMILY.reject(
        &format!("{name} with an area off by 1 %"),
        &chi2(&bins, &hist, off_area),
    );
    if beta > 0.0 {
        let finer = LightRegion {
            level: region.level + 1,
            cell: region.cell * 4 + 1,
            ..region
        };
        let wrong = LightPointSampler::new(finer, beta, &emitters).unwrap();
        FAMILY.reject(
            &format!("{name} with the region one level finer"),
            &chi2(&bins, &hist, light_pdf(&wrong, &mesh, &emitters)),
        );
    }
}

#[test]
fn light_whole_triangle_region() {
    let region = LightRegion {
        prim: 0,
        level: 0,
        cell: 0,
    };
    for (beta, seed) in [(0.0, 21), (0.5, 22), (0.99, 23)] {
        check_light(region, beta, seed);
    }
}

#[test]
fn light_level_2_cell() {
    // Cell 9 = digits (2, 1): corner 1 of the corner-2 child of the small emitter.
    let region = LightRegion {
        prim: 2,
        level: 2,
        cell: 9,
    };
    for (beta, seed) in [(0.0, 24), (0.5, 25), (0.99, 26)] {
        check_light(region, beta, seed);
    }
}

// ---------------------------------------------------------------- ∫ pdf = 1

/// `∫ pdf dω` over the sphere in polar coordinates about `axis`, split at the polar angle
/// `theta_split`: Gauss–Legendre in θ on `[0, θs]` and in `ε = π − θ` on `[0, π − θs]` (so
/// both caps keep their precision), trapezoid (spectrally accurate) in φ.
fn sphere_integral(pdf: impl Fn(DVec3) -> f64, axis: DVec3, theta_split: f64) -> f64 {
    let helper = if axis.x.abs() < 0.9 {
        DVec3::X
    } else {
        DVec3::Y
    };
    let t = helper.cross(axis).normalize();
    let b = axis.cross(t);
    let nodes = gauss_legendre(24);
    let n_phi = 12;
    // Integrates over the polar angle from `pole` on [0, width].
    let cap = |pole: DVec3, width: f64| -> f64 {
        let mut sum = 0.0;
        for &(x, w) in &nodes {
            let theta = 0.5 * width * (1.0 + x);
            let (st, ct) = theta.sin_cos();
            for j in 0..n_phi {
                let (sp, cp) = (2.0 * PI * (j as f64 + 0.5) / n_phi as f64).sin_cos();
                let d = t * (st * cp) + b * (st * sp) + pole * ct;
                sum += pdf(d) * st * w * 0.5 * width * (2.0 * PI / n_phi as f64);
            }
        }
        sum
    };
    // `PI` is π rounded down by 1.22e-16, which is 1e-10 of a cap of 1e-6 rad: add it back.
    const PI_LOW: f64 = 1.2246467991473532e-16;
    cap(axis, theta_split) + cap(-axis, (PI - theta_split) + PI_LOW)
}

#[test]
fn anchor_pdf_integrates_to_one() {
    let axis = (ANCHOR - FROM).normalize();
    for theta_c in [1e-6, 0.3, PI - 1e-6] {
        for alpha in [1e-9, 0.5, 1.0 - 1e-9] {
            let s = AnchorSampler::new(ANCHOR, theta_c, alpha).unwrap();
            let total = sphere_integral(|d| s.pdf(FROM, d), axis, theta_c);
            println!(
                "anchor θc={theta_c:e} α={alpha:e}: ∫pdf − 1 = {:.2e}",
                total - 1.0
            );
            assert!(
                (total - 1.0).abs() < 1e-12,
                "θc={theta_c} α={alpha}: {total}"
            );
            // The same quadrature sees an outside density that ignores the cone.
            let (p1, _) = s.densities();
            let wrong = |d| {
                if s.inside(FROM, d) {
                    p1
                } else {
                    (1.0 - alpha) / (4.0 * PI)
                }
            };
            let wrong_total = sphere_integral(wrong, axis, theta_c);
            let deficit = (1.0 - alpha) * cone_solid_angle(theta_c) / (4.0 * PI);
            assert!(
                (1.0 - wrong_total - deficit).abs() < 1e-9,
                "{wrong_total} {deficit}"
            );
        }
    }
}

#[test]
fn anchor_samples_have_finite_positive_pdf_at_the_bounds() {
    let mut rng = Pcg64::seed_from_u64(31);
    for theta_c in [1e-7, 1e-6, 0.3, PI - 1e-6, PI - 1e-7] {
        for alpha in [1e-9, 0.5, 1.0 - 1e-9] {
            let s = AnchorSampler::new(ANCHOR, theta_c, alpha).unwrap();
            for from in [FROM, ANCHOR] {
                for _ in 0..100_000 {
                    let d = s.sample(from, [rng.random(), rng.random(), rng.random()]);
                    let p = s.pdf(from, d);
                    assert!((d.length() - 1.0).abs() < 1e-14, "{d}");
                    assert!(p.is_finite() && p > 0.0, "θc={theta_c} α={alpha} {d}: {p}");
                }
            }
        }
    }
}

#[test]
fn light_pdf_integrates_to_one() {
    let (mesh, emitters) = light_scene();
    // 64 divisions per edge: cells of level 6, finer than every region below.
    let bins = emitter_bins(&mesh, &emitters, 64);
    let total = |pdf: &dyn Fn(&(u32, DVec3)) -> f64| -> f64 {
        (0..bins.bins()).map(|bin| bins.integrate(bin, pdf)).sum()
    };
    for (prim, level, cell) in [(0, 0, 0), (2, 2, 9), (0, 5, 777)] {
        let region = LightRegion { prim, level, cell };
        for beta in [0.0, 0.5, 1.0 - 1e-9] {
            let s = LightPointSampler::new(region, beta, &emitters).unwrap();
            let pdf = light_pdf(&s, &mesh, &emitters);
            let integral = total(&pdf);
            println!(
                "light k={level} β={beta:e}: ∫pdf − 1 = {:.2e}",
                integral - 1.0
            );
            assert!(
                (integral - 1.0).abs() < 1e-12,
                "k={level} β={beta}: {integral}"
            );
            // Off the emitters the density is 0.
            let centroid = mesh.vertices(1).iter().map(|v| v.as_dvec3()).sum::<DVec3>() / 3.0;
            assert_eq!(s.pdf_area(&mesh, &emitters, centroid, 1), 0.0);
            // The same quadrature sees a region area off by 1 %.
            let a = region.area(&mesh);
            let wrong = |&(q, p): &(u32, DVec3)| {
                pdf(&(q, p))
                    + if region.contains(&mesh, q, p) {
                        beta / (1.01 * a) - beta / a
                    } else {
                        0.0
                    }
            };
            let expected = 1.0 - beta * (1.0 - 1.0 / 1.01);
            assert!((total(&wrong) - expected).abs() < 1e-9);
        }
    }
}

#[test]
fn light_samples_have_finite_positive_pdf_and_land_in_place() {
    let (mesh, emitters) = light_scene();
    let mut rng = Pcg64::seed_from_u64(32);
    let n = mesh.normals[0].as_dvec3();
    let below = DVec3::new(0.1, 0.5, 0.1);
    for (prim, level, cell) in [(0, 0, 0), (2, 2, 9), (0, 7, 12345)] {
        let region = LightRegion { prim, level, cell };
        for beta in [0.0, 0.5, 1.0 - 1e-9] {
            let s = LightPointSampler::new(region, beta, &emitters).unwrap();
            for _ in 0..100_000 {
                let u = [rng.random(), rng.random(), rng.random()];
                let (p, q) = s.sample(&mesh, &emitters, u);
                let pdf = s.pdf_area(&mesh, &emitters, p, q);
                assert!(pdf.is_finite() && pdf > 0.0, "{p} on {q}: {pdf}");
                // Points drawn from the region are found in it again.
                if u[0] < beta {
                    assert!(region.contains(&mesh, q, p), "{p} not in {region:?}");
                    assert_eq!(LightRegion::containing(&mesh, prim, level, p), region);
                }
                if q == 0 {
                    // Emitter A faces down towards `below`.
                    assert!(solid_angle_pdf(pdf, below, p, n) > 0.0);
                }
            }
        }
    }
}

#[test]
fn light_sampler_rejects_invalid_parameters() {
    let (_, emitters) = light_scene();
    let region = |prim, level, cell| LightRegion { prim, level, cell };
    assert!(LightPointSampler::new(region(0, 2, 15), 0.5, &emitters).is_ok());
    assert!(LightPointSampler::new(region(1, 0, 0), 0.5, &emitters).is_err());
    assert!(LightPointSampler::new(region(0, 2, 16), 0.5, &emitters).is_err());
    assert!(LightPointSampler::new(region(0, 17, 0), 0.5, &emitters).is_err());
    assert!(LightPointSampler::new(region(0, 0, 0), 1.0, &emitters).is_err());
    assert!(LightPointSampler::new(region(0, 0, 0), -0.1, &emitters).is_err());
}

// ---------------------------------------------------------------------- patch sampler

/// Accepts a patch sampler's pdf; rejects the pdf with 1 % more mass on the patch and the
/// one that converts area to solid angle without the cosine at the patch. The bins' cap
/// (about the direction to the patch's centre) holds the whole patch in 16 rings.
fn check_patch(s: &PatchSampler, from: DVec3, cap: f64, seed: u64) {
    let axis = (s.center - from).normalize();
    // Patch edges cut bins anywhere: the quadrature starts from 256 cells per bin.
    let bins = SphereBins::split_at(axis, 1.0 - cap.cos(), 16, 8, 32).resolving(4);
    let (hist, c) = chi2_test(
        &bins,
        SAMPLES,
        seed,
        |u| s.sample(from, u),
        |d| s.pdf(from, *d),
    );
    let name = format!("patch α={} from {from}", s.alpha);
    FAMILY.accept(&name, &hist, &c);
    // The bins' adaptive quadrature, which shares no code with the sampler, integrates the
    // density to 1 across the patch's edges.
    assert!((c.pdf_total - 1.0).abs() < 2e-3, "{name}: {c}");
    let uniform = (1.0 - s.alpha) / (4.0 * PI);
    let more = |d: &DVec3| 1.01 * (s.pdf(from, *d) - uniform) + uniform;
    FAMILY.reject(
        &format!("{name} with 1 % more mass on the patch"),
        &chi2(&bins, &hist, more),
    );
    // Area density 1/A taken as a solid-angle density after t² alone (no 1/|cos θ|).
    let n = s.half_u.cross(s.half_v).normalize();
    let no_cosine = |d: &DVec3| {
        let on_patch = s.pdf(from, *d) - uniform;
        on_patch * n.dot(*d).abs() + uniform
    };
    FAMILY.reject(
        &format!("{name} without the cosine"),
        &chi2(&bins, &hist, no_cosine),
    );
}

#[test]
fn patch_skewed_and_oblique() {
    // A skewed parallelogram seen at about 50° from its normal.
    let s = PatchSampler::new(
        DVec3::new(-1.0, 2.0, 0.5),
        DVec3::new(0.5, 0.0, 0.1),
        DVec3::new(0.1, 0.15, 0.3),
        0.8,
    )
    .unwrap();
    check_patch(&s, FROM, 0.45, 31);
}

#[test]
fn patch_nearly_edge_on() {
    // The patch seen about 78° off its normal: small |n·ω|, large densities. (More
    // nearly edge-on, the patch becomes a sliver thinner than the bins' quadrature
    // resolves.)
    let s = PatchSampler::new(
        DVec3::new(0.0, 0.05, 1.5),
        DVec3::new(0.6, 0.0, 0.0),
        DVec3::new(0.0, 0.08, 0.3),
        0.95,
    )
    .unwrap();
    check_patch(&s, DVec3::new(0.1, -0.02, 0.0), 0.7, 32);
}

#[test]
fn patch_tiny() {
    let s = PatchSampler::new(
        DVec3::new(1.0, 1.0, 1.0),
        DVec3::new(1e-3, 0.0, 0.0),
        DVec3::new(0.0, 2e-3, 0.0),
        0.5,
    )
    .unwrap();
    check_patch(&s, FROM, 2e-3, 33);
}
