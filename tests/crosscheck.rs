//! Embree and obvhs must answer every ray query alike: same hit or miss, same primitive,
//! `t` within 1e-4 relative, any-hit consistent with closest-hit, and packets identical to
//! single rays. Needs both back-ends: `cargo test --features embree,obvhs --test crosscheck`.
//!
//! Two principled allowances, each counted in the report:
//! * *ambiguous*: different triangles at the same `t`, both really crossed there (checked by
//!   an independent f64 Möller–Trumbore): a shared edge, or two triangles meeting at the hit.
//! * *resolution*: hits closer to the origin than the f32 resolution of the coordinates
//!   (a few ulps of the largest coordinate) cannot agree to 1e-4 relative; there `t` must
//!   agree to that absolute resolution instead, and the any-hit probes step by at least it.
#![cfg(all(feature = "embree", feature = "obvhs"))]

mod stress;

use genpath::accel::{
    Accel, BvhAccel, Coherence, EmbreeAccel, Hit, Ray, TriangleMesh, PACKET_SIZE,
};
use genpath::report::bench;
use genpath::scene::Scene;
use glam::Vec3;
use std::fmt;

/// Relative tolerance on `t` between back-ends.
const T_REL_TOL: f32 = 1e-4;
/// Slack, in barycentric units, when deciding in f64 whether a ray passes through a triangle:
/// f32 rounding of the inputs moves an edge crossing by ~1e-6 for the stress mesh's smallest
/// triangles, so 1e-4 only admits rays that really graze an edge.
const BARY_SLACK: f64 = 1e-4;
/// Relative step of `tmax` below / above a closest hit for the any-hit checks.
const ANY_HIT_STEP: f32 = 1e-3;
/// Absolute resolution of `t`, in ulps of the largest coordinate involved (f32 rounding of the
/// origin and vertices alone moves a hit by about one ulp of them).
const RESOLUTION_ULPS: f32 = 4.0;
/// Failures quoted in a report (all are counted).
const QUOTED: usize = 12;

/// How one ray's two answers compare.
#[derive(Debug, PartialEq)]
enum Verdict {
    Agree,
    /// Same triangle, `t` equal only to within the coordinates' f32 resolution.
    Resolution,
    /// Different triangles at the same `t`, both really crossed there (a shared edge or two
    /// triangles meeting at the hit point): either answer is right.
    Ambiguous,
    Disagree(String),
}

/// Independent f64 Möller–Trumbore: `(t, u, v)` of the ray's crossing with the triangle's
/// plane, barycentrics in Embree's convention (`u` weights v1, `v` weights v2), no bounds test.
fn crossing_f64(mesh: &TriangleMesh, prim: u32, ray: &Ray) -> Option<(f64, f64, f64)> {
    let [v0, v1, v2] = mesh.vertices(prim).map(|v| v.as_dvec3());
    let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
    let (e1, e2) = (v1 - v0, v2 - v0);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        return None;
    }
    let s = o - v0;
    let q = s.cross(e1);
    Some((e2.dot(q) / det, s.dot(p) / det, d.dot(q) / det))
}

/// The tolerances for one mesh.
struct Checker<'a> {
    mesh: &'a TriangleMesh,
    /// Largest absolute vertex coordinate.
    scale: f32,
}

impl<'a> Checker<'a> {
    fn new(mesh: &'a TriangleMesh) -> Self {
        let scale = mesh
            .positions
            .iter()
            .fold(0.0f32, |m, p| m.max(p.abs().max_element()));
        Self { mesh, scale }
    }

    /// The smallest meaningful difference in `t` along `ray`.
    fn resolution(&self, ray: &Ray) -> f32 {
        let scale = self.scale.max(ray.origin.abs().max_element());
        RESOLUTION_ULPS * f32::EPSILON * scale / ray.dir.length()
    }

    fn t_close(&self, ray: &Ray, a: f32, b: f32) -> bool {
        (a - b).abs() <= T_REL_TOL * a.abs().max(b.abs()).max(self.resolution(ray) / T_REL_TOL)
    }

    /// Whether the ray really crosses triangle `prim` at `t` (within tolerances).
    fn crosses_at(&self, prim: u32, ray: &Ray, t: f32) -> bool {
        crossing_f64(self.mesh, prim, ray).is_some_and(|(tf, u, v)| {
            let inside = u >= -BARY_SLACK && v >= -BARY_SLACK && u + v <= 1.0 + BARY_SLACK;
            inside && self.t_close(ray, tf as f32, t)
        })
    }

    fn compare(&self, ray: &Ray, a: Option<Hit>, b: Option<Hit>) -> Verdict {
        match (a, b) {
            (None, None) => Verdict::Agree,
            (Some(a), Some(b)) if a.prim == b.prim => {
                if (a.t - b.t).abs() <= T_REL_TOL * a.t.abs().max(b.t.abs()) {
                    Verdict::Agree
                } else if self.t_close(ray, a.t, b.t) {
                    Verdict::Resolution
                } else {
                    Verdict::Disagree(format!("{ray:?}: {a:?} vs {b:?}"))
                }
            }
            (Some(a), Some(b))
                if self.t_close(ray, a.t, b.t)
                    && self.crosses_at(a.prim, ray, a.t)
                    && self.crosses_at(b.prim, ray, b.t) =>
            {
                Verdict::Ambiguous
            }
            (a, b) => Verdict::Disagree(format!("{ray:?}: {a:?} vs {b:?}")),
        }
    }

    /// `tmax` just short of (`sign = -1`) or just past (`+1`) a hit at `t`.
    fn probe_tmax(&self, ray: &Ray, t: f32, sign: f32) -> f32 {
        t + sign * (ANY_HIT_STEP * t).max(self.resolution(ray))
    }
}

#[derive(Default)]
struct Report {
    rays: usize,
    hits: usize,
    agree: usize,
    ambiguous: usize,
    /// Largest `|Δt| / t` over agreeing hits on the same triangle.
    max_rel_dt: f32,
    disagree: usize,
    any_hit_failures: usize,
    packet_failures: usize,
    /// Hits on the same triangle whose `t` agree only to the coordinates' resolution.
    resolution: usize,
    quoted: Vec<String>,
}

impl Report {
    fn fail(&mut self, message: String) {
        if self.quoted.len() < QUOTED {
            self.quoted.push(message);
        }
    }

    fn failures(&self) -> usize {
        self.disagree + self.any_hit_failures + self.packet_failures
    }

    fn assert_clean(&self) {
        assert_eq!(self.failures(), 0, "back-ends disagree:\n{self}");
    }
}

impl fmt::Display for Report {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "{} rays, {} hit: {} agree (max |Δt|/t {:.2e}), {} agree within f32 resolution, \
             {} ambiguous (same t, other triangle also crossed), {} disagree; any-hit failures \
             {}; packet failures {}",
            self.rays,
            self.hits,
            self.agree,
            self.max_rel_dt,
            self.resolution,
            self.ambiguous,
            self.disagree,
            self.any_hit_failures,
            self.packet_failures
        )?;
        for message in &self.quoted {
            writeln!(f, "  {message}")?;
        }
        Ok(())
    }
}

/// Embree's two packet paths: packets go to Embree 8 or 16 rays at a time (the CPU's native
/// width decides which one renders), and both must answer like single rays on any CPU.
const EMBREE_LANES: [usize; 2] = [8, 16];

/// Cross-checks Embree, with each of [`EMBREE_LANES`], against obvhs on `rays` over `mesh`.
fn crosscheck(mesh: &TriangleMesh, rays: &[Ray]) -> [Report; 2] {
    let bvh = BvhAccel::new(mesh);
    EMBREE_LANES.map(|lanes| {
        let embree = EmbreeAccel::with_lanes(mesh, lanes).expect("Embree builds the scene");
        assert_eq!(embree.packet_lanes(), lanes);
        crosscheck_accels(mesh, &embree, &bvh, rays)
    })
}

fn crosscheck_accels(mesh: &TriangleMesh, a: &dyn Accel, b: &dyn Accel, rays: &[Ray]) -> Report {
    let checker = Checker::new(mesh);
    let mut report = Report {
        rays: rays.len(),
        ..Report::default()
    };
    let hits_a: Vec<Option<Hit>> = rays.iter().map(|r| a.intersect(r)).collect();
    let hits_b: Vec<Option<Hit>> = rays.iter().map(|r| b.intersect(r)).collect();

    for ((ray, &ha), &hb) in rays.iter().zip(&hits_a).zip(&hits_b) {
        report.hits += usize::from(ha.is_some());
        match checker.compare(ray, ha, hb) {
            Verdict::Agree => {
                report.agree += 1;
                if let (Some(ha), Some(hb)) = (ha, hb) {
                    let rel = (ha.t - hb.t).abs() / ha.t.abs().max(f32::MIN_POSITIVE);
                    report.max_rel_dt = report.max_rel_dt.max(rel);
                }
            }
            Verdict::Resolution => report.resolution += 1,
            Verdict::Ambiguous => report.ambiguous += 1,
            Verdict::Disagree(message) => {
                report.disagree += 1;
                report.fail(format!("closest hit: {message}"));
            }
        }
    }
    for (accel, hits) in [(a, &hits_a), (b, &hits_b)] {
        check_any_hit(&checker, accel, rays, hits, &mut report);
        check_packets(&checker, accel, rays, hits, &mut report);
    }
    report
}

/// Any-hit must agree with closest-hit: blocked over the whole segment iff there is a hit,
/// free just short of the hit, blocked just past it.
fn check_any_hit(
    checker: &Checker,
    accel: &dyn Accel,
    rays: &[Ray],
    hits: &[Option<Hit>],
    report: &mut Report,
) {
    for (ray, &hit) in rays.iter().zip(hits) {
        let whole = accel.occluded(ray);
        let (short, long) = match hit {
            None => (false, true),
            Some(h) => {
                let short_tmax = checker.probe_tmax(ray, h.t, -1.0);
                let long_tmax = checker.probe_tmax(ray, h.t, 1.0);
                let short = short_tmax > ray.tmin
                    && accel.occluded(&Ray {
                        tmax: short_tmax,
                        ..*ray
                    });
                (
                    short,
                    accel.occluded(&Ray {
                        tmax: long_tmax,
                        ..*ray
                    }),
                )
            }
        };
        if whole != hit.is_some() || short || !long {
            report.any_hit_failures += 1;
            let name = accel.name();
            report.fail(format!(
                "{name} any-hit (whole {whole}, short {short}, long {long}) vs {hit:?}: {ray:?}"
            ));
        }
    }
}

/// Packet queries must return exactly the single-ray answers, with either traversal.
/// Packet sizes cycle through 16 and partial sizes so that masked-off lanes are exercised.
/// The coherence hint alternates every four packets, so that each traversal sees full and
/// partial packets. Where a ray meets two triangles at one `t`, the coherent traversal may
/// name either (see `Accel`): the checker's ambiguous verdict is accepted there.
fn check_packets(
    checker: &Checker,
    accel: &dyn Accel,
    rays: &[Ray],
    hits: &[Option<Hit>],
    report: &mut Report,
) {
    let name = accel.name();
    let mut start = 0;
    for chunk_index in 0.. {
        if start >= rays.len() {
            break;
        }
        let size = if chunk_index % 4 == 3 {
            1 + chunk_index % PACKET_SIZE
        } else {
            PACKET_SIZE
        };
        let end = (start + size).min(rays.len());
        let (packet, expected) = (&rays[start..end], &hits[start..end]);
        let coherence = [Coherence::Coherent, Coherence::Incoherent][(chunk_index / 4) % 2];

        let mut got = [None; PACKET_SIZE];
        accel.intersect_packet(packet, &mut got[..packet.len()], coherence);
        for (i, (g, e)) in got.iter().zip(expected).enumerate() {
            let tie = coherence == Coherence::Coherent
                && matches!(checker.compare(&packet[i], *g, *e), Verdict::Ambiguous);
            if g != e && !tie {
                report.packet_failures += 1;
                report.fail(format!(
                    "{name} {coherence:?} packet intersect {g:?} vs single {e:?}: {:?}",
                    packet[i]
                ));
            }
        }

        // Occlusion over whole segments and over segments stopping just short of the hit,
        // so that packets see both answers.
        for short in [false, true] {
            let shadow: Vec<Ray> = packet
                .iter()
                .zip(expected)
                .map(|(r, h)| match h {
                    Some(h) if short => Ray {
                        tmax: checker.probe_tmax(r, h.t, -1.0).max(r.tmin),
                        ..*r
                    },
                    _ => *r,
                })
                .collect();
            let mut blocked = [false; PACKET_SIZE];
            accel.occluded_packet(&shadow, &mut blocked[..shadow.len()], coherence);
            for (ray, &b) in shadow.iter().zip(&blocked) {
                if b != accel.occluded(ray) {
                    report.packet_failures += 1;
                    report.fail(format!(
                        "{name} {coherence:?} packet occluded {b} differs from single: {ray:?}"
                    ));
                }
            }
        }
        start = end;
    }
}

fn stress_scene() -> TriangleMesh {
    let mesh = stress::stress_mesh(7);
    assert!(mesh.triangles.len() >= 100_000);
    mesh
}

#[test]
fn incoherent_rays_agree() {
    let mesh = stress_scene();
    let (lo, hi) = mesh.bounds();
    let rays = bench::random_rays(lo, hi, 100_000, 11);
    for (lanes, report) in EMBREE_LANES.iter().zip(crosscheck(&mesh, &rays)) {
        println!("incoherent, Embree {lanes} lanes: {report}");
        report.assert_clean();
        // About half the rays escape upwards; the rest must hit, or the test tests little.
        assert!(report.hits > rays.len() * 2 / 5, "{report}");
    }
}

/// The design's extreme scales (1e-4 and 1e5): only relative tolerances may matter.
#[test]
fn tiny_and_huge_scenes_agree() {
    for scale in [1e-4f32, 1e5] {
        let mut mesh = stress_scene();
        mesh.positions.iter_mut().for_each(|p| *p *= scale);
        let (lo, hi) = mesh.bounds();
        let rays = bench::random_rays(lo, hi, 20_000, 5);
        for (lanes, report) in EMBREE_LANES.iter().zip(crosscheck(&mesh, &rays)) {
            println!("scale {scale:e}, Embree {lanes} lanes: {report}");
            report.assert_clean();
            assert!(report.hits > rays.len() * 2 / 5, "{report}");
        }
    }
}

#[test]
fn coherent_rays_agree() {
    let mesh = stress_scene();
    let rays = stress::camera_rays(Vec3::new(0.3, 0.8, 4.5), Vec3::ZERO, 50.0, 320, 320);
    assert!(rays.len() >= 100_000);
    for (lanes, report) in EMBREE_LANES.iter().zip(crosscheck(&mesh, &rays)) {
        println!("coherent, Embree {lanes} lanes: {report}");
        report.assert_clean();
        assert!(
            report.hits > rays.len() / 2 && report.hits < rays.len(),
            "{report}"
        );
    }
}

/// A shipped scene: every pixel centre of its camera at 320 × 320, and as many random rays
/// inside its bounds.
fn shipped_scene_agrees(name: &str) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name)
        .join("scene.toml");
    let scene = Scene::load(&path).unwrap_or_else(|err| panic!("{}: {err}", path.display()));
    let camera = scene.camera.resized(320, 320);
    let mut rays: Vec<Ray> = (0..320 * 320)
        .map(|i| camera.ray((i % 320) as f32 + 0.5, (i / 320) as f32 + 0.5))
        .collect();
    let (lo, hi) = scene.mesh.bounds();
    rays.extend(bench::random_rays(lo, hi, 100_000, 13));
    for (lanes, report) in EMBREE_LANES.iter().zip(crosscheck(&scene.mesh, &rays)) {
        println!("{name}, Embree {lanes} lanes: {report}");
        report.assert_clean();
        assert!(report.hits > rays.len() / 2, "{report}");
    }
}

#[test]
fn fig5_scene_agrees() {
    shipped_scene_agrees("fig5");
}

#[test]
fn cbox_scene_agrees() {
    shipped_scene_agrees("cbox");
}

/// Shading normals depend on a hit's barycentrics, not only its triangle and `t`: on the
/// smooth-shaded `scenes/mitsuba/smooth.xml`, every camera ray at 128² that both back-ends
/// send to the same triangle gets the same interpolated normal (≤ 1e-4); the same normals
/// with `u` and `v` swapped (the other barycentric convention) must differ.
#[test]
fn smooth_scene_shading_normals_agree() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/mitsuba/smooth.xml");
    let scene = Scene::load(&path).unwrap_or_else(|err| panic!("{}: {err}", path.display()));
    let camera = scene.camera.resized(128, 128);
    let bvh = BvhAccel::new(&scene.mesh);
    let embree = EmbreeAccel::with_lanes(&scene.mesh, 8).expect("Embree builds the scene");
    let (mut smooth, mut swapped_apart, mut worst) = (0, 0, 0.0f32);
    for i in 0..128 * 128 {
        let ray = camera.ray((i % 128) as f32 + 0.5, (i / 128) as f32 + 0.5);
        let (Some(a), Some(b)) = (embree.intersect(&ray), bvh.intersect(&ray)) else {
            continue;
        };
        let t = scene.mesh.triangles[a.prim as usize];
        if a.prim != b.prim || scene.shading.normal(t, 0.0, 0.0).is_none() {
            continue;
        }
        smooth += 1;
        let ns = |h: &Hit| scene.shading_normal(h.prim, (h.u, h.v), h.ng);
        worst = worst.max((ns(&a) - ns(&b)).length());
        let swapped = scene.shading_normal(b.prim, (b.v, b.u), b.ng);
        swapped_apart += usize::from((swapped - ns(&a)).length() > 1e-3);
    }
    println!("{smooth} smooth hits, largest difference {worst:e}, {swapped_apart} apart with u and v swapped");
    assert!(smooth > 1000, "{smooth}");
    assert!(worst <= 1e-4, "{worst}");
    assert!(swapped_apart > smooth / 2, "{swapped_apart} of {smooth}");
}

/// A two-triangle quad in z = 0 sharing the diagonal v0–v2.
fn quad() -> TriangleMesh {
    let positions = vec![
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
    ];
    TriangleMesh::new(positions, vec![[0, 1, 2], [0, 2, 3]])
}

fn down_at(x: f32, y: f32) -> Ray {
    Ray::new(
        Vec3::new(x, y, 2.0),
        Vec3::new(0.0, 0.0, -1.0),
        0.0,
        f32::INFINITY,
    )
}

fn hit(prim: u32, t: f32) -> Hit {
    Hit {
        t,
        prim,
        u: 0.0,
        v: 0.0,
        ng: Vec3::Z,
    }
}

#[test]
fn comparison_rejects_wrong_hits() {
    let mesh = quad();
    let checker = Checker::new(&mesh);
    let ray = down_at(0.75, 0.25); // crosses triangle 0 only, at t = 2
    assert_eq!(
        checker.compare(&ray, Some(hit(0, 2.0)), Some(hit(0, 2.0001))),
        Verdict::Agree
    );
    assert_eq!(checker.compare(&ray, None, None), Verdict::Agree);
    let wrong = [
        (Some(hit(0, 2.0)), Some(hit(1, 2.1))), // other triangle, other t
        (Some(hit(0, 2.0)), Some(hit(1, 2.0))), // other triangle, same t, but not crossed
        (Some(hit(0, 2.0)), Some(hit(0, 2.001))), // same triangle, t off by 5e-4
        (Some(hit(0, 2.0)), None),
        (None, Some(hit(0, 2.0))),
    ];
    for (a, b) in wrong {
        let verdict = checker.compare(&ray, a, b);
        assert!(
            matches!(verdict, Verdict::Disagree(_)),
            "{a:?} vs {b:?} gave {verdict:?}"
        );
    }
}

#[test]
fn resolution_allowance_is_only_a_few_ulps() {
    let mesh = quad();
    let checker = Checker::new(&mesh);
    // Origin 1e-6 above the quad: the coordinates' resolution is ~5e-7, so a 1e-7 difference
    // in t is rounding, a 1e-5 one is not.
    let ray = Ray::new(
        Vec3::new(0.75, 0.25, 1e-6),
        Vec3::new(0.0, 0.0, -1.0),
        0.0,
        1.0,
    );
    assert_eq!(
        checker.compare(&ray, Some(hit(0, 1e-6)), Some(hit(0, 1.1e-6))),
        Verdict::Resolution
    );
    assert!(matches!(
        checker.compare(&ray, Some(hit(0, 1e-6)), Some(hit(0, 1.1e-5))),
        Verdict::Disagree(_)
    ));
}

#[test]
fn comparison_accepts_either_triangle_on_a_shared_edge() {
    let mesh = quad();
    let checker = Checker::new(&mesh);
    let on_edge = down_at(0.5, 0.5); // through the shared diagonal
    assert_eq!(
        checker.compare(&on_edge, Some(hit(0, 2.0)), Some(hit(1, 2.0))),
        Verdict::Ambiguous
    );
    // Just off the edge (1e-3 in barycentrics, 10× the slack) it is no longer ambiguous.
    let off_edge = down_at(0.5005, 0.4995);
    assert!(matches!(
        checker.compare(&off_edge, Some(hit(0, 2.0)), Some(hit(1, 2.0))),
        Verdict::Disagree(_)
    ));
}

/// Wraps a back-end and corrupts some single-ray answers (prim off by one at a different t)
/// while packet queries still return the true ones.
struct Corrupted<'a>(&'a dyn Accel);

impl Accel for Corrupted<'_> {
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.0.intersect(ray).map(|h| {
            if h.prim % 50 == 0 {
                Hit {
                    prim: h.prim + 1,
                    t: h.t * 1.01,
                    ..h
                }
            } else {
                h
            }
        })
    }
    fn occluded(&self, ray: &Ray) -> bool {
        self.0.occluded(ray)
    }
    fn intersect_packet(&self, rays: &[Ray], hits: &mut [Option<Hit>], c: Coherence) {
        self.0.intersect_packet(rays, hits, c)
    }
    fn occluded_packet(&self, rays: &[Ray], blocked: &mut [bool], c: Coherence) {
        self.0.occluded_packet(rays, blocked, c)
    }
    fn name(&self) -> &'static str {
        "corrupted"
    }

    fn packet_lanes(&self) -> usize {
        self.0.packet_lanes()
    }
}

#[test]
fn crosscheck_catches_a_corrupted_back_end() {
    let mesh = stress_scene();
    let (lo, hi) = mesh.bounds();
    let rays = bench::random_rays(lo, hi, 5_000, 3);
    let embree = EmbreeAccel::new(&mesh).expect("Embree builds the scene");
    let bvh = BvhAccel::new(&mesh);
    let clean = crosscheck_accels(&mesh, &embree, &bvh, &rays);
    clean.assert_clean();
    let corrupted = Corrupted(&bvh);
    let report = crosscheck_accels(&mesh, &embree, &corrupted, &rays);
    println!("corrupted: {report}");
    // About 2% of hits are corrupted: each must show up as a closest-hit disagreement, a
    // failed any-hit check (the corrupted t is 1% too far) and a packet mismatch.
    assert!(
        report.disagree > 0 && report.disagree == report.packet_failures,
        "{report}"
    );
    assert!(report.any_hit_failures >= report.disagree, "{report}");
}

/// Rays Embree would assert on (non-finite origin or direction, `tmin > tmax`, negative
/// `tmin`): both back-ends answer no hit and blocked, alone and inside packets of valid rays.
#[test]
fn invalid_rays_miss_and_are_blocked_on_both_back_ends() {
    let mesh = quad();
    let [embree8, embree16] =
        EMBREE_LANES.map(|lanes| EmbreeAccel::with_lanes(&mesh, lanes).unwrap());
    let bvh = BvhAccel::new(&mesh);
    // Off the shared diagonal: on it, either triangle is a right answer (see `Accel`).
    let good = down_at(0.3, 0.2);
    let bad = [
        Ray::new(Vec3::new(f32::NAN, 1.0, 0.0), good.dir, 0.0, f32::INFINITY),
        Ray::new(
            good.origin,
            Vec3::new(0.0, f32::NEG_INFINITY, 0.0),
            0.0,
            f32::INFINITY,
        ),
        Ray::new(good.origin, good.dir, 2.0, 1.0),
        Ray::new(good.origin, good.dir, -1.0, f32::INFINITY),
        Ray::new(good.origin, good.dir, f32::NAN, f32::INFINITY),
    ];
    for accel in [&embree8 as &dyn Accel, &embree16, &bvh] {
        assert!(accel.intersect(&good).is_some() && !accel.occluded(&Ray { tmax: 0.5, ..good }));
        for ray in &bad {
            assert!(!ray.is_valid());
            assert_eq!(accel.intersect(ray), None, "{}: {ray:?}", accel.name());
            assert!(accel.occluded(ray), "{}: {ray:?}", accel.name());
        }
        let mut packet = vec![good; 3];
        packet.extend_from_slice(&bad);
        let mut hits = vec![None; packet.len()];
        let mut blocked = vec![false; packet.len()];
        for coherence in [Coherence::Coherent, Coherence::Incoherent] {
            accel.intersect_packet(&packet, &mut hits, coherence);
            accel.occluded_packet(&packet, &mut blocked, coherence);
            for (i, ray) in packet.iter().enumerate() {
                let name = accel.name();
                assert_eq!(
                    hits[i],
                    accel.intersect(ray),
                    "{name} {coherence:?}: lane {i}"
                );
                assert_eq!(
                    blocked[i],
                    accel.occluded(ray),
                    "{name} {coherence:?}: lane {i}"
                );
            }
        }
    }
}
