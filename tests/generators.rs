//! `PathGenerator::pdf_path` (and, with next-event estimation at every vertex, the density
//! of the technique that sampled a path, `PathGenerator::pdf_techniques`), evaluated from the
//! stored vertices alone, equals the product of the densities used while the path was
//! sampled, for paths of every generator type (BRDF-only `srt`, anchor-point, with a
//! light-point region), in a diffuse scene, in a scene with Phong lobes and a mirror, and
//! under an environment (`scenes/mitsuba/env.xml`: paths that escape to it, whose density is
//! their directions' at every vertex).

use genpath::accel::{self, AccelKind};
use genpath::path::generator::{
    Contribution, DirectionSampler, Nee, PathGenerator, PathVertices, Step, ABSORPTION_MIN,
    SRT_ABSORPTION, SRT_ABSORPTION_NEE_EVERY, SRT_ROULETTE_FROM,
};
use genpath::path::{mixture_file, RayCounts, SceneView};
use genpath::sampling::anchor::AnchorSampler;
use genpath::sampling::{sample_rng, uniform};
use genpath::scene::Scene;
use glam::DVec3;
use std::path::Path;

fn load(name: &str) -> Scene {
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let path = match name.strip_suffix(".xml") {
        Some(_) => scenes.join("mitsuba").join(name),
        None => scenes.join(name).join("scene.toml"),
    };
    let mut scene = Scene::load(&path).unwrap();
    scene.resize(32, 32);
    scene
}

fn generators(scene: &Scene) -> Vec<PathGenerator> {
    let light = mixture_file::uniform_light(scene);
    let c = scene
        .mesh
        .positions
        .iter()
        .fold(DVec3::ZERO, |s, p| s + p.as_dvec3())
        / scene.mesh.positions.len() as f64;
    let anchor = |offset: f64, theta_c: f64, alpha: f64| {
        DirectionSampler::Anchor(
            AnchorSampler::new(c + DVec3::new(offset, 0.3, 0.0), theta_c, alpha).unwrap(),
        )
    };
    let mut focused = light;
    focused.beta = 0.7;
    vec![
        PathGenerator::srt(5, 0.4, light),
        PathGenerator {
            steps: vec![
                Step {
                    sampler: anchor(-0.5, 0.4, 0.9),
                    absorption: 0.1,
                },
                Step {
                    sampler: DirectionSampler::Brdf,
                    absorption: 0.8,
                },
                Step {
                    sampler: anchor(0.5, 1e-3, 0.2),
                    absorption: 0.5,
                },
            ],
            light: focused,
        },
        // No absorption before step 5, 0.1 from there: srt's default with NEE everywhere.
        PathGenerator::srt(8, Nee::Every.default_srt_absorption(), light),
    ]
}

fn relative_difference(a: f64, b: f64) -> f64 {
    (a - b).abs() / a.abs().max(b.abs()).max(f64::MIN_POSITIVE)
}

/// The product of the densities `g` sampled contribution `c` of `path` with, and the same
/// density as `g` evaluates it from the stored vertices.
fn sampled_and_evaluated(
    view: &SceneView,
    g: &PathGenerator,
    path: &PathVertices,
    c: &Contribution,
    nee: Nee,
) -> (f64, f64) {
    if nee == Nee::End {
        let scattering = if c.nee { c.len - 1 } else { c.len };
        let mut product: f64 = path.vertices[..scattering]
            .iter()
            .map(|v| v.pdf_sampled)
            .product();
        if c.nee {
            product *= path.light.unwrap().pdf_sampled;
        }
        return (product, g.pdf_path(view, path, c.len, c.nee, 5));
    }
    let (dir, light) = g.pdf_techniques(view, path, c, 5);
    let Some(end) = c.light else {
        // Through a delta last vertex: directions only, the last one of density 1.
        let product = path.vertices[..c.len]
            .iter()
            .map(|v| v.pdf_sampled)
            .product();
        return (product, dir);
    };
    let product: f64 = path.vertices[..c.len - 1]
        .iter()
        .map(|v| v.pdf_sampled)
        .product();
    if c.nee {
        // The light point's area density, as `pdf_techniques` converts it.
        (product * end.pdf_sampled * end.area_to_solid_angle, light)
    } else {
        (product * end.pdf_sampled, dir)
    }
}

/// The contributions checked, and how many of them escaped to the environment.
fn check_scene(name: &str, nee: Nee) -> (usize, usize) {
    let scene = load(name);
    let accel = accel::build(AccelKind::default_available(), &scene.mesh).unwrap();
    let view = SceneView::new(&scene, accel.as_ref());
    let mut counts = RayCounts::default();
    let mut path = PathVertices::default();
    let (mut checked, mut escaped) = (0, 0);
    for (gi, g) in generators(&scene).iter().enumerate() {
        for i in 0..16 * 32 * 32 {
            let pixel = i % (32 * 32);
            let mut rng = sample_rng(5, pixel, (i / (32 * 32)) * 2 + gi as u64);
            let (x, y) = ((pixel % 32) as f32, (pixel / 32) as f32);
            let ray = scene
                .camera
                .ray(x + uniform(&mut rng), y + uniform(&mut rng));
            let Some(x1) = view.trace(&ray, &mut counts) else {
                continue;
            };
            let mut contributions: Vec<Contribution> = Vec::new();
            g.sample_path(
                &view,
                ray.origin,
                x1,
                (5, nee),
                &mut rng,
                &mut counts,
                &mut path,
                &mut contributions,
            );
            for c in &contributions {
                let (product, evaluated) = sampled_and_evaluated(&view, g, &path, c, nee);
                assert!(
                    product > 0.0 && product.is_finite(),
                    "{name}: sampled density {product}"
                );
                assert!(
                    relative_difference(product, evaluated) <= 1e-9,
                    "{name} {nee:?}, generator {gi}, pixel {pixel}: sampled {product:e} vs evaluated {evaluated:e}"
                );
                checked += 1;
                escaped += usize::from(c.escaped);
            }
        }
    }
    (checked, escaped)
}

#[test]
fn pdf_path_matches_the_sampling_densities() {
    for name in ["fig5", "glossy", "env.xml"] {
        for nee in [Nee::End, Nee::Every] {
            let (checked, escaped) = check_scene(name, nee);
            assert!(
                checked > 200,
                "{name} {nee:?}: only {checked} light-carrying paths checked"
            );
            assert_eq!(
                escaped > 200,
                name == "env.xml",
                "{name} {nee:?}: {escaped}"
            );
        }
    }
}

#[test]
fn pdf_path_of_another_generator_differs() {
    // Evaluating a path under a generator that did not sample it gives that generator's own
    // density: for the anchor generator against the srt one it must differ somewhere.
    let scene = load("fig5");
    let accel = accel::build(AccelKind::default_available(), &scene.mesh).unwrap();
    let view = SceneView::new(&scene, accel.as_ref());
    let [srt, anchored, _] = <[PathGenerator; 3]>::try_from(generators(&scene)).unwrap();
    let mut counts = RayCounts::default();
    let mut path = PathVertices::default();
    let mut differ = 0;
    for i in 0..16 * 32 * 32 {
        let pixel = i % (32 * 32);
        let mut rng = sample_rng(9, pixel, i / (32 * 32));
        let ray = scene
            .camera
            .ray((pixel % 32) as f32 + 0.5, (pixel / 32) as f32 + 0.5);
        let Some(x1) = view.trace(&ray, &mut counts) else {
            continue;
        };
        let mut contributions = Vec::new();
        srt.sample_path(
            &view,
            ray.origin,
            x1,
            (5, Nee::End),
            &mut rng,
            &mut counts,
            &mut path,
            &mut contributions,
        );
        for c in &contributions {
            let own = srt.pdf_path(&view, &path, c.len, c.nee, 5);
            let other = anchored.pdf_path(&view, &path, c.len, c.nee, 5);
            assert!(other.is_finite() && other >= 0.0);
            if relative_difference(own, other) > 1e-3 {
                differ += 1;
            }
        }
    }
    assert!(
        differ > 10,
        "only {differ} paths had a different density under another generator"
    );
}

/// `srt`'s default absorption with NEE at every vertex does not absorb before step
/// `SRT_ROULETTE_FROM` (as `pt`'s roulette), then absorbs `SRT_ABSORPTION_NEE_EVERY`; with
/// NEE at the end alone, and as a plain number, it is the same at every step.
#[test]
fn srt_absorbs_from_the_roulette_step_with_nee_everywhere() {
    let scene = load("cbox");
    let light = mixture_file::uniform_light(&scene);
    let absorptions = |g: PathGenerator| g.steps.iter().map(|s| s.absorption).collect::<Vec<_>>();
    let every = absorptions(PathGenerator::srt(
        8,
        Nee::Every.default_srt_absorption(),
        light,
    ));
    let mut expected = vec![ABSORPTION_MIN; SRT_ROULETTE_FROM];
    expected.resize(8, SRT_ABSORPTION_NEE_EVERY);
    assert_eq!(every, expected);
    let end = absorptions(PathGenerator::srt(
        8,
        Nee::End.default_srt_absorption(),
        light,
    ));
    assert_eq!(end, vec![SRT_ABSORPTION; 8]);
    assert_eq!(absorptions(PathGenerator::srt(3, 0.3, light)), vec![0.3; 3]);
    for g in generators(&scene) {
        mixture_file::check_generator(&g, &scene).unwrap();
    }
}
