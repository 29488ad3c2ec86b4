//! The genetic algorithm on the paper's scene (fig5, small): operator invariants, the
//! per-path generator densities of the test-path store, eq. 10 against a measured second
//! moment, and the GA improving on the srt baseline.

use genpath::accel::{self, Accel, AccelKind, Coherence, Hit, Ray, PACKET_SIZE};
use genpath::genetic::fitness::{second_moment, Evaluator};
use genpath::genetic::individual::{GenePool, Individual, PATCH_HALF_RANGE};
use genpath::genetic::operators::{crossover, mutate};
use genpath::genetic::plan::{GateConfig, Plan, PlanConfig, PlanFor, PlanInputs, PILOT_PIXELS};
use genpath::genetic::population::evolve;
use genpath::genetic::test_paths::TestPaths;
use genpath::genetic::{ChannelWeights, GaConfig};
use genpath::integrators::pg::{
    train_spatial, PlanGuides, TrainingSchedule, FIRST_TRIAL_PASS, LEVELS_KEEP_RATIO,
};
use genpath::integrators::RenderSettings;
use genpath::path::generator::{
    DirectionSampler, PathGenerator, PathVertices, ABSORPTION_MAX, ABSORPTION_MIN,
};
use genpath::path::mixture::{Mixture, MixtureScratch};
use genpath::path::mixture_file::{self, check_generator};
use genpath::path::{RayCounts, SceneView};
use genpath::sampling::anchor::AnchorSampler;
use genpath::sampling::patch::{PatchSampler, PatchShape};
use genpath::sampling::{sample_rng, uniform, Rng};
use genpath::scene::Scene;
use glam::{DVec3, Vec3};
use rand::SeedableRng;
use std::path::{Path, PathBuf};
use std::time::Instant;

const SIZE: u32 = 32;
const MAX_BOUNCES: u32 = 5;

fn fig5_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/fig5")
}

fn fig5() -> (Scene, Box<dyn Accel>) {
    fig5_on(AccelKind::default_available())
}

fn fig5_on(kind: AccelKind) -> (Scene, Box<dyn Accel>) {
    fig5_sized(kind, SIZE)
}

fn fig5_sized(kind: AccelKind, size: u32) -> (Scene, Box<dyn Accel>) {
    let mut scene = Scene::load(&fig5_dir().join("scene.toml")).expect("fig5 loads");
    scene.resize(size, size);
    let accel = accel::build(kind, &scene.mesh).expect("accel");
    (scene, accel)
}

/// A GA small enough for a test, with which fig5's pilot still pays for a guide.
fn small_guide_ga() -> GaConfig {
    GaConfig {
        population: 16,
        generations: 8,
        test_paths: 4000,
        ..GaConfig::default()
    }
}

/// The back-ends built into this test binary.
fn backends() -> Vec<AccelKind> {
    let mut kinds = Vec::new();
    if cfg!(feature = "embree") {
        kinds.push(AccelKind::Embree);
    }
    if cfg!(feature = "obvhs") {
        kinds.push(AccelKind::Bvh);
    }
    kinds
}

/// A pixel on the floor, left of the centre (lit mostly through the red wall).
const FLOOR_PIXEL: (u32, u32) = (SIZE / 3, SIZE / 2);

fn assert_on_floor(view: &SceneView, (x, y): (u32, u32)) {
    let ray = view.scene.camera.ray(x as f32 + 0.5, y as f32 + 0.5);
    let hit = view.trace(&ray, &mut RayCounts::default()).expect("hit");
    assert!(
        hit.p.y.abs() < 1e-4,
        "pixel {x},{y} is not on the floor: {}",
        hit.p
    );
}

/// The pixel holding the far left corner of the floor, `(-1, 0, -1)`: its camera rays hit the
/// floor, the red wall, or nothing (there is no back wall).
const EDGE_PIXEL: (u32, u32) = (4, 7);

/// What the camera rays through the corners of pixel `(x, y)` hit: a material name each, or
/// "nothing".
fn corner_hits(view: &SceneView, (x, y): (u32, u32)) -> Vec<String> {
    let mut seen: Vec<String> = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
        .iter()
        .map(|(dx, dy)| {
            let ray = view.scene.camera.ray(x as f32 + dx, y as f32 + dy);
            view.trace(&ray, &mut RayCounts::default())
                .map_or("nothing".into(), |hit| view.material(hit.prim).name.clone())
        })
        .collect();
    seen.sort();
    seen.dedup();
    seen
}

fn anchors_mixture(scene: &Scene) -> Mixture {
    let srt_absorption = GaConfig::default().srt_absorption;
    mixture_file::load(
        &fig5_dir().join("anchors.toml"),
        scene,
        MAX_BOUNCES,
        srt_absorption,
    )
    .expect("fig5 anchors load")
}

fn srt_mixture(scene: &Scene) -> Mixture {
    let srt = PathGenerator::srt(
        MAX_BOUNCES,
        GaConfig::default().srt_absorption,
        mixture_file::uniform_light(scene),
    );
    Mixture::new(vec![srt], vec![1.0])
}

/// Every invariant of an individual that keeps the estimator unbiased and finite.
fn check_individual(ind: &Individual, pool: &GenePool, config: &GaConfig) {
    let scene = pool.scene;
    assert_eq!(ind.genes.len(), config.generators + 1);
    assert_eq!(ind.genes.len(), ind.weights.len());
    assert_eq!(ind.genes[0], pool.srt(), "the defensive component changed");
    let sum: f64 = ind.weights.iter().sum();
    assert!((sum - 1.0).abs() < 1e-12, "weights sum to {sum}");
    assert!(ind.weights.iter().all(|w| *w >= 0.0 && w.is_finite()));
    assert!(ind.weights[0] >= config.defensive_weight - 1e-12);
    assert!(config.defensive_weight >= mixture_file::W_MIN);
    for gene in &ind.genes[1..] {
        check_generator(&gene.generator, scene).unwrap_or_else(|e| panic!("{e}"));
        let light = gene.generator.light;
        assert!((0.0..1.0).contains(&light.beta));
        for (step, prim) in gene.generator.steps.iter().zip(&gene.anchor_prims) {
            assert!((ABSORPTION_MIN..=ABSORPTION_MAX).contains(&step.absorption));
            match (&step.sampler, prim) {
                (DirectionSampler::Brdf, None) => {}
                (DirectionSampler::Anchor(a), Some(prim)) => {
                    assert!(a.alpha > 0.0 && a.alpha < 1.0, "{}", a.alpha);
                    assert!(a.theta_c > 0.0 && a.theta_c < std::f64::consts::PI);
                    assert!(a.anchor.is_finite());
                    // Data-driven anchors are ray hits, computed in f32.
                    let d = distance_to_triangle(scene, *prim, a.anchor);
                    let tolerance = 1e-6 * f64::from(scene.extent);
                    assert!(
                        d < tolerance,
                        "anchor {} is {d} off triangle {prim}",
                        a.anchor
                    );
                }
                (DirectionSampler::Patch(p), None) => {
                    assert!(p.alpha > 0.0 && p.alpha < 1.0, "{}", p.alpha);
                    assert!(p.center.is_finite());
                    let extent = f64::from(scene.extent);
                    let (lo, hi) = PATCH_HALF_RANGE;
                    for half in [p.half_u, p.half_v] {
                        let h = half.length() / extent;
                        assert!(h >= lo * (1.0 - 1e-9) && h <= hi * (1.0 + 1e-9), "{h}");
                    }
                }
                other => panic!("sampler and anchor triangle disagree: {other:?}"),
            }
        }
    }
}

/// Distance from `p` to its projection on triangle `prim`'s plane plus how far its
/// barycentrics are outside [0, 1] (scaled by the triangle's size): 0 on the triangle.
fn distance_to_triangle(scene: &Scene, prim: u32, p: DVec3) -> f64 {
    let [a, b, c] = scene.mesh.vertices(prim).map(|v| v.as_dvec3());
    let n = (b - a).cross(c - a).normalize();
    let plane = (p - a).dot(n).abs();
    let (e1, e2, d) = (b - a, c - a, p - a);
    let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let det = d11 * d22 - d12 * d12;
    let b1 = (d22 * d.dot(e1) - d12 * d.dot(e2)) / det;
    let b2 = (d11 * d.dot(e2) - d12 * d.dot(e1)) / det;
    let outside = [1.0 - b1 - b2, b1, b2]
        .iter()
        .map(|w| (-w).max(0.0))
        .sum::<f64>();
    plane + outside * e1.length().max(e2.length())
}

#[test]
fn operators_keep_every_invariant() {
    let (scene, accel) = fig5();
    let view = SceneView::new(&scene, accel.as_ref());
    // High rates so that 10⁵ applications exercise every branch many times.
    let config = GaConfig {
        p_cross: 0.8,
        p_sampler_mutate: 0.3,
        p_switch: 0.5,
        p_weight: 0.5,
        p_absorb: 0.5,
        ..GaConfig::default()
    };
    // Test paths, so that data-driven anchors and patches are drawn too.
    let (paths, _) = TestPaths::sample(
        &view,
        &srt_mixture(&scene),
        FLOOR_PIXEL,
        4000,
        MAX_BOUNCES,
        3,
    );
    let mut pool = GenePool::new(&scene, MAX_BOUNCES, &config).with_test_paths(&paths);
    let mut rng = Rng::seed_from_u64(1);
    let mut population: Vec<Individual> = (0..20)
        .map(|_| pool.random_individual(&config, &mut rng))
        .collect();
    population
        .iter()
        .for_each(|i| check_individual(i, &pool, &config));
    let (mut anchors, mut brdfs, mut patches) = (0usize, 0usize, 0usize);
    for round in 0..5000 {
        for i in 0..population.len() {
            let j = (i + 1 + round) % population.len();
            if i != j && uniform(&mut rng) < 0.3 {
                let (mut a, mut b) = (population[i].clone(), population[j].clone());
                crossover(&mut a, &mut b, &config, &mut rng);
                check_individual(&a, &pool, &config);
                check_individual(&b, &pool, &config);
                population[i] = a;
            }
            mutate(&mut population[i], &mut pool, &config, &mut rng);
            check_individual(&population[i], &pool, &config);
        }
        for gene in population.iter().flat_map(|i| &i.genes[1..]) {
            for step in &gene.generator.steps {
                match step.sampler {
                    DirectionSampler::Brdf => brdfs += 1,
                    DirectionSampler::Anchor(_) => anchors += 1,
                    DirectionSampler::Patch(_) => patches += 1,
                }
            }
        }
    }
    // Every sampler type stays in the population (replacement draws any).
    assert!(
        anchors > 0 && brdfs > 0 && patches > 0,
        "{anchors} anchors, {brdfs} brdf, {patches} patches"
    );
}

#[test]
fn stored_paths_give_the_generators_own_densities() {
    let (scene, accel) = fig5();
    let view = SceneView::new(&scene, accel.as_ref());
    let config = GaConfig::default();
    let mut pool = GenePool::new(&scene, MAX_BOUNCES, &config);
    let mut rng = Rng::seed_from_u64(2);
    // Hand-made anchors find light often; random generators exercise every sampler type.
    let anchors = anchors_mixture(&scene);
    let random = pool.random_individual(&config, &mut rng).to_mixture();
    let sampler = Mixture::combine(&[(1.0, &anchors), (1.0, &random)]);
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
    let mut paths = TestPaths::new(MAX_BOUNCES);
    let mut expected = Vec::new();
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
            MAX_BOUNCES,
            &mut rng,
            &mut counts,
            &mut path,
            &mut contributions,
        );
        for c in &contributions {
            paths.push(&view, &path, c, DVec3::ONE);
            expected.push(
                judges
                    .iter()
                    .map(|j| {
                        j.generator
                            .pdf_path(&view, &path, c.len, c.nee, MAX_BOUNCES)
                    })
                    .collect::<Vec<_>>(),
            );
        }
    }
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
                "path {i}, generator {j}: {g} vs {e}"
            );
            nonzero += (e > 0.0) as usize;
        }
    }
    assert!(
        nonzero > paths.len(),
        "densities are mostly zero: {nonzero}"
    );
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

/// Mean of `F²` and the variance of that mean, `F² = Σ_c w_c v_c²` for one sample `v` of
/// eq. 8 at `pixel` with `mixture` (the render loop of one pixel, emission seen directly
/// excluded) and the test paths' channel weights `w`.
fn measured_second_moment(
    view: &SceneView,
    (mixture, weights): (&Mixture, ChannelWeights),
    (x, y): (u32, u32),
    n: u64,
) -> (f64, f64) {
    let camera = &view.scene.camera;
    let mut scratch = MixtureScratch::default();
    let mut counts = RayCounts::default();
    let (mut s2, mut s4) = (0.0, 0.0);
    for s in 0..n {
        let mut rng = sample_rng(99, (y * SIZE + x) as u64, s);
        let ray = camera.ray(x as f32 + uniform(&mut rng), y as f32 + uniform(&mut rng));
        let f2 = match view.trace(&ray, &mut counts) {
            Some(x1) => {
                let v = mixture.estimate(
                    view,
                    ray.origin,
                    x1,
                    MAX_BOUNCES,
                    &mut rng,
                    &mut counts,
                    &mut scratch,
                );
                weights.weigh(v * v)
            }
            None => 0.0,
        };
        s2 += f2;
        s4 += f2 * f2;
    }
    let n = n as f64;
    let mean = s2 / n;
    (mean, (s4 / n - mean * mean) / (n - 1.0))
}

/// Eq. 10 and the variance of that estimate: its terms `F²/(pdf·q)` (0 for paths without
/// light) are i.i.d. over the M test paths.
fn eq10_with_variance(view: &SceneView, paths: &TestPaths, mixture: &Mixture) -> (f64, f64) {
    let v = second_moment(view, paths, mixture);
    // The variance needs the individual terms, which `second_moment` does not expose.
    let mut pdf = vec![0.0; paths.len()];
    let mut one = vec![0.0; paths.len()];
    for (g, w) in mixture.generators.iter().zip(&mixture.weights) {
        paths.generator_pdfs(view, g, &mut one);
        pdf.iter_mut().zip(&one).for_each(|(p, o)| *p += w * o);
    }
    let m = paths.sampled as f64;
    let t2: f64 = paths
        .f2_over_q
        .iter()
        .zip(&pdf)
        .map(|(f, p)| (f / p).powi(2))
        .sum::<f64>()
        / m;
    (v, (t2 - v * v) / (m - 1.0))
}

/// Eq. 10 predicts the second moment of the estimator that is measured by rendering the
/// pixel. Both sides are means of i.i.d. terms with finite variance (each mixture holds the
/// srt component with weight ≥ 1/2, so `F²/(pdf·q) ≤ 2 F²/q²`, and srt's `F/q` is bounded on
/// fig5: BRDF sampling divides out the BRDF, and the light's distance to any lit point is
/// ≥ 0.2), so their difference over its standard error is asymptotically normal: |z| < 4
/// fails by chance with probability 6·10⁻⁵ per comparison.
#[test]
fn eq10_matches_the_measured_second_moment() {
    let (scene, accel) = fig5();
    let view = SceneView::new(&scene, accel.as_ref());
    assert_on_floor(&view, FLOOR_PIXEL);
    let srt = srt_mixture(&scene);
    let (paths, _) = TestPaths::sample(&view, &srt, FLOOR_PIXEL, 2_000_000, MAX_BOUNCES, 5);
    // The anchors with the srt component at weight 1/2: values at most twice srt's, so the
    // fourth moment that the measured side's standard error depends on stays moderate.
    let mut good = anchors_mixture(&scene);
    good.weights = vec![0.5, 0.25, 0.25];
    for (name, mixture) in [("srt", &srt), ("anchors", &good)] {
        let (v, v_var) = eq10_with_variance(&view, &paths, mixture);
        let (measured, m_var) =
            measured_second_moment(&view, (mixture, paths.weights()), FLOOR_PIXEL, 2_000_000);
        let se = (v_var + m_var).sqrt();
        let z = (v - measured) / se;
        eprintln!(
            "{name}: eq. 10 {v:.4e} ± {:.2e}, measured {measured:.4e} ± {:.2e}, z {z:.2}",
            v_var.sqrt(),
            m_var.sqrt()
        );
        assert!(
            z.abs() < 4.0,
            "{name}: eq. 10 {v} vs measured {measured}: z = {z}"
        );
        // Sharp enough to mean something: a 4σ band no wider than ±32 %.
        assert!(
            se < 0.08 * measured,
            "{name}: standard error {se} too wide for {measured}"
        );
    }
}

/// A generator of fig5's anchors file, re-aimed at `anchor` with the same parameters.
fn reaimed(good: &Mixture, anchor: DVec3) -> Mixture {
    let mut bad = good.clone();
    for g in &mut bad.generators[1..] {
        if let DirectionSampler::Anchor(a) = &mut g.steps[0].sampler {
            a.anchor = anchor;
        }
    }
    bad
}

#[test]
fn eq10_ranks_good_anchors_above_bad_ones() {
    let (scene, accel) = fig5();
    let view = SceneView::new(&scene, accel.as_ref());
    let srt = srt_mixture(&scene);
    let (paths, _) = TestPaths::sample(&view, &srt, FLOOR_PIXEL, 20_000, MAX_BOUNCES, 6);
    let good = anchors_mixture(&scene);
    let v_good = second_moment(&view, &paths, &good);
    let v_srt = second_moment(&view, &paths, &srt);
    // The black occluder, and a floor corner far from both walls' lit parts.
    for anchor in [DVec3::new(0.0, 1.8, 0.0), DVec3::new(0.0, 0.0, -1.0)] {
        let v_bad = second_moment(&view, &paths, &reaimed(&good, anchor));
        eprintln!("V: anchors {v_good:.4e}, srt {v_srt:.4e}, aimed at {anchor} {v_bad:.4e}");
        assert!(v_good < 0.5 * v_bad, "good {v_good} vs bad {v_bad}");
    }
    assert!(v_good < 0.5 * v_srt, "good {v_good} vs srt {v_srt}");
}

/// The cached evaluator gives eq. 10 of each individual's own mixture.
#[test]
fn cached_fitness_equals_the_direct_evaluation() {
    let (scene, accel) = fig5();
    let view = SceneView::new(&scene, accel.as_ref());
    let config = GaConfig::default();
    let (paths, _) = TestPaths::sample(
        &view,
        &srt_mixture(&scene),
        FLOOR_PIXEL,
        5000,
        MAX_BOUNCES,
        8,
    );
    let mut pool = GenePool::new(&scene, MAX_BOUNCES, &config);
    let mut rng = Rng::seed_from_u64(9);
    let mut population: Vec<Individual> = (0..10)
        .map(|_| pool.random_individual(&config, &mut rng))
        .collect();
    let mut evaluator = Evaluator::default();
    let mut v = Vec::new();
    // Several generations, so that cached, evicted and reused slots all take part.
    for _ in 0..5 {
        evaluator.evaluate(&view, &paths, &population, &mut v);
        for (ind, &vi) in population.iter().zip(&v) {
            let direct = second_moment(&view, &paths, &ind.to_mixture());
            assert!(
                (vi - direct).abs() <= 1e-12 * direct,
                "cached {vi} vs direct {direct}"
            );
        }
        let copy = population[0].clone();
        for ind in &mut population {
            mutate(ind, &mut pool, &config, &mut rng);
        }
        population[9] = copy;
    }
    assert!(evaluator.generator_evaluations < 5 * 10 * (config.generators as u64 + 1));
}

/// The GA finds generators that beat srt by a clear margin on a floor pixel, on its own test
/// paths and on independent ones; elitism keeps the best V from increasing; and the run is
/// deterministic given the seed.
#[test]
fn ga_improves_on_srt() {
    let (scene, accel) = fig5();
    let view = SceneView::new(&scene, accel.as_ref());
    assert_on_floor(&view, FLOOR_PIXEL);
    let config = GaConfig::default();
    let srt = srt_mixture(&scene);
    let (paths, _) =
        TestPaths::sample(&view, &srt, FLOOR_PIXEL, config.test_paths, MAX_BOUNCES, 10);
    let start = Instant::now();
    let evolution = evolve(&config, &paths, &view, &mut Rng::seed_from_u64(11));
    let elapsed = start.elapsed().as_secs_f64();
    let v_srt = second_moment(&view, &paths, &srt);
    let (mut fresh, _) = TestPaths::sample(&view, &srt, FLOOR_PIXEL, 200_000, MAX_BOUNCES, 12);
    // The variance the GA minimised: the training paths' channel weights.
    fresh.weigh(paths.weights());
    let best = evolution.best.to_mixture();
    let (fresh_best, fresh_srt) = (
        second_moment(&view, &fresh, &best),
        second_moment(&view, &fresh, &srt),
    );
    eprintln!(
        "{} light paths of {}; V srt {v_srt:.4e}, best {:.4e}; on fresh paths srt {fresh_srt:.4e}, best {fresh_best:.4e}",
        paths.len(), paths.sampled, evolution.best_v
    );
    eprintln!(
        "{} individuals, {} generators evaluated in {elapsed:.3} s: {:.0} individuals/s",
        evolution.individual_evaluations,
        evolution.generator_evaluations,
        evolution.individual_evaluations as f64 / elapsed
    );
    for (g, s) in evolution.history.iter().enumerate() {
        eprintln!("generation {g}: best {:.4e}, mean {:.4e}", s.best, s.mean);
    }
    eprintln!("best: {:#?}", evolution.best);
    for w in evolution.history.windows(2) {
        assert!(
            w[1].best <= w[0].best,
            "best V increased: {} -> {}",
            w[0].best,
            w[1].best
        );
    }
    assert_eq!(
        evolution.best_v,
        evolution.history.last().map_or(f64::NAN, |h| h.best)
    );
    assert!(
        evolution.best_v < 0.5 * v_srt,
        "GA {} vs srt {v_srt}",
        evolution.best_v
    );
    // On 103 light-carrying paths the GA overfits: V 0.26 × srt's on its own paths, 0.65 ×
    // on fresh ones (V over the RGB channels with the pixel's weights; with luminance it was
    // below 0.6).
    assert!(
        fresh_best < 0.7 * fresh_srt,
        "fresh paths: GA {fresh_best} vs srt {fresh_srt}"
    );
    let again = evolve(&config, &paths, &view, &mut Rng::seed_from_u64(11));
    assert_eq!(again.best_v.to_bits(), evolution.best_v.to_bits());
    assert_eq!(again.best, evolution.best);
}

#[test]
fn config_defaults_are_valid_and_bad_values_rejected() {
    let config = GaConfig::default();
    config.validate().expect("defaults are valid");
    let text = toml::to_string(&config).expect("serialises");
    assert_eq!(toml::from_str::<GaConfig>(&text).expect("parses"), config);
    assert!(
        toml::from_str::<GaConfig>("populaton = 3").is_err(),
        "unknown field accepted"
    );
    let partial: GaConfig = toml::from_str("population = 7").expect("partial config");
    assert_eq!(partial.population, 7);
    assert_eq!(partial.generations, config.generations);
    for bad in [
        GaConfig {
            population: 0,
            ..config.clone()
        },
        GaConfig {
            elitism: config.population + 1,
            ..config.clone()
        },
        GaConfig {
            p_cross: 1.5,
            ..config.clone()
        },
        GaConfig {
            p_weight: f64::NAN,
            ..config.clone()
        },
        GaConfig {
            defensive_weight: 0.001,
            ..config.clone()
        },
        GaConfig {
            srt_absorption: 1.0,
            ..config.clone()
        },
    ] {
        assert!(bad.validate().is_err(), "{bad:?} accepted");
    }
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

/// With a time limit the plan has already used up, only the gate's pilot evolves. Where the
/// pilot shows that guiding pays (fig5), the cells left without a GA pixel take their evolved
/// neighbours' guides: with a guide they are not `pt` points, which then hold only the
/// low-variance cells, and the pilot's guides reach far beyond their own cells. (With a
/// mixture they would be `pt` points; no shipped scene makes the mixture's pilot pay, see
/// `Plan::build`.)
#[test]
fn cells_the_time_limit_leaves_out_take_their_neighbours_guides() {
    let (scene, accel) = fig5_sized(AccelKind::default_available(), 64);
    let view = SceneView::new(&scene, accel.as_ref());
    let ga = small_guide_ga();
    let config = PlanConfig {
        grid: 8,
        time_limit: Some(0.0),
        ..PlanConfig::default()
    };
    let plan = Plan::build(
        &view,
        &PlanInputs::new(&ga, &config, PlanFor::Guide, MAX_BOUNCES),
        5,
        false,
    )
    .expect("plan");
    let stats = &plan.stats;
    eprintln!(
        "{} GA pixels, {} late, {} pt points, {} low-variance cells",
        plan.pixels.len(),
        stats.time_limited_pixels,
        plan.pt_points.len(),
        stats.low_variance_cells
    );
    assert_eq!(
        stats.gated_pixels, 0,
        "the pilot must pay on fig5 for this test"
    );
    assert_eq!(plan.pixels.len(), PILOT_PIXELS, "only the pilot evolves");
    assert!(stats.time_limited_pixels > 0);
    assert_eq!(plan.pt_points.len(), stats.low_variance_cells);
    let guided = (0..64)
        .flat_map(|y| (0..64).map(move |x| (x, y)))
        .filter(|&(x, y)| plan.local(x, y).is_some())
        .count();
    // Were the late cells `pt` points, a pixel would render guided only where a pilot
    // pixel's weight dominates, about its own 8 × 8 cell: 8 × 64 pixels.
    let cells = PILOT_PIXELS * 64;
    assert!(guided > 2 * cells, "{guided} guided pixels");
}

/// cbox has nothing for a mixture to learn: its pilot fails. On one thread the pilot pixels
/// run in order and stop once the pilot cannot pay (after `PILOT_PIXELS / 2 + 1` failures),
/// no baseline runs (no cell is judged by its variance) and every pixel renders with `pt`,
/// even next to the pilot pixels. The same pilot for a guide runs all its pixels, and without
/// the gate every pixel gets a mixture: the stop and the closure come from the failed pilot.
#[test]
fn a_mixture_pilot_that_cannot_pay_stops_early_and_leaves_pt() {
    let mut scene =
        Scene::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cbox/scene.toml"))
            .expect("cbox loads");
    scene.resize(48, 48);
    let accel = accel::build(AccelKind::default_available(), &scene.mesh).expect("accel");
    let view = SceneView::new(&scene, accel.as_ref());
    let ga = GaConfig {
        population: 12,
        generations: 8,
        test_paths: 3000,
        ..GaConfig::default()
    };
    let config = PlanConfig {
        grid: 8,
        ..PlanConfig::default()
    };
    let one_thread = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool");
    let build = |inputs: PlanInputs| {
        one_thread.install(|| Plan::build(&view, &inputs, 3, false).expect("plan"))
    };
    let mixture = build(PlanInputs::new(&ga, &config, PlanFor::Mixture, MAX_BOUNCES));
    let gains: Vec<f64> = mixture
        .pixels
        .iter()
        .map(|p| p.trial.map_or(0.0, |t| t.gain))
        .collect();
    eprintln!("mixture pilot gains {gains:?}");
    assert!(
        gains.iter().all(|&g| g < 2.0),
        "the pilot must fail on cbox for this test"
    );
    assert_eq!(mixture.pixels.len(), PILOT_PIXELS / 2 + 1);
    let stats = &mixture.stats;
    assert_eq!(
        stats.gated_pixels + mixture.pixels.len() + stats.empty_cells,
        36
    );
    assert!(!stats.baseline_ran);
    assert_eq!(stats.low_variance_cells, 0, "no baseline ran");
    for p in &mixture.pixels {
        assert!(
            mixture.local(p.x, p.y).is_none(),
            "({}, {}) keeps a mixture",
            p.x,
            p.y
        );
    }
    assert!((0..48).all(|y| (0..48).all(|x| mixture.local(x, y).is_none())));

    let guide = build(PlanInputs::new(&ga, &config, PlanFor::Guide, MAX_BOUNCES));
    assert!(
        guide.pixels.len() >= PILOT_PIXELS,
        "a guide's pilot does not stop early"
    );

    let ungated = build(PlanInputs {
        gate: GateConfig { gate: false },
        ..PlanInputs::new(&ga, &config, PlanFor::Mixture, MAX_BOUNCES)
    });
    assert!(ungated.pixels.len() > PILOT_PIXELS);
    assert!(ungated.stats.baseline_ran);
    assert!((0..48).all(|y| (0..48).all(|x| ungated.local(x, y).is_some())));
}

/// `ga-pt`'s training passes try the plan's per-pixel guides against the spatial guide
/// alone, which one pixel in sixteen keeps, and keep them only if the pixels they guide are
/// not noisier. On fig5 the evolved guides win the first trial; the same plan with every
/// evolved first-vertex sampler replaced by a narrow cone aimed at the camera, with 90 % of
/// the weight (a deliberately wrong guide), must lose it, and then no pixel renders with the
/// plan's guides.
#[test]
fn training_passes_keep_the_plans_guides_only_where_they_help() {
    let (scene, accel) = fig5_sized(AccelKind::default_available(), 96);
    let view = SceneView::new(&scene, accel.as_ref());
    let ga = small_guide_ga();
    let config = PlanConfig {
        grid: 12,
        ..PlanConfig::default()
    };
    let plan = Plan::build(
        &view,
        &PlanInputs::new(&ga, &config, PlanFor::Guide, MAX_BOUNCES),
        5,
        false,
    )
    .expect("plan");
    assert!(
        !plan.is_closed(),
        "the pilot must pay on fig5 for this test"
    );
    let settings = RenderSettings {
        method: genpath::integrators::Method::GaPt,
        spp: 64,
        max_bounces: MAX_BOUNCES,
        seed: 9,
        progress: false,
        shard: Default::default(),
    };
    let schedule = TrainingSchedule::Passes(5);
    let trial_of = |plan: &Plan| {
        let training = train_spatial(&view, &settings, schedule, Some(plan));
        let trial = training.guide.stats.guides_trial.expect("a trial ran");
        eprintln!("{trial:?}");
        assert_eq!(
            trial.pass, FIRST_TRIAL_PASS,
            "a clear outcome ends the trials"
        );
        assert!(trial.control_pixels >= 400, "{trial:?}");
        (trial, training.plan_guides)
    };
    let (evolved, levels) = trial_of(&plan);
    assert!(evolved.kept && evolved.ratio < 1.0, "{evolved:?}");
    assert_eq!(levels, PlanGuides::Everywhere);

    let mut wrong = plan.clone();
    let aim = scene.camera.origin.as_dvec3();
    let cone = AnchorSampler::new(aim, 0.05, 0.95).expect("a valid cone");
    for pixel in &mut wrong.pixels {
        // Component 0 is the defensive `srt` generator; the others' first steps go astray,
        // and take 90 % of the weight.
        let mut generators = pixel.mixture.generators.clone();
        for g in generators.iter_mut().skip(1) {
            g.steps[0].sampler = DirectionSampler::Anchor(cone);
        }
        let others = (generators.len() - 1) as f64;
        let mut weights = vec![0.9 / others; generators.len()];
        weights[0] = 0.1;
        pixel.mixture = Mixture::new(generators, weights);
    }
    let (astray, levels) = trial_of(&wrong);
    assert!(
        !astray.kept && astray.ratio > LEVELS_KEEP_RATIO,
        "{astray:?}"
    );
    assert_eq!(levels, PlanGuides::Nowhere);
}
