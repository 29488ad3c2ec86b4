//! The scene, GA settings and checks the tests share.

use super::*;

pub(crate) const SIZE: u32 = 32;
pub(crate) const MAX_BOUNCES: u32 = 5;

pub(crate) fn fig5_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/fig5")
}

pub(crate) fn fig5() -> (Scene, Box<dyn Accel>) {
    fig5_on(AccelKind::default_available())
}

pub(crate) fn fig5_on(kind: AccelKind) -> (Scene, Box<dyn Accel>) {
    fig5_sized(kind, SIZE)
}

pub(crate) fn fig5_sized(kind: AccelKind, size: u32) -> (Scene, Box<dyn Accel>) {
    let mut scene = Scene::load(&fig5_dir().join("scene.toml")).expect("fig5 loads");
    scene.resize(size, size);
    let accel = accel::build(kind, &scene.mesh).expect("accel");
    (scene, accel)
}

/// Shipped scene `name` (`scenes/NAME/scene.toml`) at `size`², on the default back-end.
pub(crate) fn scene_sized(name: &str, size: u32) -> (Scene, Box<dyn Accel>) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenes/{name}/scene.toml"));
    let mut scene = Scene::load(&path).unwrap_or_else(|e| panic!("{name} loads: {e}"));
    scene.resize(size, size);
    let accel = accel::build(AccelKind::default_available(), &scene.mesh).expect("accel");
    (scene, accel)
}

/// The GA of the mixture plan tests: 12 individuals, 8 generations, 3000 test paths.
pub(crate) fn small_mixture_ga() -> GaConfig {
    GaConfig {
        population: 12,
        generations: 8,
        test_paths: 3000,
        ..GaConfig::default()
    }
}

/// A GA small enough for a test, with which fig5's pilot still pays for a guide. Its
/// 10 000 test paths (`GaConfig::default`'s) matter: with 4 000 the evolved guides over-fit
/// and the pilot's cautious gain (`Trial::cautious_gain`) opened fig5's 96² plan (grid 12)
/// on 4 of seeds 1–12; with 10 000, on all 12.
pub(crate) fn small_guide_ga() -> GaConfig {
    GaConfig {
        population: 16,
        generations: 8,
        test_paths: 10_000,
        ..GaConfig::default()
    }
}

/// The back-ends built into this test binary.
pub(crate) fn backends() -> Vec<AccelKind> {
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
pub(crate) const FLOOR_PIXEL: (u32, u32) = (SIZE / 3, SIZE / 2);

pub(crate) fn assert_on_floor(view: &SceneView, (x, y): (u32, u32)) {
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
pub(crate) const EDGE_PIXEL: (u32, u32) = (4, 7);

/// What the camera rays through the corners of pixel `(x, y)` hit: a material name each, or
/// "nothing".
pub(crate) fn corner_hits(view: &SceneView, (x, y): (u32, u32)) -> Vec<String> {
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

pub(crate) fn anchors_mixture(scene: &Scene) -> Mixture {
    let srt_absorption = GaConfig::default().srt_absorption;
    mixture_file::load(
        &fig5_dir().join("anchors.toml"),
        scene,
        MAX_BOUNCES,
        srt_absorption,
    )
    .expect("fig5 anchors load")
}

pub(crate) fn srt_mixture(scene: &Scene) -> Mixture {
    let srt = PathGenerator::srt(
        MAX_BOUNCES,
        GaConfig::default().srt_absorption,
        mixture_file::uniform_light(scene),
    );
    Mixture::new(vec![srt], vec![1.0])
}

/// Every invariant of an individual that keeps the estimator unbiased and finite.
pub(crate) fn check_individual(ind: &Individual, pool: &GenePool, config: &GaConfig) {
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
pub(crate) fn distance_to_triangle(scene: &Scene, prim: u32, p: DVec3) -> f64 {
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
