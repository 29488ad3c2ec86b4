//! The test-path store: the generators' own densities, packets against single rays, and
//! where its step targets lie.

use super::*;

#[test]
fn stored_paths_give_the_generators_own_densities() {
    for nee in [Nee::End, Nee::Every] {
        stored_paths_give_the_generators_own_densities_with(nee);
    }
}

fn stored_paths_give_the_generators_own_densities_with(nee: Nee) {
    let (scene, accel) = fig5();
    let view = SceneView::new(&scene, accel.as_ref());
    let config = GaConfig::default();
    let mut pool = GenePool::new(&scene, MAX_BOUNCES, &config);
    let mut rng = Rng::seed_from_u64(2);
    // Hand-made anchors find light often; random generators exercise every sampler type.
    let anchors = anchors_mixture(&scene);
    let random = pool.random_individual(&config, &mut rng).to_mixture();
    let sampler = Mixture::combine(&[(1.0, &anchors), (1.0, &random)]).with_nee(nee);
    let mut judges: Vec<_> = (0..8).map(|_| pool.random_gene(&mut rng)).collect();
    // A patch over the red wall's lit top at the first step.
    let mut patched = judges[0].clone();
    patched.generator.steps[0].sampler = DirectionSampler::Patch(
        PatchSampler::new(
            DVec3::new(-1.0, 1.8, 0.0),
            DVec3::new(0.0, 0.2, 0.0),
            DVec3::new(0.0, 0.0, 1.0),
            0.9,
        )
        .unwrap(),
    );
    patched.anchor_prims[0] = None;
    judges.push(patched);
    let mut paths = TestPaths::new(MAX_BOUNCES, nee);
    let mut expected = Vec::new();
    // The same of the paths of at most two vertices: the judges have steps past what any of
    // them reads, whose absorption still weighs an end-only light point.
    let mut short = (TestPaths::new(MAX_BOUNCES, nee), Vec::new());
    let (mut path, mut contributions) = (PathVertices::default(), Vec::new());
    let mut counts = RayCounts::default();
    for s in 0..20_000u64 {
        let mut rng = sample_rng(3, 0, s);
        let (x, y) = (
            uniform(&mut rng) * SIZE as f32,
            uniform(&mut rng) * SIZE as f32,
        );
        let ray = scene.camera.ray(x, y);
        let Some(x1) = view.trace(&ray, &mut counts) else {
            continue;
        };
        let g = &sampler.generators[(s as usize) % sampler.generators.len()];
        contributions.clear();
        g.sample_path(
            &view,
            ray.origin,
            x1,
            (MAX_BOUNCES, nee),
            &mut rng,
            &mut counts,
            &mut path,
            &mut contributions,
        );
        for c in &contributions {
            let densities: Vec<f64> = judges
                .iter()
                .map(|j| {
                    j.generator
                        .pdf_contribution(&view, &path, c, (MAX_BOUNCES, nee))
                })
                .collect();
            if c.len <= 2 {
                short.0.push(&view, &path, c, DVec3::ONE);
                short.1.push(densities.clone());
            }
            paths.push(&view, &path, c, DVec3::ONE);
            expected.push(densities);
        }
    }
    for (paths, expected) in [(&paths, &expected), (&short.0, &short.1)] {
        assert!(
            paths.len() > 50,
            "only {} light-carrying paths",
            paths.len()
        );
        let mut got = vec![0.0; paths.len()];
        let mut nonzero = 0;
        for (j, judge) in judges.iter().enumerate() {
            paths.generator_pdfs(&view, &judge.generator, &mut got);
            for (i, g) in got.iter().enumerate() {
                let e = expected[i][j];
                assert!(
                    (g - e).abs() <= 1e-12 * e.abs(),
                    "{nee:?}: path {i} of {}, generator {j}: {g} vs {e}",
                    paths.len()
                );
                nonzero += (e > 0.0) as usize;
            }
        }
        assert!(
            nonzero > paths.len(),
            "densities are mostly zero: {nonzero}"
        );
    }
}

/// Whether two stores hold the same paths in the same order: every array, `F²/q` bit for bit.
fn same_paths(a: &TestPaths, b: &TestPaths) -> bool {
    a == b
        && a.f2_over_q
            .iter()
            .zip(&b.f2_over_q)
            .all(|(x, y)| x.to_bits() == y.to_bits())
}

/// Test paths per comparison: not a multiple of 16, so that the last packet is partial.
const PACKET_M: usize = 8001;

/// Test paths traced in packets equal those traced ray by ray with the same seed (every
/// stored array and the ray counts), on every back-end, for srt and the anchors, at a floor
/// pixel and at a pixel whose packets mix floor, wall and camera rays that miss. A store of
/// another seed differs, so the comparison can fail.
#[test]
fn packet_traced_test_paths_equal_single_ray_ones() {
    for kind in backends() {
        let (scene, accel) = fig5_on(kind);
        let view = SceneView::new(&scene, accel.as_ref());
        assert_on_floor(&view, FLOOR_PIXEL);
        let edge = corner_hits(&view, EDGE_PIXEL);
        assert_eq!(
            edge,
            ["nothing", "red", "white"],
            "{EDGE_PIXEL:?} is not the corner"
        );
        for (name, q) in [
            ("srt", srt_mixture(&scene)),
            ("anchors", anchors_mixture(&scene)),
        ] {
            for pixel in [FLOOR_PIXEL, EDGE_PIXEL] {
                let what = format!("{kind:?}, {name}, pixel {pixel:?}");
                let sample =
                    |seed| TestPaths::sample(&view, &q, pixel, PACKET_M, MAX_BOUNCES, seed);
                let (single, single_counts) =
                    TestPaths::sample_single(&view, &q, pixel, PACKET_M, MAX_BOUNCES, 13);
                let (packet, packet_counts) = sample(13);
                assert_eq!(single.sampled, PACKET_M);
                assert!(single.len() > 20, "{what}: {} light paths", single.len());
                assert!(
                    same_paths(&single, &packet),
                    "{what}: {} light paths traced singly, {} in packets",
                    single.len(),
                    packet.len()
                );
                assert_eq!(
                    (single_counts.closest, single_counts.shadow),
                    (packet_counts.closest, packet_counts.shadow),
                    "{what}: ray counts"
                );
                eprintln!("{what}: {} light paths of {PACKET_M}", packet.len());
                let (other, _) = sample(14);
                assert!(!same_paths(&other, &packet), "{what}: seed ignored");
            }
        }
    }
}

/// [`TestPaths::sample_until`] stops after the first 16 paths (`0..16`, `16..32`, …) during
/// which the stored light-carrying paths reach the limit, whatever the size of the waves it
/// traces: its store equals the one of that many paths traced ray by ray, which 16 fewer
/// paths leave short of the limit.
#[test]
fn test_paths_stop_after_the_packet_that_reaches_the_limit() {
    let (scene, accel) = fig5_on(AccelKind::default_available());
    let view = SceneView::new(&scene, accel.as_ref());
    let q = srt_mixture(&scene);
    for max_light in [1, 37, 100, 333] {
        let (until, _) = TestPaths::sample_until(
            &view,
            &q,
            FLOOR_PIXEL,
            (PACKET_M, max_light),
            MAX_BOUNCES,
            13,
        );
        let m = until.sampled;
        assert!(
            until.len() >= max_light,
            "{max_light}: stopped short at {m}"
        );
        assert_eq!(m % PACKET_SIZE, 0, "{max_light}: {m} paths");
        let (single, _) = TestPaths::sample_single(&view, &q, FLOOR_PIXEL, m, MAX_BOUNCES, 13);
        assert!(same_paths(&single, &until), "{max_light}: {m} paths");
        let (fewer, _) =
            TestPaths::sample_single(&view, &q, FLOOR_PIXEL, m - PACKET_SIZE, MAX_BOUNCES, 13);
        assert!(
            fewer.len() < max_light,
            "{max_light}: went on past {}",
            fewer.sampled
        );
    }
}

/// A back-end whose closest-hit packet queries turn the ray in lane 3 slightly: a packet
/// driver that mixes up one lane's ray, which the comparison of stores must catch.
struct NudgedLane<'a>(&'a dyn Accel);

impl Accel for NudgedLane<'_> {
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.0.intersect(ray)
    }
    fn occluded(&self, ray: &Ray) -> bool {
        self.0.occluded(ray)
    }
    fn intersect_packet(&self, rays: &[Ray], hits: &mut [Option<Hit>], c: Coherence) {
        let mut nudged = [Ray::new(Vec3::ZERO, Vec3::ZERO, 0.0, 0.0); PACKET_SIZE];
        nudged[..rays.len()].copy_from_slice(rays);
        if let Some(ray) = nudged[..rays.len()].get_mut(3) {
            ray.dir = (ray.dir + Vec3::new(1e-3, 0.0, 0.0)).normalize();
        }
        self.0.intersect_packet(&nudged[..rays.len()], hits, c);
    }
    fn occluded_packet(&self, rays: &[Ray], blocked: &mut [bool], c: Coherence) {
        self.0.occluded_packet(rays, blocked, c)
    }
    fn name(&self) -> &'static str {
        "nudged"
    }
    fn packet_lanes(&self) -> usize {
        self.0.packet_lanes()
    }
}

#[test]
fn test_paths_with_one_lane_off_differ_from_single_ray_ones() {
    for kind in backends() {
        let (scene, accel) = fig5_on(kind);
        let nudged = NudgedLane(accel.as_ref());
        let (view, nudged_view) = (
            SceneView::new(&scene, accel.as_ref()),
            SceneView::new(&scene, &nudged),
        );
        let q = srt_mixture(&scene);
        let (single, _) =
            TestPaths::sample_single(&view, &q, FLOOR_PIXEL, PACKET_M, MAX_BOUNCES, 13);
        // Single rays do not go through the nudged packet query.
        let (nudged_single, _) =
            TestPaths::sample_single(&nudged_view, &q, FLOOR_PIXEL, PACKET_M, MAX_BOUNCES, 13);
        assert!(same_paths(&single, &nudged_single), "{kind:?}");
        let (packet, _) =
            TestPaths::sample(&nudged_view, &q, FLOOR_PIXEL, PACKET_M, MAX_BOUNCES, 13);
        assert!(
            !same_paths(&single, &packet),
            "{kind:?}: a nudged lane went unnoticed"
        );
    }
}

/// Time of packet against single-ray tracing of the GA's test paths (M = 50 000, a fig5
/// floor pixel, Embree, this thread): printed, not asserted, as other tests may run beside
/// it. Best of five runs each, interleaved.
#[cfg(feature = "embree")]
#[test]
fn packet_tracing_time() {
    let (scene, accel) = fig5_on(AccelKind::Embree);
    let view = SceneView::new(&scene, accel.as_ref());
    let q = srt_mixture(&scene);
    let m = 50_000;
    let (mut single_s, mut packet_s) = (f64::INFINITY, f64::INFINITY);
    let mut counts = RayCounts::default();
    let mut light_paths = 0;
    for _ in 0..5 {
        let start = Instant::now();
        let (single, single_counts) =
            TestPaths::sample_single(&view, &q, FLOOR_PIXEL, m, MAX_BOUNCES, 15);
        single_s = single_s.min(start.elapsed().as_secs_f64());
        let start = Instant::now();
        let (packet, _) = TestPaths::sample(&view, &q, FLOOR_PIXEL, m, MAX_BOUNCES, 15);
        packet_s = packet_s.min(start.elapsed().as_secs_f64());
        assert!(same_paths(&single, &packet));
        (counts, light_paths) = (single_counts, packet.len());
    }
    eprintln!(
        "M = {m} test paths on Embree ({} rays, {} of them shadow; {light_paths} light paths): \
         single rays {:.1} ms, packets of 16 {:.1} ms, packet/single {:.3}",
        counts.total(),
        counts.shadow,
        single_s * 1e3,
        packet_s * 1e3,
        packet_s / single_s
    );
}

/// The step targets of stored test paths (where data-driven anchors and path-following
/// generators aim) lie along the directions those paths sampled, on the triangle named;
/// the same check rejects another path's targets. Path-following generators aim
/// their first cone at such a target, as seen from their first vertex.
#[test]
fn step_targets_lie_along_the_sampled_directions() {
    let (scene, accel) = fig5();
    let view = SceneView::new(&scene, accel.as_ref());
    let srt = srt_mixture(&scene);
    let (paths, _) = TestPaths::sample(&view, &srt, FLOOR_PIXEL, 4000, MAX_BOUNCES, 3);
    assert!(paths.len() > 10, "{} light-carrying paths", paths.len());
    // `along(i, k, j)`: path j's k-th step target seen from path i's k-th step.
    let along = |i: usize, k: usize, j: usize| -> Option<bool> {
        let (origin, wi) = paths.step_origin(i, k)?;
        let (target, prim) = paths.step_target(j, k)?;
        let [a, b, c] = scene.mesh.vertices(prim).map(|v| v.as_dvec3());
        let n = (b - a).cross(c - a).normalize();
        let on_triangle = (target - a).dot(n).abs() < 1e-4;
        Some(on_triangle && (target - origin).normalize().dot(wi) > 1.0 - 1e-6)
    };
    let (mut right, mut checked, mut wrong, mut wrong_checked) = (0, 0, 0, 0);
    for i in 0..paths.len() {
        for k in 0..MAX_BOUNCES as usize {
            if let Some(ok) = along(i, k, i) {
                checked += 1;
                right += usize::from(ok);
            }
            if let Some(ok) = along(i, k, (i + 1) % paths.len()) {
                wrong_checked += 1;
                wrong += usize::from(ok);
            }
        }
    }
    assert!(
        checked > paths.len() && right == checked,
        "{right} of {checked}"
    );
    assert!(
        wrong_checked > 10 && wrong * 10 < wrong_checked,
        "{wrong} of {wrong_checked}"
    );
    // A path-following generator's first cone contains a target from its first vertex.
    let config = GaConfig {
        patches: 0.0,
        ..GaConfig::default()
    };
    let mut pool = GenePool::new(&scene, MAX_BOUNCES, &config).with_test_paths(&paths);
    let mut rng = Rng::seed_from_u64(5);
    let gene = pool.path_gene(&mut rng).expect("test paths carry light");
    let DirectionSampler::Anchor(cone) = &gene.generator.steps[0].sampler else {
        panic!("the first step of a path-following generator is an anchor cone");
    };
    let hit = (0..paths.len()).any(|i| {
        paths.step_target(i, 0).is_some_and(|(t, _)| {
            let (origin, _) = paths.step_origin(i, 0).unwrap();
            (t - cone.anchor).length() < 1e-12 && cone.inside(origin, (t - origin).normalize())
        })
    });
    assert!(
        hit,
        "anchor {:?} is no stored path's first target",
        cone.anchor
    );
    // With patches only, its first step is a patch over first-step targets; the same patch
    // shrunk about its centre to a millionth holds none.
    let config = GaConfig {
        patches: 1.0,
        ..GaConfig::default()
    };
    let mut pool = GenePool::new(&scene, MAX_BOUNCES, &config).with_test_paths(&paths);
    let mut rng = Rng::seed_from_u64(6);
    let gene = pool.path_gene(&mut rng).expect("test paths carry light");
    let DirectionSampler::Patch(patch) = gene.generator.steps[0].sampler else {
        panic!("with --patches 1, a path-following generator's first step is a patch");
    };
    let shrunk = PatchSampler {
        half_u: 1e-6 * patch.half_u,
        half_v: 1e-6 * patch.half_v,
        ..patch
    };
    let inside = |p: &PatchSampler| {
        let shape = PatchShape::new(p);
        (0..paths.len())
            .filter(|&i| {
                let (Some((origin, _)), Some((t, _))) =
                    (paths.step_origin(i, 0), paths.step_target(i, 0))
                else {
                    return false;
                };
                shape.patch_density(origin, (t - origin).normalize()) > 0.0
            })
            .count()
    };
    let (held, held_shrunk) = (inside(&patch), inside(&shrunk));
    println!(
        "the patch holds {held} of {} first-step targets",
        paths.len()
    );
    assert!(held >= 5, "the patch holds {held} first-step targets");
    assert_eq!(held_shrunk, 0, "the shrunk patch holds {held_shrunk}");
}

/// A GA pixel's test paths start over its footprint (`plan.footprint`): uniform over the
/// square of `side` pixels centred on the pixel, inside the image. A side of one pixel is
/// the pixel itself, ray for ray (the paper's test paths) — and fails the coverage check.
#[test]
fn footprint_rays_cover_the_square_around_the_pixel() {
    use genpath::genetic::test_paths::{footprint_point, footprint_ray};
    use genpath::sampling::camera_ray;
    let (w, h) = (64, 48);
    let at = (20, 30);
    // Whether 4000 positions drawn with `drawn` fill the square of `side` around `at`: all
    // inside it, some within half a pixel of each edge, and their mean at its centre.
    let covers = |drawn: f32, side: f32, seed: u64| {
        let mut rng = sample_rng(seed, 0, 0);
        let points: Vec<(f32, f32)> = (0..4000)
            .map(|_| footprint_point((w, h), at, drawn, &mut rng))
            .collect();
        let axis = |p: u32, v: &dyn Fn(&(f32, f32)) -> f32| {
            let (lo, hi) = (p as f32 + 0.5 - side / 2.0, p as f32 + 0.5 + side / 2.0);
            let (min, max) = points
                .iter()
                .map(v)
                .fold((f32::MAX, f32::MIN), |(a, b), x| (a.min(x), b.max(x)));
            let mean = points.iter().map(v).sum::<f32>() / points.len() as f32;
            let centred = (mean - (p as f32 + 0.5)).abs() < 0.05 * side;
            min >= lo && max <= hi && min < lo + 0.5 && max > hi - 0.5 && centred
        };
        axis(at.0, &|p| p.0) && axis(at.1, &|p| p.1)
    };
    assert!(covers(16.0, 16.0, 1), "side 16");
    assert!(covers(5.0, 5.0, 2), "side 5");
    assert!(
        !covers(1.0, 16.0, 3),
        "the pixel alone cannot fill the square of 16"
    );
    assert!(!covers(16.0, 5.0, 3), "nor a square of 16 fit in one of 5");
    // Clipped into the image at its corner.
    let mut rng = sample_rng(4, 0, 0);
    for _ in 0..1000 {
        let (x, y) = footprint_point((w, h), (1, 47), 16.0, &mut rng);
        assert!(
            (0.0..w as f32).contains(&x) && (0.0..h as f32).contains(&y),
            "{x}, {y}"
        );
    }
    // A side of at most one pixel: the pixel's own camera rays, bit for bit.
    let (scene, _) = fig5();
    for side in [0.0, 0.5, 1.0] {
        let (mut a, mut b) = (sample_rng(5, 1, 2), sample_rng(5, 1, 2));
        for _ in 0..16 {
            let (r, s) = (
                footprint_ray(&scene.camera, FLOOR_PIXEL, side, &mut a),
                camera_ray(&scene.camera, FLOOR_PIXEL, &mut b),
            );
            assert_eq!((r.origin, r.dir), (s.origin, s.dir), "side {side}");
        }
    }
}
