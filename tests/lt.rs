//! Light tracing (`lt`) estimates what `pt` does on the paths both reach: `pt` restricted to
//! paths that do not go on through a delta lobe at the camera ray's hit
//! (`integrators::pt::NoDeltaFirst`; a light tracer cannot connect through a mirror or
//! smooth glass seen directly). Per block of pixels and channel, the difference of the two
//! means must lie inside a 99.9 % interval, Šidák-corrected over every block and channel of
//! the scene. `pt`'s variance is its film's (independent samples per pixel); `lt`'s comes
//! from independent one-pass renders (a light path splats onto several pixels, so its
//! pixels' variances do not add up to a block's). The must-reject twins (fault injections
//! of feature `testing`): the camera's importance without its `cos⁴ θ`, the light path
//! scattering through the radiance-mode BSDF (no adjoint: no shading-normal correction, and
//! refracted light scaled by `1/η²`), and each emitter's pick taken as another emitter's.
//!
//! And `lt` agrees with Mitsuba 3's light tracer (`ptracer`) on `box.xml` and `lights.xml`
//! (references `scenes/mitsuba/NAME.ptracer.exr` at 64 × the test's samples with their
//! blocks' variance in `NAME.ptracer.json`, made by `scripts/mitsuba_ptracer_references.py`),
//! with the same twins.
//!
//! The default run (the README's test command) covers the twins' scenes: cbox, `lights.xml`,
//! `maps.xml`, and `box.xml` and `lights.xml` against `ptracer`; every other TOML and
//! Mitsuba test scene runs in CI's lane of ignored tests (`.ci/run`: `cargo test … --test lt
//! -- --ignored`), for time.

#![cfg(feature = "testing")]

use genpath::accel::{self, AccelKind};
use genpath::film::Film;
use genpath::integrators::lt::LightTracing;
use genpath::integrators::pt::NoDeltaFirst;
use genpath::integrators::{Integrator, Method, RenderSettings};
use genpath::path::lt::{Fault, LightTracer};
use genpath::path::SceneView;
use genpath::scene::Scene;
use statrs::distribution::{ContinuousCDF, Normal};
use std::path::{Path, PathBuf};

const SIZE: u32 = 32;
const BLOCK: u32 = 8;

fn scene_file(name: &str) -> PathBuf {
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    match name.ends_with(".xml") {
        true => scenes.join(name),
        false => scenes.join(name).join("scene.toml"),
    }
}

fn settings(spp: u32, max_bounces: u32, seed: u64) -> RenderSettings {
    RenderSettings {
        method: Method::Lt,
        spp,
        max_bounces,
        seed,
        progress: false,
        shard: Default::default(),
        control: Default::default(),
        learning: None,
    }
}

/// Per block and channel: a mean and the variance of that mean.
type Blocks = Vec<(f64, f64)>;

/// The block sums of `image(x, y)[c]`, block by block, channel by channel.
fn block_sums(get: impl Fn(u32, u32, usize) -> f64) -> Vec<f64> {
    let mut out = Vec::new();
    for by in (0..SIZE).step_by(BLOCK as usize) {
        for bx in (0..SIZE).step_by(BLOCK as usize) {
            for c in 0..3 {
                let mut sum = 0.0;
                for y in by..by + BLOCK {
                    for x in bx..bx + BLOCK {
                        sum += get(x, y, c);
                    }
                }
                out.push(sum / f64::from(BLOCK * BLOCK));
            }
        }
    }
    out
}

/// A scene of the test suite at the test's size, and the bounces it renders with.
fn load(name: &str) -> (Scene, u32) {
    let mut scene = Scene::load(&scene_file(name)).unwrap();
    scene.resize(SIZE, SIZE);
    let bounces = scene.render.max_bounces.min(6);
    (scene, bounces)
}

/// `pt` restricted to the paths `lt` reaches, at `spp`: its blocks (pixels independent, so
/// their variances add).
fn pt_blocks(scene: &Scene, bounces: u32, spp: u32) -> Blocks {
    let accel = accel::build(AccelKind::default_available(), &scene.mesh).unwrap();
    let view = SceneView::new(scene, accel.as_ref());
    let film: Film = NoDeltaFirst {
        max_bounces: bounces,
    }
    .render(&view, &settings(spp, bounces, 11));
    let means = block_sums(|x, y, c| f64::from(film.image.get(x, y)[c]));
    let n = f64::from(BLOCK * BLOCK);
    let vars = block_sums(|x, y, c| film.variance_of_mean[(y * SIZE + x) as usize][c] / n);
    means.into_iter().zip(vars).collect()
}

/// `lt` (with `fault`) in `passes` independent renders of one sample per pixel: its blocks'
/// means and the variance of those means from their spread over the renders.
fn lt_blocks(scene: &Scene, bounces: u32, passes: u32, fault: Option<Fault>) -> Blocks {
    let accel = accel::build(AccelKind::default_available(), &scene.mesh).unwrap();
    let view = SceneView::new(scene, accel.as_ref());
    let lt = LightTracing {
        tracer: LightTracer {
            fault,
            ..LightTracer::new(bounces)
        },
    };
    let mut sum: Vec<f64> = Vec::new();
    let mut sum_sq: Vec<f64> = Vec::new();
    for pass in 0..passes {
        let film = lt.render(&view, &settings(1, bounces, 1000 + u64::from(pass)));
        let blocks = block_sums(|x, y, c| f64::from(film.image.get(x, y)[c]));
        sum.resize(blocks.len(), 0.0);
        sum_sq.resize(blocks.len(), 0.0);
        for ((s, q), b) in sum.iter_mut().zip(&mut sum_sq).zip(&blocks) {
            *s += b;
            *q += b * b;
        }
    }
    let n = f64::from(passes);
    (sum.iter().zip(&sum_sq))
        .map(|(s, q)| {
            let mean = s / n;
            (mean, ((q - n * mean * mean) / (n - 1.0)).max(0.0) / n)
        })
        .collect()
}

/// Critical |z| of a two-sided 99.9 % interval, Šidák-corrected over `comparisons`.
fn z_critical(comparisons: usize) -> f64 {
    let alpha = 1.0 - 0.999f64.powf(1.0 / comparisons as f64);
    Normal::new(0.0, 1.0)
        .unwrap()
        .inverse_cdf(1.0 - alpha / 2.0)
}

/// The largest |z| over blocks and channels, the critical |z|, and the largest relative
/// standard error of a block that is not black in both.
fn compare(a: &Blocks, b: &Blocks) -> (f64, f64, f64) {
    let (mut z, mut rel) = (0.0f64, 0.0f64);
    for ((ma, va), (mb, vb)) in a.iter().zip(b) {
        let se = (va + vb).sqrt();
        if se > 0.0 {
            z = z.max((ma - mb).abs() / se);
            rel = rel.max(se / ma.abs().max(mb.abs()).max(1e-3));
        } else if ma != mb {
            z = f64::INFINITY;
        }
    }
    (z, z_critical(a.len()), rel)
}

/// `lt` agrees with restricted `pt` on `name`, and its relative standard error is small
/// enough for the agreement to mean something. Returns `pt`'s blocks for the twins.
fn agrees(name: &str, pt_spp: u32, lt_passes: u32) -> (Scene, u32, Blocks) {
    let (scene, bounces) = load(name);
    let pt = pt_blocks(&scene, bounces, pt_spp);
    let lt = lt_blocks(&scene, bounces, lt_passes, None);
    let (z, critical, rel) = compare(&lt, &pt);
    eprintln!("{name}: lt vs pt (no delta first): max |z| {z:.2} (critical {critical:.2}), worst relative se {rel:.4}");
    assert!(
        z <= critical,
        "{name}: lt vs pt: max |z| {z:.2} > {critical:.2}"
    );
    assert!(
        rel < 0.08,
        "{name}: relative standard error {rel:.4} too wide to judge"
    );
    (scene, bounces, pt)
}

/// The twin: `lt` with `fault` is told apart from restricted `pt`.
fn rejects(name: &str, (scene, bounces, pt): &(Scene, u32, Blocks), passes: u32, fault: Fault) {
    let wrong = lt_blocks(scene, *bounces, passes, Some(fault));
    let (z, critical, _) = compare(&wrong, pt);
    eprintln!("{name}: lt with {fault:?}: max |z| {z:.2} (critical {critical:.2})");
    assert!(
        z > critical,
        "{name}: lt with {fault:?} went unnoticed (max |z| {z:.2})"
    );
}

/// cbox (area light, diffuse walls): `lt` agrees, and the importance without its `cos⁴`
/// does not.
#[test]
fn cbox_agrees_and_an_importance_without_cos4_does_not() {
    let fixture = agrees("cbox", 256, 256);
    rejects("cbox", &fixture, 256, Fault::NoCos4);
}

/// Every emitter kind at once (`lights.xml`: an environment map, a point, a directional
/// and an area light, picked by power): `lt` agrees, and each emitter's pick taken as the
/// next one's does not.
#[test]
fn lights_agree_and_a_wrong_emitter_pick_does_not() {
    let fixture = agrees("mitsuba/lights.xml", 256, 256);
    rejects("lights.xml", &fixture, 256, Fault::WrongEmitterPick);
}

/// Rough glass (`roughglass.xml`): `lt` agrees through refraction in the adjoint mode.
/// (Radiance mode is no twin here: its `1/η²` into the glass and `η²` out of it cancel on
/// the paths this scene's camera sees; `maps.xml` is the adjoint's twin.)
#[test]
#[ignore = "slow: CI runs it with --ignored"]
fn roughglass_agrees() {
    agrees("mitsuba/roughglass.xml", 1024, 1024);
}

/// Normal and bump maps (`maps.xml`, shading normals far from the geometric ones): `lt`
/// agrees with the shading-normal correction, and without it (radiance mode) it does not.
#[test]
fn maps_agree_and_no_shading_normal_correction_does_not() {
    let fixture = agrees("mitsuba/maps.xml", 512, 512);
    rejects("maps.xml", &fixture, 512, Fault::NoAdjoint);
}

/// Smooth shading normals (`smooth.xml`): `lt` agrees with the shading-normal correction
/// (on these meshes it changes the image too little for a twin at this size).
#[test]
#[ignore = "slow: CI runs it with --ignored"]
fn smooth_agrees() {
    agrees("mitsuba/smooth.xml", 256, 256);
}

/// Smooth plastics, whose vertices choose between the coat (delta) and the diffuse lobe,
/// and smooth glass (`plastic.xml`; `pt` leaves the coat seen directly out).
#[test]
#[ignore = "slow: CI runs it with --ignored"]
fn plastic_agrees() {
    agrees("mitsuba/plastic.xml", 256, 256);
}

/// Every other TOML test scene (CI's lane of ignored tests), at samples that judge each to
/// a few per cent.
#[test]
#[ignore = "slow: CI runs it with --ignored"]
fn every_toml_scene_agrees() {
    for (name, spp) in [
        ("fig1", 256),
        ("fig5", 8192),
        ("glossy", 1024),
        ("gap", 8192),
        ("shelf", 2048),
        ("window", 1024),
        ("corridor", 1024),
    ] {
        agrees(name, spp, spp);
    }
}

/// Every other Mitsuba test scene (CI's lane of ignored tests).
#[test]
#[ignore = "slow: CI runs it with --ignored"]
fn every_mitsuba_scene_agrees() {
    for (name, spp) in [
        ("box", 256),
        ("env", 8192),
        ("glass", 1024),
        ("legacy", 1024),
        ("mask", 1024),
        ("params", 1024),
        ("rough", 1024),
        ("spheres", 1024),
        ("spot", 1024),
        ("textures", 1024),
    ] {
        agrees(&format!("mitsuba/{name}.xml"), spp, spp);
    }
}

/// `lt` (with `fault`) against Mitsuba's `ptracer` on `scenes/mitsuba/NAME.xml`: the largest
/// |z| over blocks and channels, with the reference's own variance (`NAME.ptracer.json`,
/// from its passes' spread), and the critical |z|.
fn against_ptracer(name: &str, fault: Option<Fault>) -> (f64, f64) {
    let (scene, bounces) = load(&format!("mitsuba/{name}.xml"));
    let file =
        Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenes/mitsuba/{name}.ptracer.exr"));
    let reference = genpath::image::read(&file).unwrap();
    assert_eq!((reference.width, reference.height), (SIZE, SIZE));
    let theirs = block_sums(|x, y, c| f64::from(reference.get(x, y)[c]));
    let ours = lt_blocks(&scene, bounces, 256, fault);
    let json = std::fs::read_to_string(file.with_extension("json")).unwrap();
    let json: serde_json::Value = serde_json::from_str(&json).unwrap();
    let their_var: Vec<f64> = (json["block_variance"].as_array().unwrap().iter())
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert_eq!(their_var.len(), theirs.len());
    let mut z = 0.0f64;
    for (((mean, var), r), r_var) in ours.iter().zip(&theirs).zip(&their_var) {
        let se = (var + r_var).sqrt();
        z = z.max(if se > 0.0 {
            (mean - r).abs() / se
        } else {
            f64::from(u8::from(mean != r)) * f64::INFINITY
        });
    }
    (z, z_critical(ours.len()))
}

/// `lt` agrees with Mitsuba's light tracer on `box.xml` (an area light in a diffuse box), and
/// its importance without `cos⁴` does not.
#[test]
fn box_agrees_with_mitsuba_ptracer_and_no_cos4_does_not() {
    let (z, critical) = against_ptracer("box", None);
    eprintln!("box.xml: lt vs Mitsuba ptracer: max |z| {z:.2} (critical {critical:.2})");
    assert!(
        z <= critical,
        "box.xml: lt vs ptracer: max |z| {z:.2} > {critical:.2}"
    );
    let (z, critical) = against_ptracer("box", Some(Fault::NoCos4));
    eprintln!("box.xml: lt with NoCos4 vs Mitsuba ptracer: max |z| {z:.2}");
    assert!(
        z > critical,
        "box.xml: NoCos4 went unnoticed against ptracer ({z:.2})"
    );
}

/// `lt` agrees with Mitsuba's light tracer on `lights.xml` (an environment map, a point, a
/// directional and an area light), and a wrong emitter pick does not.
#[test]
fn lights_agree_with_mitsuba_ptracer_and_a_wrong_pick_does_not() {
    let (z, critical) = against_ptracer("lights", None);
    eprintln!("lights.xml: lt vs Mitsuba ptracer: max |z| {z:.2} (critical {critical:.2})");
    assert!(
        z <= critical,
        "lights.xml: lt vs ptracer: max |z| {z:.2} > {critical:.2}"
    );
    let (z, critical) = against_ptracer("lights", Some(Fault::WrongEmitterPick));
    eprintln!("lights.xml: lt with WrongEmitterPick vs Mitsuba ptracer: max |z| {z:.2}");
    assert!(
        z > critical,
        "lights.xml: a wrong pick went unnoticed against ptracer ({z:.2})"
    );
}
