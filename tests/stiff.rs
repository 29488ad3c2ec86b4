//! The stiff and extreme catalogue (design §8, `scenes/stiff/`, made by
//! `scripts/make_stiff_scenes.py`): on every scene, every method renders without a NaN,
//! infinite or negative pixel, every sampled density is finite and positive, every fitness
//! value is finite, and the image means agree with `pt`'s (`genpath check`). The check must
//! fail on a biased estimator. On rough glass that is a delta in all but name (roughness
//! 1e-4, index 1.0001) the image means of the estimators that find light through it by
//! light samples alone are not compared (see `NEAR_DELTA_GLASS`). Unit cases push generator
//! parameters to their bounds. A tiny bright sun in an environment map (`sun_env`: one
//! pixel of 2e5 in a sky of 0.2) converges: `pt`'s standard error falls as 1/√spp and its
//! means at 16 and 256 spp agree. Huge and single-texel textures (`textures`: an 8192²
//! bitmap alternating texel by texel, a 1×1 one) pass the check; the same scene with its
//! texture file missing fails to load, naming the file and the line.

// The must-reject twins use the fault injections of feature `testing`.
#![cfg(feature = "testing")]

use genpath::accel::{self, Accel, AccelKind};
use genpath::check::{check, CheckConfig};
use genpath::integrators::mixture::MixtureIntegrator;
use genpath::integrators::pt::PathTracing;
use genpath::integrators::{Integrator, Method, RenderSettings};
use genpath::path::generator::{
    DirectionSampler, Nee, PathGenerator, PathVertices, Step, ABSORPTION_MAX, ABSORPTION_MIN,
};
use genpath::path::mixture::Mixture;
use genpath::path::{mixture_file, RayCounts, SceneView};
use genpath::sampling::anchor::AnchorSampler;
use genpath::sampling::light_point::{LightPointSampler, LightRegion};
use genpath::sampling::{sample_rng, uniform};
use genpath::scene::Scene;
use glam::DVec3;
use std::path::{Path, PathBuf};

const SCENES: [&str; 17] = [
    "tiny_light",
    "grazing_light",
    "phong_1e4",
    "scale_1e-4",
    "scale_1e5",
    "slivers",
    "coincident",
    "long_room",
    "mirror",
    "rough_1e-4",
    "rough_1",
    "rough_glass_1e-4",
    "rough_glass_1",
    "rough_glass_ior_1",
    "sun_env",
    "textures",
    "plastic",
];

/// The scene file of stiff scene `name`: its `scene.xml` (the microfacet cases, rough glass
/// included, which MTL cannot describe, and the environment map's), else its `scene.toml`.
fn stiff(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes/stiff")
        .join(name);
    match dir.join("scene.xml") {
        xml if xml.exists() => xml,
        _ => dir.join("scene.toml"),
    }
}

fn load(name: &str, size: u32) -> (Scene, Box<dyn Accel>) {
    let mut scene = Scene::load(&stiff(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
    scene.resize(size, size);
    let accel = accel::build(AccelKind::default_available(), &scene.mesh).unwrap();
    (scene, accel)
}

/// The scenes whose rough glass is a delta in all but name (roughness 1e-4; index 1.0001,
/// whose refraction lobe is about `(η − 1) α` wide), and the estimators that find light
/// reached through such glass by light samples alone (`nee-only`, and the end-only
/// estimators of `srt` and `ga`, which count emission a direction finds only through a
/// delta vertex), and light tracing (`lt`, which sees the glass only through its
/// connections to the camera, each a sample of that lobe): unbiased, but a light sample or a
/// connection lands in a lobe 1e-4 wide almost never, so at the check's 64 spp they miss
/// the light seen and the caustics cast through the glass (some 30 % of these images).
/// Their image means are not compared there; everything else is, every other method's mean
/// included.
const NEAR_DELTA_GLASS: [&str; 2] = ["rough_glass_1e-4", "rough_glass_ior_1"];
const LIGHT_SAMPLES_ALONE: [&str; 4] = ["nee-only", "srt:nee=end", "ga:nee=end", "lt"];

/// Whether `failure` of scene `name`'s check is one [`NEAR_DELTA_GLASS`] explains.
fn near_delta_miss(name: &str, failure: &str) -> bool {
    NEAR_DELTA_GLASS.contains(&name)
        && (failure.contains("image mean differs from pt's")
            || failure.contains("image mean differs from pt:no-delta-first's"))
        && LIGHT_SAMPLES_ALONE
            .iter()
            .any(|m| failure.starts_with(&format!("{m}:")))
}

#[test]
fn every_stiff_scene_passes_the_check() {
    let mut failed = Vec::new();
    for name in SCENES {
        let (scene, accel) = load(name, 24);
        let view = SceneView::new(&scene, accel.as_ref());
        let report = check(&view, &CheckConfig::new(64, 5, 1)).unwrap();
        let compared = report.methods.iter().filter(|m| {
            !(NEAR_DELTA_GLASS.contains(&name) && LIGHT_SAMPLES_ALONE.contains(&m.method.as_str()))
        });
        eprintln!(
            "{name:<14} bad pixels {:?}  max |z| {:.2}  pdf [{:.2e}, {:.2e}] bad {}  fitness bad {}",
            report.methods.iter().map(|m| m.bad_pixels).collect::<Vec<_>>(),
            compared.map(|m| m.z_vs_pt).fold(0.0, f64::max),
            report.pdf_min,
            report.pdf_max,
            report.pdf_bad,
            report.fitness_bad
        );
        assert!(report.pdf_samples > 1000, "{name}: too few densities seen");
        for f in &report.failures {
            if near_delta_miss(name, f) {
                eprintln!("{name}: not compared (see NEAR_DELTA_GLASS): {f}");
            } else {
                failed.push(format!("{name}: {f}"));
            }
        }
    }
    assert!(failed.is_empty(), "{}", failed.join("\n"));
}

#[test]
fn the_check_rejects_a_biased_estimator() {
    let (scene, accel) = load("coincident", 24);
    let view = SceneView::new(&scene, accel.as_ref());
    // srt, its density scaled by 1.5 when evaluated, rendered as `mixture`.
    let mut config = CheckConfig::new(64, 5, 1);
    let srt = mixture_file::srt(
        &scene,
        5,
        config.methods.srt.absorption(config.methods.srt.nee),
    );
    config.methods.loaded_mixture = Some(srt.with_pdf_error(0, 1.5));
    let report = check(&view, &config).unwrap();
    assert!(!report.passed(), "a density off by 50 % went unnoticed");
    assert!(
        report.failures.iter().any(|f| f.starts_with("mixture:")),
        "{:?}",
        report.failures
    );
}

/// Generators at the bounds of every parameter: cones of 1e-7 rad and π − 1e-7, α and β
/// next to 0 and 1, absorptions at their limits, weights of 1e-12. No bad pixel, and every
/// sampled density finite and positive.
#[test]
fn generators_at_their_bounds_stay_finite() {
    let (scene, accel) = load("tiny_light", 16);
    let view = SceneView::new(&scene, accel.as_ref());
    let light_prim = scene.emitters.prims[0];
    let light = |beta| LightPointSampler {
        region: LightRegion {
            prim: light_prim,
            level: 16,
            cell: 7,
        },
        beta,
    };
    let anchor = |theta, alpha, a| Step {
        sampler: DirectionSampler::Anchor(
            AnchorSampler::new(DVec3::new(0.0, 1.9, 0.0), theta, alpha).unwrap(),
        ),
        absorption: a,
    };
    let extremes = vec![
        PathGenerator {
            steps: vec![
                anchor(1e-7, 1.0 - 1e-12, ABSORPTION_MIN),
                anchor(std::f64::consts::PI - 1e-7, 1e-12, ABSORPTION_MAX),
            ],
            light: light(1.0 - 1e-12),
        },
        PathGenerator {
            steps: vec![
                anchor(1e-7, 1e-12, ABSORPTION_MAX),
                Step {
                    sampler: DirectionSampler::Brdf,
                    absorption: ABSORPTION_MIN,
                },
            ],
            light: light(0.0),
        },
    ];
    let srt = PathGenerator::srt(5, 0.5, mixture_file::uniform_light(&scene));
    let mut generators = vec![srt];
    generators.extend(extremes);
    let cases = [
        vec![0.5, 0.25, 0.25],
        vec![1.0, 1e-12, 1e-12],
        vec![0.01, 0.99 - 1e-12, 1e-12],
    ];
    for (weights, nee) in cases.iter().flat_map(|w| [(w, Nee::Every), (w, Nee::End)]) {
        let mixture = Mixture::new(generators.clone(), weights.clone()).with_nee(nee);
        let settings = RenderSettings {
            method: Method::Mixture,
            spp: 32,
            max_bounces: 5,
            seed: 2,
            progress: false,
            shard: Default::default(),
            control: Default::default(),
            learning: None,
        };
        let integrator = MixtureIntegrator {
            mixture: mixture.clone(),
            max_bounces: 5,
        };
        let film = integrator.render(&view, &settings);
        let bad = film
            .image
            .pixels
            .iter()
            .flatten()
            .filter(|c| !c.is_finite() || **c < 0.0)
            .count();
        assert_eq!(bad, 0, "weights {weights:?}, {nee:?}");
        // Sampled densities of each generator, and the mixture density of each path.
        let mut path = PathVertices::default();
        let mut contributions = Vec::new();
        let mut counts = RayCounts::default();
        let mut seen = 0;
        for (gi, g) in mixture.generators.iter().enumerate() {
            for j in 0..2000u64 {
                let mut rng = sample_rng(9, gi as u64, j);
                let ray = scene
                    .camera
                    .ray(8.0 + uniform(&mut rng), 8.0 + uniform(&mut rng));
                let Some(x1) = view.trace(&ray, &mut counts) else {
                    continue;
                };
                contributions.clear();
                g.sample_path(
                    &view,
                    ray.origin,
                    x1,
                    (5, mixture.nee),
                    &mut rng,
                    &mut counts,
                    &mut path,
                    &mut contributions,
                );
                let sampled = path
                    .vertices
                    .iter()
                    .filter(|v| !v.delta && v.wi != glam::Vec3::ZERO)
                    .map(|v| v.pdf_sampled)
                    .chain(path.light.map(|l| l.pdf_sampled))
                    .chain(
                        contributions
                            .iter()
                            .filter_map(|c| c.light)
                            .map(|l| l.pdf_sampled),
                    );
                for pdf in sampled.chain(
                    contributions
                        .iter()
                        .map(|c| mixture.pdf_path(&view, &path, c, 5)),
                ) {
                    assert!(
                        pdf.is_finite() && pdf > 0.0,
                        "generator {gi}: density {pdf}"
                    );
                    seen += 1;
                }
            }
        }
        assert!(seen > 1000, "{seen} densities");
    }
}

/// The tiny bright sun in an environment map (`sun_env`): `pt` at 16, 64 and 256 spp gives
/// no NaN, infinite or negative pixel, the standard error of its image mean falls as 1/√spp
/// (a heavy tail, a sun that light sampling missed, would keep it up), and its means agree.
#[test]
fn a_tiny_sun_in_an_environment_map_converges() {
    let (scene, accel) = load("sun_env", 24);
    let view = SceneView::new(&scene, accel.as_ref());
    let mut stats = Vec::new();
    for spp in [16, 64, 256] {
        let settings = RenderSettings {
            method: Method::Pt,
            spp,
            max_bounces: 5,
            seed: 5,
            progress: false,
            shard: Default::default(),
            control: Default::default(),
            learning: None,
        };
        let film = PathTracing { max_bounces: 5 }.render(&view, &settings);
        let pixels = &film.image.pixels;
        assert!(pixels.iter().flatten().all(|c| c.is_finite() && *c >= 0.0));
        let n = pixels.len() as f64;
        let mean = pixels.iter().map(|p| f64::from(p[0])).sum::<f64>() / n;
        let se = film
            .variance_of_mean
            .iter()
            .map(|v| v[0])
            .sum::<f64>()
            .sqrt()
            / n;
        eprintln!("sun_env pt {spp} spp: mean {mean:.4} ± {se:.4}");
        stats.push((mean, se));
    }
    let ((m16, se16), (m256, se256)) = (stats[0], stats[2]);
    assert!(se256 < 0.35 * se16, "{se16} at 16 spp, {se256} at 256");
    let z = (m16 - m256).abs() / (se16 * se16 + se256 * se256).sqrt();
    assert!(
        z < 4.0,
        "means {m16} and {m256} differ by {z:.1} standard errors"
    );
}

/// The `textures` scene with its floor's texture file missing: an error naming the missing
/// file and the scene file's line, not a panic (what `genpath check` and `render` print).
#[test]
fn a_missing_texture_names_its_file_and_line() {
    let defines = [("floor".to_string(), "no_such_texture.png".to_string())];
    let error = Scene::load_with(&stiff("textures"), &defines)
        .unwrap_err()
        .to_string();
    assert!(
        error.contains("no_such_texture.png") && error.contains("scene.xml:16"),
        "{error}"
    );
}
