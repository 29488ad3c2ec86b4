//! Mitsuba 3 XML scenes: genpath's `pt` against Mitsuba 3's own render of the same file
//! (`scenes/mitsuba/*.ref.exr`, rendered by `scripts/mitsuba_reference.py` at 64 × this
//! test's samples), per block of pixels inside a 99.9 % interval (Šidák-corrected), with a
//! must-reject twin: for `box.xml` the same render mirrored left-right (a camera frame with
//! +x to the right instead of Mitsuba's left), for `glass.xml` (a `dielectric` cube and a
//! `thindielectric` pane) a render with the cube's index of refraction 3 % off, for
//! `env.xml` (a `constant` emitter and a small area light) a render with the sky's radiance
//! 3 % off, for `lights.xml` (an `envmap`, a `point`, a `directional` and an area light) a
//! render with the map's scale 3 % off and one with it turned by 10°, for `spheres.xml` (analytic spheres, glass, diffuse and emitting, and a disk
//! light) a render with the emitting sphere's radius 3 % off, for `smooth.xml` (smooth-shaded
//! meshes) a render with `face_normals`, for `legacy.xml` (Mitsuba 0.6's format, upgraded;
//! `<include>`, `<alias>`, `fovAxis`, `nearClip`) a render with the field of view 3 % wide,
//! for `params.xml` (`<matrix>`, `focal_length`, `far_clip`, `<path>`, a serialized file
//! with `flip_normals`, a conductor's `eta`/`k`) a render with a 3 × 3 matrix transposed,
//! for `rough.xml` (rough conductors and a rough plastic) the other distribution or the
//! anisotropy exchanged, for `roughglass.xml` (`roughdielectric`, GGX and Beckmann) the
//! roughnesses exchanged or a sphere's normals flipped, for `textures.xml` a texture upside
//! down or not sRGB-decoded, for `maps.xml` (`normalmap` and `bumpmap`) the normal map's
//! green channel flipped or the bump scale 30 % off, for `mask.xml` (`mask`) the opacities
//! inverted or shadow rays stopped by every mask, for `plastic.xml` (`plastic`, and a
//! `roughdielectric` with textured transmittance) the floor's `nonlinear` flipped or the
//! pane's bitmap not decoded; and `hide_emitters`. Vertex normals and texture
//! coordinates as Mitsuba places them. And the
//! mesh formats: ASCII and binary PLY and Mitsuba's serialized format give the same
//! triangles; and the glass's indices as Mitsuba reads them.

use flate2::write::ZlibEncoder;
use genpath::accel::{self, AccelKind};
use genpath::film::Film;
use genpath::image::Image;
use genpath::integrators::pt::PathTracing;
use genpath::integrators::{Integrator, Method, RenderSettings};
use genpath::path::SceneView;
use genpath::scene::{LightSampler, Scene};
use glam::Vec3;
use statrs::distribution::{ContinuousCDF, Normal};
use std::io::Write;
use std::path::{Path, PathBuf};

const SPP: u32 = 256;
const BLOCK: u32 = 8;

fn scene_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes/mitsuba")
        .join(name)
}

/// `pt`'s render with Mitsuba's uniform light picking (not the default `auto`, which takes
/// the light tree on scenes of several lights): the agreement tests take the reference's
/// variance to be the render's over 64, true only of the same estimator, and the tree's
/// variance is below Mitsuba's (spot.xml: 0.31 × the relMSE), so that the reference's own
/// noise would show as disagreement. The tree is checked against this render instead.
fn render(scene: &Scene, spp: u32) -> Film {
    render_with(scene, spp, |view| {
        view.with_light_sampler(LightSampler::Uniform)
    })
}

/// [`render`] with the view changed by `lit` (its light sampler, a fault injected).
fn render_with(scene: &Scene, spp: u32, lit: impl Fn(SceneView) -> SceneView) -> Film {
    let accel = accel::build(AccelKind::default_available(), &scene.mesh).unwrap();
    let view = lit(SceneView::new(scene, accel.as_ref()));
    let settings = RenderSettings {
        method: Method::Pt,
        spp,
        max_bounces: scene.render.max_bounces,
        seed: 3,
        progress: false,
        shard: Default::default(),
        control: Default::default(),
        learning: None,
    };
    PathTracing {
        max_bounces: scene.render.max_bounces,
    }
    .render(&view, &settings)
}

/// Critical |z| of a two-sided 99.9 % interval, Šidák-corrected over `comparisons`.
fn z_critical(comparisons: usize) -> f64 {
    let alpha = 1.0 - 0.999f64.powf(1.0 / comparisons as f64);
    Normal::new(0.0, 1.0)
        .unwrap()
        .inverse_cdf(1.0 - alpha / 2.0)
}

/// The largest |z| over blocks and channels of genpath's film (mirrored left-right when
/// `mirrored`) against the reference, and the number of comparisons.
fn max_z(film: &Film, reference: &Image, mirrored: bool) -> (f64, usize) {
    let z = block_z(film, reference, mirrored);
    (z.iter().fold(0.0f64, |m, &z| m.max(z)), z.len())
}

/// |z| of each block and channel of genpath's film (mirrored left-right when `mirrored`)
/// against the reference, whose own variance is genpath's over 64 (it has 64 × the
/// samples). A block of zero variance (all of it on a light), or of a standard error below
/// the f32 rounding of the reference, has |z| 0 where it equals the reference up to that
/// rounding (of its average over passes), else ∞.
fn block_z(film: &Film, reference: &Image, mirrored: bool) -> Vec<f64> {
    let (w, h) = (reference.width, reference.height);
    let mut out = Vec::new();
    for by in (0..h).step_by(BLOCK as usize) {
        for bx in (0..w).step_by(BLOCK as usize) {
            for c in 0..3 {
                let (mut ours, mut var, mut theirs) = (0.0, 0.0, 0.0);
                for y in by..by + BLOCK {
                    for x in bx..bx + BLOCK {
                        let xs = if mirrored { w - 1 - x } else { x };
                        ours += f64::from(film.image.get(xs, y)[c]);
                        var += film.variance_of_mean[(y * w + xs) as usize][c];
                        theirs += f64::from(reference.get(x, y)[c]);
                    }
                }
                let k = f64::from(BLOCK * BLOCK);
                let se = (var * (1.0 + 1.0 / 64.0)).sqrt() / k;
                let diff = (ours - theirs).abs() / k;
                // Below the f32 rounding of the reference's average (a block that sees a
                // constant stretch of an environment map), the standard error says nothing.
                let rounding = 1e-6 * theirs.abs() / k;
                out.push(if se > rounding {
                    diff / se
                } else if diff < 1e-5 * (theirs.abs() / k).max(0.1) {
                    0.0
                } else {
                    f64::INFINITY
                });
            }
        }
    }
    out
}

/// `pt`'s render of `scene` (the file `scenes/mitsuba/NAME`) at `spp` against NAME's
/// Mitsuba reference (`NAME.ref.exr`): of one size, and every block inside its interval.
/// Returns the render, the reference, and the largest |z| with its critical value.
fn agrees_with_reference(name: &str, scene: &Scene, spp: u32) -> (Film, Image, (f64, f64)) {
    let reference = genpath::image::read(&scene_path(&name.replace(".xml", ".ref.exr"))).unwrap();
    assert_eq!(
        (scene.camera.width, scene.camera.height),
        (reference.width, reference.height)
    );
    let film = render(scene, spp);
    let (z, n) = max_z(&film, &reference, false);
    let critical = z_critical(n);
    assert!(z < critical, "{name}: max |z| {z:.2} ≥ {critical:.2}");
    (film, reference, (z, critical))
}

/// The must-reject twin of [`agrees_with_reference`]: the file NAME loaded with `defines`
/// (a deliberate error, `what`) and rendered alike must be outside the interval somewhere.
fn twin_is_rejected(
    name: &str,
    defines: &[(&str, &str)],
    spp: u32,
    reference: &Image,
    (z, critical): (f64, f64),
    what: &str,
) {
    let defines: Vec<(String, String)> = defines
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    let twin = Scene::load_with(&scene_path(name), &defines).unwrap();
    let (z_twin, _) = max_z(&render(&twin, spp), reference, false);
    eprintln!("{name}: max |z| {z:.2}, {what} {z_twin:.2} (critical {critical:.2})");
    assert!(
        z_twin > critical,
        "{name} {what}: max |z| {z_twin:.2} < {critical:.2}, the test cannot see it"
    );
}

#[test]
fn pt_agrees_with_mitsuba_and_a_mirrored_camera_does_not() {
    let scene = Scene::load(&scene_path("box.xml")).unwrap();
    let (film, reference, (_, critical)) = agrees_with_reference("box.xml", &scene, SPP);
    let (z_mirrored, _) = max_z(&film, &reference, true);
    assert!(
        z_mirrored > critical,
        "box.xml mirrored: max |z| {z_mirrored:.2} < {critical:.2}, the test cannot see a mirrored camera"
    );
}

/// The samples of the glass test (its reference has 64 × as many).
const GLASS_SPP: u32 = 256;

#[test]
fn pt_agrees_with_mitsuba_through_glass_and_an_index_3_percent_off_does_not() {
    let scene = Scene::load(&scene_path("glass.xml")).unwrap();
    let (film, reference, z) = agrees_with_reference("glass.xml", &scene, GLASS_SPP);
    assert!(film
        .image
        .pixels
        .iter()
        .flatten()
        .all(|v| v.is_finite() && *v >= 0.0));
    let index = [("ior", "1.545")];
    twin_is_rejected(
        "glass.xml",
        &index,
        GLASS_SPP,
        &reference,
        z,
        "with the index 3 % off",
    );
}

/// The samples of the environment test (its reference has 64 × as many).
const ENV_SPP: u32 = 256;

#[test]
fn pt_agrees_with_mitsuba_under_an_environment_and_a_sky_3_percent_off_does_not() {
    let scene = Scene::load(&scene_path("env.xml")).unwrap();
    assert!(scene.environment.is_some() && !scene.emitters.prims.is_empty());
    let (_, reference, z) = agrees_with_reference("env.xml", &scene, ENV_SPP);
    // The sky's radiance 3 % high.
    let sky = [("env", "0.515, 0.618, 0.824")];
    twin_is_rejected(
        "env.xml",
        &sky,
        ENV_SPP,
        &reference,
        z,
        "with the sky 3 % off",
    );
}

/// The samples of the lights test (its reference has 64 × as many).
const LIGHTS_SPP: u32 = 256;

/// Every kind of emitter at once (`lights.xml`: an `envmap` with a sun, a `point`, a
/// `directional` and an area light): `pt` agrees with Mitsuba, and a map 3 % brighter or
/// turned by 10° about +y does not.
#[test]
fn pt_agrees_with_mitsuba_under_every_emitter_and_a_map_3_percent_off_or_turned_does_not() {
    let scene = Scene::load(&scene_path("lights.xml")).unwrap();
    assert!(scene.environment.as_ref().is_some_and(|e| e.map.is_some()));
    assert_eq!(scene.delta_lights.len(), 2);
    assert!(!scene.emitters.prims.is_empty());
    let (_, reference, z) = agrees_with_reference("lights.xml", &scene, LIGHTS_SPP);
    for (defines, what) in [
        (("scale", "1.03"), "with the map's scale 3 % off"),
        (("turn", "10"), "with the map turned by 10°"),
    ] {
        twin_is_rejected("lights.xml", &[defines], LIGHTS_SPP, &reference, z, what);
    }
}

/// The samples of the spot test (its reference has 64 × as many).
const SPOT_SPP: u32 = 256;

/// Mitsuba's `spot` (`spot.xml`: two spots, one with a soft edge across the floor and a box,
/// and a small area light): `pt` agrees with Mitsuba, and a spot whose cutoff is 3 % wider
/// does not.
#[test]
fn pt_agrees_with_mitsuba_under_spot_lights_and_a_cutoff_3_percent_wide_does_not() {
    let scene = Scene::load(&scene_path("spot.xml")).unwrap();
    assert_eq!(scene.delta_lights.len(), 2);
    let (_, reference, z) = agrees_with_reference("spot.xml", &scene, SPOT_SPP);
    twin_is_rejected(
        "spot.xml",
        &[("cutoff", "30.9")],
        SPOT_SPP,
        &reference,
        z,
        "with a cutoff 3 % wide",
    );
}

/// |z| of each block and channel of film `a` against film `b`, each with its own variance.
fn films_z(a: &Film, b: &Film) -> Vec<f64> {
    let (w, h) = (a.image.width, a.image.height);
    let mut out = Vec::new();
    for by in (0..h).step_by(BLOCK as usize) {
        for bx in (0..w).step_by(BLOCK as usize) {
            for c in 0..3 {
                let (mut diff, mut var) = (0.0, 0.0);
                for y in by..by + BLOCK {
                    for x in bx..bx + BLOCK {
                        let i = (y * w + x) as usize;
                        diff += f64::from(a.image.get(x, y)[c]) - f64::from(b.image.get(x, y)[c]);
                        var += a.variance_of_mean[i][c] + b.variance_of_mean[i][c];
                    }
                }
                out.push(match var > 0.0 {
                    true => diff.abs() / var.sqrt(),
                    false if diff == 0.0 => 0.0,
                    false => f64::INFINITY,
                });
            }
        }
    }
    out
}

/// The light tree's densities are exact where multiple importance sampling weighs them:
/// `pt` with `--light-sampler bvh` agrees, block by block, with `pt` with uniform picking
/// (which agrees with Mitsuba: the tests above) under every emitter kind (`lights.xml`),
/// spot lights (`spot.xml`) and emitting spheres and a disk (`spheres.xml`); and the same
/// render with the tree's probability halved in the weight of the directions that find a
/// light does not. (Against Mitsuba's reference directly the test would be unfair to the
/// tree: it assumes the reference's variance to be the render's over 64, and the tree's
/// variance is below Mitsuba's.)
#[test]
fn pt_with_the_light_tree_agrees_with_uniform_picking_and_a_wrong_pick_probability_does_not() {
    for (name, spp) in [("lights.xml", 128), ("spot.xml", 128), ("spheres.xml", 64)] {
        let scene = Scene::load(&scene_path(name)).unwrap();
        let uniform = render(&scene, 2 * spp);
        let tree = render_with(&scene, spp, |v| v.with_light_sampler(LightSampler::Bvh));
        let z = films_z(&tree, &uniform);
        let (max, critical) = (z.iter().fold(0.0f64, |m, &z| m.max(z)), z_critical(z.len()));
        assert!(
            max < critical,
            "{name} with the light tree: max |z| {max:.2} ≥ {critical:.2}"
        );
        if name == "spheres.xml" {
            let twin = render_with(&scene, spp, |mut v| {
                v.fault_light_pick_halved = true;
                v.with_light_sampler(LightSampler::Bvh)
            });
            let z_twin = films_z(&twin, &uniform).into_iter().fold(0.0f64, f64::max);
            eprintln!("{name}: light tree max |z| {max:.2}, pick halved {z_twin:.2} (critical {critical:.2})");
            assert!(
                z_twin > critical,
                "a halved pick probability is not seen: {z_twin:.2}"
            );
        }
    }
}

/// The samples of the spheres test (its reference has 64 × as many).
const SPHERES_SPP: u32 = 256;

#[test]
fn pt_agrees_with_mitsuba_on_spheres_and_a_disk_and_a_light_radius_3_percent_off_does_not() {
    let path = scene_path("spheres.xml");
    let scene = Scene::load(&path).unwrap();
    assert_eq!(scene.mesh.shapes.len(), 4);
    let (_, reference, (z, critical)) = agrees_with_reference("spheres.xml", &scene, SPHERES_SPP);
    let off = Scene::load_with(&path, &[("lr".into(), "0.206".into())]).unwrap();
    // Over the blocks with variance only: the light's own blocks, whose outline the larger
    // radius moves, would reject it alone.
    let z_off = block_z(&render(&off, SPHERES_SPP), &reference, false)
        .into_iter()
        .filter(|z| z.is_finite())
        .fold(0.0f64, f64::max);
    eprintln!(
        "spheres.xml: max |z| {z:.2}, with the light's radius 3 % off {z_off:.2} (critical {critical:.2})"
    );
    assert!(
        z_off > critical,
        "spheres.xml with the light's radius 3 % off: max |z| {z_off:.2} < {critical:.2}, the test cannot see it"
    );
}

/// `hide_emitters`: every method's camera rays that escape to the environment or see the
/// light give 0, and the rest of the image is what it is without it (`env.xml` at 32², its
/// camera moved back so that the sky and the light's face are in view).
#[test]
fn hide_emitters_hides_the_sky_and_the_light_from_the_camera_only() {
    let text = std::fs::read_to_string(scene_path("env.xml"))
        .unwrap()
        .replace("0.3, 3, 4.5", "0.3, 1.2, 6");
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("env.xml");
    std::fs::write(&path, text).unwrap();
    let load = |hide: &str| {
        let defines = [("hide".into(), hide.into()), ("res".into(), "32".into())];
        let scene = Scene::load_with(&path, &defines).unwrap();
        assert_eq!(scene.hide_emitters, hide == "true");
        scene
    };
    let (shown, hidden) = (load("false"), load("true"));
    for method in [
        Method::Pt,
        Method::Srt,
        Method::Ga,
        Method::GaPt,
        Method::Pg,
    ] {
        let render = |scene: &Scene| {
            let accel = accel::build(AccelKind::default_available(), &scene.mesh).unwrap();
            let view = SceneView::new(scene, accel.as_ref());
            let settings = RenderSettings {
                method,
                spp: 4,
                max_bounces: scene.render.max_bounces,
                seed: 3,
                progress: false,
                shard: Default::default(),
                control: Default::default(),
                learning: None,
            };
            let mut config = genpath::integrators::Settings::default();
            for setting in [
                "ga_grid=8",
                "population=8",
                "generations=2",
                "test_paths=500",
            ] {
                config.assign(setting).unwrap();
            }
            genpath::integrators::prepare(&view, &config, &settings)
                .unwrap()
                .render(&view, &settings)
                .image
        };
        let (a, b) = (render(&shown), render(&hidden));
        let (mut sky, mut light, mut other) = (0, 0, 0);
        let sky_radiance = shown.environment.as_ref().unwrap().radiance;
        for (pa, pb) in a.pixels.iter().zip(&b.pixels) {
            if glam::Vec3::from(*pa) == sky_radiance {
                // The sky seen directly (nothing else is exactly its radiance).
                assert_eq!(*pb, [0.0; 3], "{method:?}");
                sky += 1;
            } else if pa[0] > 30.0 {
                assert!(
                    pb[0] < 30.0,
                    "{method:?}: the light is seen with hide_emitters"
                );
                light += 1;
            } else {
                other += 1;
            }
        }
        assert!(
            sky > 32 && light > 0 && other > 32,
            "{method:?}: {sky} {light} {other}"
        );
    }
}

/// The glass of `glass.xml` as Mitsuba reads it: η = int_ior / ext_ior in single precision,
/// with Mitsuba's named indices (bk7 1.5046, air 1.000277), both sides scattering.
#[test]
fn glass_xml_has_mitsubas_indices() {
    let scene = Scene::load(&scene_path("glass.xml")).unwrap();
    let glass: Vec<_> = scene
        .materials
        .iter()
        .filter_map(|m| m.dielectric.map(|d| (m, d)))
        .collect();
    assert_eq!(glass.len(), 2);
    let (cube, smooth) = glass[0];
    assert!(!smooth.thin && cube.mirror && cube.two_sided);
    assert_eq!(smooth.eta, 1.5f32 / 1.000277f32);
    assert_eq!((cube.ks, smooth.transmittance), (Vec3::ONE, Vec3::ONE));
    let (pane, thin) = glass[1];
    assert!(thin.thin && pane.mirror && pane.two_sided);
    assert_eq!(thin.eta, 1.5046f32 / 1.000277f32);
    assert_eq!(thin.transmittance, Vec3::new(0.9, 0.95, 0.7));
}

/// Every method (`pt`, `srt` and `ga` with either estimator, `ga-pt` with and without the
/// spatial guide, `pg`, the test-only `nee-only`, and `srt` as a loaded `mixture`) renders
/// `glass.xml` at 32² without a NaN, infinite or negative pixel, with every sampled density
/// finite and positive and the image mean of `pt` (`genpath::check`); the same check with
/// the mixture's density 50 % off must fail.
#[cfg(feature = "testing")]
#[test]
fn every_method_renders_glass_as_pt_does_and_a_wrong_density_is_seen() {
    every_method_renders_as_pt_does("glass.xml");
}

/// As for `glass.xml`: every method renders `env.xml` (a `constant` emitter with a small
/// area light) at 32² without a bad pixel, with finite positive densities and `pt`'s image
/// mean; and a mixture density 50 % off is seen.
#[cfg(feature = "testing")]
#[test]
fn every_method_renders_env_as_pt_does_and_a_wrong_density_is_seen() {
    every_method_renders_as_pt_does("env.xml");
}

/// As for `glass.xml`: every method renders `spheres.xml` (an emitting sphere sampled by its
/// cone in `pt`, by area in the mixtures' light points; a glass and a diffuse sphere; a disk
/// light) at 32² without a bad pixel, with finite positive densities and `pt`'s image mean;
/// and a mixture density 50 % off is seen.
#[cfg(feature = "testing")]
#[test]
fn every_method_renders_spheres_as_pt_does_and_a_wrong_density_is_seen() {
    every_method_renders_as_pt_does("spheres.xml");
}

#[cfg(feature = "testing")]
fn every_method_renders_as_pt_does(name: &str) {
    use genpath::check::{check, CheckConfig};
    use genpath::path::mixture_file;
    let mut scene = Scene::load(&scene_path(name)).unwrap();
    scene.resize(32, 32);
    let accel = accel::build(AccelKind::default_available(), &scene.mesh).unwrap();
    let view = SceneView::new(&scene, accel.as_ref());
    let bounces = scene.render.max_bounces;
    let mut config = CheckConfig::new(64, bounces, 1);
    let srt = mixture_file::srt(
        &scene,
        bounces,
        config.methods.srt.absorption(config.methods.srt.nee),
    );
    config.methods.loaded_mixture = Some(srt.clone());
    let report = check(&view, &config).unwrap();
    for m in &report.methods {
        eprintln!(
            "{:<18} bad pixels {}  |z| vs pt {:.2}",
            m.method, m.bad_pixels, m.z_vs_pt
        );
        assert_eq!(m.bad_pixels, 0, "{}", m.method);
    }
    assert!(report.methods.len() >= 10 && report.pdf_samples > 1000);
    assert!(report.passed(), "{}", report.failures.join("; "));
    config.methods.loaded_mixture = Some(srt.with_pdf_error(0, 1.5));
    let wrong = check(&view, &config).unwrap();
    assert!(
        wrong.failures.iter().any(|f| f.starts_with("mixture:")),
        "a density 50 % off went unnoticed: {:?}",
        wrong.failures
    );
}

/// The scene of `box.xml` with the cube replaced by the shape `shape`.
fn with_mesh(dir: &Path, shape: &str) -> Scene {
    let text = std::fs::read_to_string(scene_path("box.xml")).unwrap();
    let start = text.find("<shape type=\"cube\">").unwrap();
    let end = start + text[start..].find("</shape>").unwrap() + "</shape>".len();
    let text = format!("{}{shape}{}", &text[..start], &text[end..]);
    let path = dir.join("s.xml");
    std::fs::write(&path, text).unwrap();
    Scene::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

/// A shape without a BSDF gets Mitsuba's default, a diffuse of reflectance 0.5, and an area
/// emitter without one a black diffuse (Mitsuba 3.9.1's `Shape` sets reflectance 0 when the
/// shape emits): the emitter reflects nothing.
#[test]
fn a_shape_without_a_bsdf_is_grey_diffuse_and_an_emitter_without_one_is_black() {
    let dir = tempfile::tempdir().unwrap();
    for (inside, kd) in [
        ("", 0.5),
        (
            r#"<emitter type="area"><rgb name="radiance" value="2"/></emitter>"#,
            0.0,
        ),
    ] {
        let shape = format!(
            r#"<shape type="rectangle"><transform name="to_world"><translate y="0.7"/></transform>{inside}</shape>"#
        );
        let scene = with_mesh(dir.path(), &shape);
        let bare: Vec<_> = scene
            .materials
            .iter()
            .filter(|m| m.name.starts_with("default"))
            .collect();
        assert_eq!(bare.len(), 1, "{inside}");
        assert_eq!(bare[0].kd, Vec3::splat(kd), "{inside}");
        assert_eq!(bare[0].ke.max_element() > 0.0, !inside.is_empty());
    }
}

const QUAD: [[f32; 3]; 4] = [
    [-0.5, 0.2, 0.0],
    [0.5, 0.2, 0.0],
    [0.5, 1.2, 0.0],
    [-0.5, 1.2, 0.0],
];

fn ply_quad(encoding: &str) -> Vec<u8> {
    let mut out = format!("ply\nformat {encoding} 1.0\ncomment a quad\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n").into_bytes();
    if encoding == "ascii" {
        for v in QUAD {
            out.extend(format!("{} {} {}\n", v[0], v[1], v[2]).bytes());
        }
        out.extend(b"4 0 1 2 3\n");
    } else {
        for v in QUAD.iter().flatten() {
            out.extend(v.to_le_bytes());
        }
        out.push(4);
        for i in 0..4i32 {
            out.extend(i.to_le_bytes());
        }
    }
    out
}

/// Mitsuba's serialized format, version 4, one mesh: the quad as two triangles.
fn serialized() -> Vec<u8> {
    let mut body = Vec::new();
    body.extend(0x1000u32.to_le_bytes()); // single precision, no normals
    body.extend(b"quad\0");
    body.extend(4u64.to_le_bytes());
    body.extend(2u64.to_le_bytes());
    for v in QUAD.iter().flatten() {
        body.extend(v.to_le_bytes());
    }
    for i in [0u32, 1, 2, 0, 2, 3] {
        body.extend(i.to_le_bytes());
    }
    let mut z = ZlibEncoder::new(Vec::new(), flate2::Compression::default());
    z.write_all(&body).unwrap();
    let mut out = vec![0x1C, 0x04, 0x04, 0x00];
    out.extend(z.finish().unwrap());
    out
}

#[test]
fn ply_ascii_binary_obj_and_serialized_give_the_same_triangles() {
    let dir = tempfile::tempdir().unwrap();
    let files: [(&str, Vec<u8>); 4] = [
        ("a.ply", ply_quad("ascii")),
        ("b.ply", ply_quad("binary_little_endian")),
        ("c.serialized", serialized()),
        ("d.obj", {
            let mut s = String::new();
            for v in QUAD {
                s += &format!("v {} {} {}\n", v[0], v[1], v[2]);
            }
            (s + "f 1 2 3 4\n").into_bytes()
        }),
    ];
    let mut meshes = Vec::new();
    for (name, bytes) in &files {
        std::fs::write(dir.path().join(name), bytes).unwrap();
        let plugin = name.rsplit('.').next().unwrap();
        let shape = format!(
            r#"<shape type="{plugin}"><string name="filename" value="{name}"/><transform name="to_world"><translate z="-0.2"/></transform></shape>"#
        );
        let scene = with_mesh(dir.path(), &shape);
        // What a shard's scene hash covers: the XML file, then the mesh file it read.
        let read: Vec<_> = scene
            .files
            .iter()
            .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
            .collect();
        assert_eq!(read, ["s.xml", name], "{:?}", scene.files);
        let n = scene.mesh.triangles.len();
        // The quad is the last shape but the light: its two triangles come before the
        // light's.
        let quad: Vec<[glam::Vec3; 3]> = (n - 4..n - 2)
            .map(|p| scene.mesh.vertices(p as u32))
            .collect();
        meshes.push((name, quad));
    }
    for (name, quad) in &meshes[1..] {
        assert_eq!(quad, &meshes[0].1, "{name} differs from a.ply");
    }
    assert!(
        (meshes[0].1[0][0] - glam::Vec3::new(-0.5, 0.2, -0.2)).length() < 1e-6,
        "{:?}",
        meshes[0].1
    );
}

/// The `constant` emitter's refusals, each naming the file and line: a scene without any
/// emitter (still), a second `constant`, one without `radiance` (genpath does not assume
/// Mitsuba's default), one nested in a shape, a negative radiance.
#[test]
fn constant_emitter_refusals_name_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        ("", "no emitter"),
        (
            r#"<emitter type="constant"><rgb name="radiance" value="1"/></emitter>
<emitter type="constant"><rgb name="radiance" value="1"/></emitter>"#,
            "a second environment",
        ),
        (r#"<emitter type="constant"/>"#, "needs a `radiance`"),
        (
            r#"<emitter type="constant"><rgb name="radiance" value="-1"/></emitter>"#,
            "negative",
        ),
        (
            r#"<shape type="rectangle"><emitter type="constant"><rgb name="radiance" value="1"/></emitter></shape>"#,
            "belongs in the scene",
        ),
    ];
    for (i, (emitters, expected)) in cases.iter().enumerate() {
        let text = format!(
            r#"<scene version="3.0.0">
<sensor type="perspective"><film type="hdrfilm"><rfilter type="box"/></film></sensor>
<shape type="cube"/>
{emitters}
</scene>
"#
        );
        let path = dir.path().join(format!("s{i}.xml"));
        std::fs::write(&path, text).unwrap();
        let error = Scene::load(&path).unwrap_err().to_string();
        assert!(
            error.contains(expected) && error.contains(&format!("s{i}.xml:")),
            "{emitters}: {error}"
        );
    }
}

/// The refusals of the `point`, `directional` and `envmap` emitters, each naming the file
/// and line: a negative or NaN intensity (the parser's refusal of a non-finite number), `position` beside `to_world`, a zero or missing
/// direction, a missing map file, a map with a NaN or an infinite pixel, a negative scale,
/// a `to_world` that scales the map, a second environment, and a delta light or map in a
/// shape.
#[test]
fn point_directional_and_envmap_refusals_name_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    for (name, bad) in [("nan.exr", f32::NAN), ("inf.exr", f32::INFINITY)] {
        let mut map = Image::new(8, 4);
        map.pixels.iter_mut().for_each(|p| *p = [0.5; 3]);
        map.pixels[13] = [1.0, bad, 1.0];
        genpath::image::write(&dir.path().join(name), &map).unwrap();
    }
    let mut good = Image::new(8, 4);
    good.pixels.iter_mut().for_each(|p| *p = [0.5; 3]);
    genpath::image::write(&dir.path().join("good.exr"), &good).unwrap();
    let envmap = |inner: &str| format!(r#"<emitter type="envmap">{inner}</emitter>"#);
    let cases = [
        (
            r#"<emitter type="point"><rgb name="intensity" value="-1"/></emitter>"#.to_string(),
            "negative",
        ),
        (
            r#"<emitter type="point"><rgb name="intensity" value="nan"/></emitter>"#.into(),
            "finite number",
        ),
        (r#"<emitter type="point"/>"#.into(), "needs an `intensity`"),
        (
            r#"<emitter type="point"><point name="position" value="0, 1, 0"/><transform name="to_world"><translate y="1"/></transform><rgb name="intensity" value="1"/></emitter>"#.into(),
            "not both",
        ),
        (
            r#"<emitter type="directional"><vector name="direction" value="0, 0, 0"/><rgb name="irradiance" value="1"/></emitter>"#.into(),
            "is zero",
        ),
        (
            r#"<emitter type="directional"><rgb name="irradiance" value="1"/></emitter>"#.into(),
            "needs a `direction`",
        ),
        (
            envmap(r#"<string name="filename" value="missing.exr"/>"#),
            "not found",
        ),
        (
            envmap(r#"<string name="filename" value="nan.exr"/>"#),
            "pixel (5, 1)",
        ),
        (
            envmap(r#"<string name="filename" value="inf.exr"/>"#),
            "infinite",
        ),
        (
            envmap(r#"<string name="filename" value="good.exr"/><float name="scale" value="-2"/>"#),
            "negative",
        ),
        (
            envmap(r#"<string name="filename" value="good.exr"/><transform name="to_world"><scale value="2"/></transform>"#),
            "without scaling",
        ),
        (
            envmap(r#"<string name="filename" value="good.exr"/>"#)
                + r#"<emitter type="constant"><rgb name="radiance" value="1"/></emitter>"#,
            "a second environment",
        ),
        (
            r#"<shape type="rectangle"><emitter type="point"><rgb name="intensity" value="1"/></emitter></shape>"#.into(),
            "belongs in the scene",
        ),
        (
            format!(r#"<shape type="rectangle">{}</shape>"#, envmap(r#"<string name="filename" value="good.exr"/>"#)),
            "belongs in the scene",
        ),
    ];
    for (i, (emitters, expected)) in cases.iter().enumerate() {
        let text = format!(
            r#"<scene version="3.0.0">
<sensor type="perspective"><film type="hdrfilm"><rfilter type="box"/></film></sensor>
<shape type="cube"/>
{emitters}
</scene>
"#
        );
        let path = dir.path().join(format!("e{i}.xml"));
        std::fs::write(&path, text).unwrap();
        let error = Scene::load(&path).unwrap_err().to_string();
        assert!(
            error.contains(expected) && error.contains(&format!("e{i}.xml:")),
            "{emitters}: {error}"
        );
    }
    // The good map loads, and its file is among those the scene was read from.
    let path = dir.path().join("good.xml");
    let text = format!(
        r#"<scene version="3.0.0"><sensor type="perspective"><film type="hdrfilm"><rfilter type="box"/></film></sensor><shape type="cube"/>{}</scene>"#,
        envmap(r#"<string name="filename" value="good.exr"/>"#)
    );
    std::fs::write(&path, text).unwrap();
    let scene = Scene::load(&path).unwrap();
    assert!(scene.files.iter().any(|f| f.ends_with("good.exr")));
}

/// The samples of the smooth-shading test (its reference has 64 × as many).
const SMOOTH_SPP: u32 = 256;

/// Shading normals: `smooth.xml` (a diffuse OBJ sphere with vertex normals, placed by a
/// mirroring transform, and a copper PLY icosphere whose normals Mitsuba computes) agrees
/// with Mitsuba's render; the same scene with `face_normals` (faceted) must not.
#[test]
fn pt_agrees_with_mitsuba_on_smooth_shading_and_face_normals_do_not() {
    let path = scene_path("smooth.xml");
    let scene = Scene::load(&path).unwrap();
    assert!(!scene.shading.normals.is_empty());
    let (_, reference, z) = agrees_with_reference("smooth.xml", &scene, SMOOTH_SPP);
    let face_normals = [("face_normals", "true")];
    let flat = Scene::load_with(&path, &[("face_normals".into(), "true".into())]).unwrap();
    assert!(flat.shading.normals.is_empty());
    twin_is_rejected(
        "smooth.xml",
        &face_normals,
        SMOOTH_SPP,
        &reference,
        z,
        "with face normals",
    );
}

/// The samples of the `legacy.xml` and `params.xml` tests (their references have 64 × as
/// many).
const PARAMS_SPP: u32 = 256;

/// Mitsuba 0.6's format: `legacy.xml` (version 0.6.0, its camelCase names upgraded: maxDepth,
/// rrDepth, fovAxis, nearClip, toWorld, sampleCount, diffuseReflectance, intIOR, extIOR,
/// specularTransmittance; its room `<include>`d from `legacy_room.xml`, whose BSDF it uses
/// under an `<alias>`; a 64 × 48 film with the field of view on the smaller axis and a near
/// clip plane through the floor) agrees with Mitsuba's render; the same scene with the field
/// of view 3 % wide must not.
#[test]
fn pt_agrees_with_mitsuba_on_a_version_0_6_file_and_a_fov_3_percent_wide_does_not() {
    let path = scene_path("legacy.xml");
    let scene = Scene::load(&path).unwrap();
    let files: Vec<_> = scene
        .files
        .iter()
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    assert_eq!(files, ["legacy.xml", "legacy_room.xml"]);
    // maxDepth 5 and sampleCount 16, upgraded.
    assert_eq!((scene.render.max_bounces, scene.render.spp), (4, Some(16)));
    assert!(
        scene.warnings.iter().any(|w| w.contains("rr_depth 3")),
        "{:?}",
        scene.warnings
    );
    let (_, reference, z) = agrees_with_reference("legacy.xml", &scene, PARAMS_SPP);
    let wide = [("fov", "39.14")];
    twin_is_rejected(
        "legacy.xml",
        &wide,
        PARAMS_SPP,
        &reference,
        z,
        "with the fov 3 % wide",
    );
}

/// `params.xml` (a camera placed by a 16-value `<matrix>` with a `focal_length` and a far
/// clip plane; a `<path>` folder holding a two-mesh serialized file: a wedge placed by a
/// 9-value `<matrix>`, and the light, turned to face down by `flip_normals`, its radiance
/// wavelength:value pairs; a conductor with explicit `eta`, `k` (pairs) and
/// `specular_reflectance`; a sphere centred by a `<vector>`; a disk turned to the room by
/// `flip_normals`; a `<float>` reflectance; `rr_depth`) agrees with
/// Mitsuba's render; the same scene with the wedge's 3 × 3 matrix transposed must not.
#[test]
fn pt_agrees_with_mitsuba_on_matrices_serialized_meshes_and_clipping_and_a_transposed_matrix_does_not(
) {
    let path = scene_path("params.xml");
    let scene = Scene::load(&path).unwrap();
    let files: Vec<_> = scene
        .files
        .iter()
        .map(|p| p.strip_prefix(scene_path("")).unwrap().to_owned())
        .collect();
    assert_eq!(
        files,
        [
            Path::new("params.xml"),
            Path::new("meshes/params.serialized"),
            Path::new("meshes/params.serialized")
        ]
    );
    // The sphere and the disk.
    assert_eq!(scene.mesh.shapes.len(), 2);
    let (_, reference, z) = agrees_with_reference("params.xml", &scene, PARAMS_SPP);
    let transposed = [(
        "rot",
        "0.573406, 0, -0.401503, 0, 0.9, 0, 0.286788, 0, 0.409576",
    )];
    let what = "with the wedge's matrix transposed";
    twin_is_rejected("params.xml", &transposed, PARAMS_SPP, &reference, z, what);
}

/// The horizontal field of view of every `fov_axis` and of `focal_length` (given with and
/// without `mm`, and Mitsuba's default 50 mm) on a landscape and a portrait film, as Mitsuba
/// 3.9.1 computes it (its `x_fov`, printed by `mi.load_string(…).sensors()[0]`).
#[test]
fn every_fov_axis_and_focal_length_give_mitsubas_horizontal_field_of_view() {
    let fov = |axis: &str| {
        format!(r#"<float name="fov" value="38"/><string name="fov_axis" value="{axis}"/>"#)
    };
    let focal = |f: &str| format!(r#"<string name="focal_length" value="{f}"/>"#);
    // (lens, x_fov at 64 × 48, x_fov at 48 × 64), in degrees.
    let cases = [
        (fov("x"), 38.0, 38.0),
        (fov("y"), 49.320_04, 28.960_054),
        (fov("diagonal"), 30.801_725, 23.345_772),
        (fov("smaller"), 49.320_04, 38.0),
        (fov("larger"), 38.0, 28.960_054),
        (focal("35mm"), 52.622_543, 40.695_274),
        (focal("50"), 38.184_84, 29.105_461),
        (String::new(), 38.184_84, 29.105_461),
    ];
    let dir = tempfile::tempdir().unwrap();
    for (lens, landscape, portrait) in &cases {
        for ((w, h), expected) in [((64, 48), landscape), ((48, 64), portrait)] {
            let text = format!(
                r#"<scene version="3.0.0">
<sensor type="perspective">{lens}<film type="hdrfilm"><integer name="width" value="{w}"/><integer name="height" value="{h}"/><rfilter type="box"/></film></sensor>
<shape type="cube"/>
<emitter type="constant"><rgb name="radiance" value="1"/></emitter>
</scene>
"#
            );
            let path = dir.path().join("fov.xml");
            std::fs::write(&path, text).unwrap();
            let scene = Scene::load(&path).unwrap();
            let x = scene.camera.fov_x.to_degrees();
            assert!(
                (x - expected).abs() < 1e-4,
                "{lens} at {w} × {h}: {x}° where Mitsuba has {expected}°"
            );
        }
    }
}

/// As for `glass.xml`: every method renders `smooth.xml` at 32² without a bad pixel, with
/// finite positive densities (the BRDF sampler's in the shading frame) and `pt`'s image
/// mean; and a mixture density 50 % off is seen.
#[cfg(feature = "testing")]
#[test]
fn every_method_renders_smooth_as_pt_does_and_a_wrong_density_is_seen() {
    every_method_renders_as_pt_does("smooth.xml");
}

/// `box.xml` with the cube replaced by `smooth_sphere.obj` or `smooth_blob.ply` (radius
/// 0.3 around `CENTRE`) with the given extra XML inside the shape.
fn with_sphere(dir: &Path, file: &str, inside: &str) -> Scene {
    let file = scene_path(file);
    let shape = format!(
        r#"<shape type="{}"><string name="filename" value="{}"/>{inside}</shape>"#,
        file.extension().unwrap().to_string_lossy(),
        file.display()
    );
    with_mesh(dir, &shape)
}

const CENTRE: Vec3 = Vec3::new(0.1, 0.5, -0.2);

/// The placed sphere's triangles (before the light's two) with their geometric and vertex
/// normals, and the outward direction at each vertex.
fn sphere_normals(scene: &Scene, faces: usize) -> Vec<(Vec3, [(Vec3, Vec3); 3])> {
    let n = scene.mesh.triangles.len();
    (n - 2 - faces..n - 2)
        .map(|p| {
            let t = scene.mesh.triangles[p];
            let ng = scene.mesh.normals[p];
            let corners = t.map(|i| {
                let radial = (scene.mesh.positions[i as usize] - CENTRE).normalize();
                (scene.shading.normals[i as usize], radial)
            });
            (ng, corners)
        })
        .collect()
}

/// Vertex normals as Mitsuba 3.9.1 places them: given ones through the inverse transpose
/// (outward under a mirroring transform, whose faces turn inward), both turned over by
/// `flip_normals`; angle-weighted ones (a PLY without normals) on the faces' side; none
/// with `face_normals`. At a hit, the shading normal is the vertices' interpolated.
#[test]
fn vertex_normals_are_placed_as_mitsuba_places_them() {
    let dir = tempfile::tempdir().unwrap();
    let place = |mirror: bool, flip: bool| {
        format!(
            r#"<boolean name="flip_normals" value="{flip}"/><transform name="to_world"><scale x="{}" y="0.3" z="0.3"/><translate x="0.1" y="0.5" z="-0.2"/></transform>"#,
            if mirror { -0.3 } else { 0.3 }
        )
    };
    // (mirror, flip): the sign of the given normals and of the faces' against outward.
    for (mirror, flip, given, faces) in [
        (false, false, 1.0, 1.0),
        (true, false, 1.0, -1.0),
        (false, true, -1.0, -1.0),
        (true, true, -1.0, 1.0),
    ] {
        let obj = with_sphere(dir.path(), "smooth_sphere.obj", &place(mirror, flip));
        let ply = with_sphere(dir.path(), "smooth_blob.ply", &place(mirror, flip));
        for (name, scene, count, sign, cos) in [
            ("obj", &obj, 100, given, 0.9999),
            ("ply", &ply, 80, faces, 0.98),
        ] {
            for (ng, corners) in sphere_normals(scene, count) {
                let centroid = corners.iter().map(|c| c.1).sum::<Vec3>();
                assert!(
                    ng.dot(centroid) * faces > 0.0,
                    "{name} mirror {mirror} flip {flip}: face normal {ng}"
                );
                for (ns, radial) in corners {
                    assert!(
                        ns.dot(radial) * sign > cos,
                        "{name} mirror {mirror} flip {flip}: vertex normal {ns} at {radial}"
                    );
                }
            }
        }
    }
    // A hit on the sphere's front, between its vertices: the interpolated normal.
    let scene = with_sphere(dir.path(), "smooth_sphere.obj", &place(false, false));
    let accel = accel::build(AccelKind::default_available(), &scene.mesh).unwrap();
    let view = SceneView::new(&scene, accel.as_ref());
    let origin = CENTRE + Vec3::new(0.13, 0.07, 2.0);
    let ray = genpath::accel::Ray::new(origin, Vec3::new(0.0, 0.0, -1.0), 0.0, f32::INFINITY);
    let x = view.trace(&ray, &mut Default::default()).unwrap();
    let hit = accel.intersect(&ray).unwrap();
    let t = scene.mesh.triangles[hit.prim as usize].map(|i| scene.shading.normals[i as usize]);
    let expected = (t[0] * (1.0 - hit.u - hit.v) + t[1] * hit.u + t[2] * hit.v).normalize();
    assert!((x.ns - expected).length() < 1e-6, "{} {expected}", x.ns);
    assert!(x.ns != x.ng && x.ng == hit.ng);
    let radial = (x.p - CENTRE).normalize();
    assert!(
        x.ns.dot(radial) > x.ng.dot(radial),
        "{} {} {radial}",
        x.ns,
        x.ng
    );
    // Face normals: nothing to interpolate.
    let flat = with_sphere(
        dir.path(),
        "smooth_sphere.obj",
        r#"<boolean name="face_normals" value="true"/>"#,
    );
    assert!(flat.shading.normals.is_empty());
}

/// Area emitters on smooth-shaded meshes are refused (with `face_normals` the mesh loads);
/// a zero vertex normal shades its triangles flat, with a warning.
#[test]
fn smooth_emitters_are_refused_and_zero_normals_shade_flat() {
    let dir = tempfile::tempdir().unwrap();
    let file = scene_path("smooth_sphere.obj");
    let text = std::fs::read_to_string(scene_path("box.xml")).unwrap();
    for (face_normals, ok) in [(false, false), (true, true)] {
        let shape = format!(
            r#"<shape type="obj"><string name="filename" value="{}"/><boolean name="face_normals" value="{face_normals}"/><emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>"#,
            file.display()
        );
        let path = dir.path().join("e.xml");
        std::fs::write(&path, text.replace("</scene>", &format!("{shape}</scene>"))).unwrap();
        match Scene::load(&path) {
            Ok(_) => assert!(ok),
            Err(e) => {
                let e = e.to_string();
                assert!(
                    !ok && e.contains("face_normals") && e.contains("e.xml:"),
                    "{e}"
                );
            }
        }
    }
    let obj = "v -0.5 0.2 0\nv 0.5 0.2 0\nv 0.5 1.2 0\nv -0.5 1.2 0\nvn 0 0 1\nvn 0 0 0\nvn 0.3 0 1\nf 1//1 2//2 3//3\nf 1//1 3//3 4//3\n";
    std::fs::write(dir.path().join("z.obj"), obj).unwrap();
    let scene = with_mesh(
        dir.path(),
        r#"<shape type="obj"><string name="filename" value="z.obj"/></shape>"#,
    );
    assert!(
        scene
            .warnings
            .iter()
            .any(|w| w.contains("1 vertices have no usable normal")),
        "{:?}",
        scene.warnings
    );
    let n = scene.mesh.triangles.len();
    let (zero, smooth) = ((n - 4) as u32, (n - 3) as u32);
    let ng = scene.mesh.normals[zero as usize];
    assert_eq!(scene.shading_normal(zero, (0.3, 0.3), ng), ng);
    let ng = scene.mesh.normals[smooth as usize];
    assert_ne!(scene.shading_normal(smooth, (0.3, 0.3), ng), ng);
}

/// Texture coordinates as Mitsuba reads them: OBJ `vt` with `v` turned into `1 − v`
/// (`flip_tex_coords`, default true), PLY `u v`, `texture_u texture_v` or `s t` (flipped
/// only when asked), serialized meshes' UVs; and from a hit's barycentrics.
#[test]
fn texture_coordinates_are_kept_as_mitsuba_reads_them() {
    let dir = tempfile::tempdir().unwrap();
    let uv = [[0.0, 0.25], [1.0, 0.25], [1.0, 0.75], [0.0, 1.0f32]];
    let flipped = uv.map(|[s, t]| [s, 1.0 - t]);
    let mut obj = String::new();
    for (v, t) in QUAD.iter().zip(uv) {
        obj += &format!("v {} {} {}\nvt {} {}\n", v[0], v[1], v[2], t[0], t[1]);
    }
    obj += "f 1/1 2/2 3/3 4/4\n";
    std::fs::write(dir.path().join("q.obj"), obj).unwrap();
    let ply = |names: [&str; 2]| {
        let mut s = format!("ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nproperty float {}\nproperty float {}\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n", names[0], names[1]);
        for (v, t) in QUAD.iter().zip(uv) {
            s += &format!("{} {} {} {} {}\n", v[0], v[1], v[2], t[0], t[1]);
        }
        s + "4 0 1 2 3\n"
    };
    std::fs::write(dir.path().join("uv.ply"), ply(["u", "v"])).unwrap();
    std::fs::write(dir.path().join("tu.ply"), ply(["texture_u", "texture_v"])).unwrap();
    std::fs::write(dir.path().join("st.ply"), ply(["s", "t"])).unwrap();
    std::fs::write(dir.path().join("q.serialized"), serialized_with_uvs(&uv)).unwrap();
    let shape = |file: &str, extra: &str| {
        let plugin = file.rsplit('.').next().unwrap();
        format!(r#"<shape type="{plugin}"><string name="filename" value="{file}"/>{extra}</shape>"#)
    };
    let flip = |on: bool| format!(r#"<boolean name="flip_tex_coords" value="{on}"/>"#);
    for (file, extra, expected) in [
        ("q.obj", String::new(), flipped),
        ("q.obj", flip(false), uv),
        ("uv.ply", String::new(), uv),
        ("tu.ply", String::new(), uv),
        ("st.ply", String::new(), uv),
        ("uv.ply", flip(true), flipped),
        ("q.serialized", String::new(), uv),
    ] {
        let scene = with_mesh(dir.path(), &shape(file, &extra));
        // The quad's four vertices come before the light's.
        let k = scene.mesh.positions.len() - 8;
        let got: Vec<[f32; 2]> = scene.shading.uvs[k..k + 4]
            .iter()
            .map(|uv| uv.unwrap().to_array())
            .collect();
        assert_eq!(got, expected, "{file} {extra}");
        // Interpolated at the first triangle's barycentrics (0.25, 0.5).
        let n = scene.mesh.triangles.len();
        let t = scene.mesh.triangles[n - 4];
        let at = scene.shading.uv(t, 0.25, 0.5);
        let e = t.map(|i| glam::Vec2::from(expected[i as usize - k]));
        let want = e[0] * 0.25 + e[1] * 0.25 + e[2] * 0.5;
        assert!((at - want).length() < 1e-6, "{file}: {at} {want}");
    }
    // Without texture coordinates: none kept for the quad, and a hit's are its barycentrics
    // (Mitsuba's default).
    std::fs::write(dir.path().join("b.ply"), ply_quad("ascii")).unwrap();
    let scene = with_mesh(dir.path(), &shape("b.ply", ""));
    let k = scene.mesh.positions.len() - 8;
    assert!(scene.shading.uvs[k..k + 4].iter().all(Option::is_none));
    let t = scene.mesh.triangles[scene.mesh.triangles.len() - 4];
    assert_eq!(scene.shading.uv(t, 0.25, 0.5), glam::Vec2::new(0.25, 0.5));
}

/// [`serialized`]'s quad with texture coordinates.
fn serialized_with_uvs(uv: &[[f32; 2]; 4]) -> Vec<u8> {
    let mut body = Vec::new();
    body.extend(0x1002u32.to_le_bytes()); // single precision, texture coordinates
    body.extend(b"quad\0");
    body.extend(4u64.to_le_bytes());
    body.extend(2u64.to_le_bytes());
    for v in QUAD.iter().flatten() {
        body.extend(v.to_le_bytes());
    }
    for t in uv.iter().flatten() {
        body.extend(t.to_le_bytes());
    }
    for i in [0u32, 1, 2, 0, 2, 3] {
        body.extend(i.to_le_bytes());
    }
    let mut z = ZlibEncoder::new(Vec::new(), flate2::Compression::default());
    z.write_all(&body).unwrap();
    let mut out = vec![0x1C, 0x04, 0x04, 0x00];
    out.extend(z.finish().unwrap());
    out
}

/// The samples of the microfacet test (its reference has 64 × as many).
const ROUGH_SPP: u32 = 256;

/// Microfacet BSDFs: `rough.xml` (a gold sphere of anisotropic GGX roughness whose tangent
/// follows its texture coordinates, a copper icosphere of isotropic Beckmann roughness
/// without texture coordinates, a GGX rough plastic wall) agrees with Mitsuba's render; the
/// same scene with the icosphere's distribution GGX, or with the sphere's `alpha_u` and
/// `alpha_v` exchanged (the anisotropy along the other tangent), must not.
#[test]
fn pt_agrees_with_mitsuba_on_rough_bsdfs_and_a_wrong_distribution_or_tangent_does_not() {
    let scene = Scene::load(&scene_path("rough.xml")).unwrap();
    let (_, reference, z) = agrees_with_reference("rough.xml", &scene, ROUGH_SPP);
    twin_is_rejected(
        "rough.xml",
        &[("blob_distribution", "ggx")],
        ROUGH_SPP,
        &reference,
        z,
        "with the icosphere's distribution GGX",
    );
    twin_is_rejected(
        "rough.xml",
        &[("sphere_alpha_u", "0.4"), ("sphere_alpha_v", "0.05")],
        ROUGH_SPP,
        &reference,
        z,
        "with the sphere's alpha_u and alpha_v exchanged",
    );
}

/// As for `glass.xml`: every method renders `rough.xml` at 32² without a bad pixel, with
/// the mixture of a wrong density seen.
#[cfg(feature = "testing")]
#[test]
fn every_method_renders_rough_as_pt_does_and_a_wrong_density_is_seen() {
    every_method_renders_as_pt_does("rough.xml");
}

/// The samples of the rough glass test (its reference has 64 × as many).
const ROUGHGLASS_SPP: u32 = 256;

/// Rough glass: `roughglass.xml` (a GGX `roughdielectric` slab through which a small light
/// and a diffuse block are seen, a Beckmann rough glass sphere sampled from the whole
/// distribution) agrees with Mitsuba's render, without a NaN, infinite or negative pixel;
/// the same scene with the slab's and the sphere's roughnesses exchanged, or with the
/// sphere's normals flipped (its glass outside it: every index seen from the wrong side),
/// must not. (An index 3 % off is not seen at these samples: through rough glass it moves
/// little light, max |z| 2.86 with the sphere's.)
#[test]
fn pt_agrees_with_mitsuba_through_rough_glass_and_wrong_roughnesses_or_sides_do_not() {
    let scene = Scene::load(&scene_path("roughglass.xml")).unwrap();
    let (film, reference, z) = agrees_with_reference("roughglass.xml", &scene, ROUGHGLASS_SPP);
    assert!(film
        .image
        .pixels
        .iter()
        .flatten()
        .all(|v| v.is_finite() && *v >= 0.0));
    twin_is_rejected(
        "roughglass.xml",
        &[("slab_alpha", "0.3"), ("sphere_alpha", "0.1")],
        ROUGHGLASS_SPP,
        &reference,
        z,
        "with the slab's and the sphere's roughnesses exchanged",
    );
    twin_is_rejected(
        "roughglass.xml",
        &[("sphere_flip", "true")],
        ROUGHGLASS_SPP,
        &reference,
        z,
        "with the sphere's normals flipped",
    );
}

/// The rough glass of `roughglass.xml` as Mitsuba reads it: η = int_ior / ext_ior in single
/// precision (a number over air's 1.000277, by name), the distributions, roughnesses and
/// sampling modes, white reflectance and transmittance, both sides scattering.
#[test]
fn roughglass_xml_has_mitsubas_parameters() {
    use genpath::scene::material::microfacet::Distribution;
    use genpath::scene::Glossy;
    let scene = Scene::load(&scene_path("roughglass.xml")).unwrap();
    let glass: Vec<_> = scene
        .materials
        .iter()
        .filter_map(|m| match &m.glossy {
            Glossy::RoughDielectric(d) => Some((m, d)),
            _ => None,
        })
        .collect();
    assert_eq!(glass.len(), 2);
    for (m, d) in &glass {
        assert!(m.two_sided && m.transmits() && !m.mirror && m.kd == Vec3::ZERO);
        assert_eq!(
            (d.specular_reflectance, d.specular_transmittance),
            (Vec3::ONE, Vec3::ONE)
        );
    }
    let (slab, sphere) = (glass[0].1, glass[1].1);
    assert_eq!(slab.eta, 1.5046f32 / 1.000277f32);
    assert_eq!(slab.microfacet.distribution, Distribution::Ggx);
    assert_eq!(
        (slab.microfacet.alpha_u, slab.microfacet.alpha_v),
        (0.1, 0.1)
    );
    assert!(slab.microfacet.sample_visible);
    assert_eq!(sphere.eta, 1.5f32 / 1.000277f32);
    assert_eq!(sphere.microfacet.distribution, Distribution::Beckmann);
    assert_eq!(
        (sphere.microfacet.alpha_u, sphere.microfacet.alpha_v),
        (0.3, 0.3)
    );
    assert!(!sphere.microfacet.sample_visible);
}

/// As for `glass.xml`: every method renders `roughglass.xml` at 32² without a bad pixel,
/// with finite positive densities and `pt`'s image mean; and a mixture density 50 % off is
/// seen.
#[cfg(feature = "testing")]
#[test]
fn every_method_renders_roughglass_as_pt_does_and_a_wrong_density_is_seen() {
    every_method_renders_as_pt_does("roughglass.xml");
}

/// The microfacet BSDFs' refusals, each naming the file and line: a roughness that is not
/// positive and finite, an unknown distribution, `alpha` beside `alpha_u`, `alpha_u`
/// without `alpha_v`, an anisotropic `roughplastic` (as Mitsuba refuses it), a smooth
/// `plastic` of equal indices or of an index beyond Mitsuba's fit (η 4: `F_dr` ≥ 1), and anisotropic roughness where genpath cannot follow Mitsuba's tangent (an
/// analytic sphere, a mesh without texture coordinates under `flip_normals`);
/// and inside `twosided` too.
#[test]
fn microfacet_refusals_name_file_and_line() {
    const CUBE: &str = r#""cube""#;
    let dir = tempfile::tempdir().unwrap();
    let conductor = |props: &str| format!(r#"<bsdf type="roughconductor">{props}</bsdf>"#);
    // The shape's type and what follows it in its opening tag's place.
    let blob = format!(
        r#""ply"><string name="filename" value="{}"/><boolean name="flip_normals" value="true"/"#,
        scene_path("smooth_blob.ply").display()
    );
    let aniso =
        conductor(r#"<float name="alpha_u" value="0.1"/><float name="alpha_v" value="0.3"/>"#);
    let cases = [
        (conductor(r#"<float name="alpha" value="0"/>"#), CUBE.to_string(), "not a positive, finite roughness"),
        (conductor(r#"<float name="alpha" value="-0.1"/>"#), CUBE.to_string(), "not a positive, finite roughness"),
        (conductor(r#"<float name="alpha_u" value="nan"/><float name="alpha_v" value="0.1"/>"#), CUBE.to_string(), "as a finite number"),
        (
            format!(r#"<bsdf type="twosided">{}</bsdf>"#, conductor(r#"<float name="alpha" value="0"/>"#)),
            CUBE.to_string(),
            "not a positive, finite roughness",
        ),
        (conductor(r#"<string name="distribution" value="phong"/>"#), CUBE.to_string(), "unknown microfacet `distribution` \"phong\""),
        (conductor(r#"<float name="alpha" value="0.1"/><float name="alpha_u" value="0.1"/><float name="alpha_v" value="0.1"/>"#), CUBE.to_string(), "either `alpha`"),
        (conductor(r#"<float name="alpha_u" value="0.1"/>"#), CUBE.to_string(), "both `alpha_u` and `alpha_v`"),
        (
            r#"<bsdf type="roughplastic"><float name="alpha_u" value="0.1"/><float name="alpha_v" value="0.3"/></bsdf>"#.to_string(),
            CUBE.to_string(),
            "anisotropic",
        ),
        (
            r#"<bsdf type="plastic"><float name="int_ior" value="1.3"/><float name="ext_ior" value="1.3"/></bsdf>"#.to_string(),
            CUBE.to_string(),
            "indices of refraction must differ",
        ),
        (
            r#"<bsdf type="plastic"><float name="int_ior" value="4"/></bsdf>"#.to_string(),
            CUBE.to_string(),
            "internal diffuse reflectance gives 1.0",
        ),
        (
            r#"<bsdf type="roughdielectric"><float name="alpha" value="0"/></bsdf>"#.to_string(),
            CUBE.to_string(),
            "not a positive, finite roughness",
        ),
        (
            r#"<bsdf type="roughdielectric"><string name="int_ior" value="glass"/></bsdf>"#.to_string(),
            CUBE.to_string(),
            "unknown index of refraction",
        ),
        (
            r#"<bsdf type="roughdielectric"><float name="int_ior" value="1.3"/><float name="ext_ior" value="1.3"/></bsdf>"#.to_string(),
            CUBE.to_string(),
            "must differ",
        ),
        (
            r#"<bsdf type="roughdielectric"><rgb name="specular_transmittance" value="1.2"/></bsdf>"#.to_string(),
            CUBE.to_string(),
            "specular_transmittance",
        ),
        (
            r#"<bsdf type="twosided"><bsdf type="roughdielectric"/></bsdf>"#.to_string(),
            CUBE.to_string(),
            "transmission",
        ),
        (aniso.clone(), r#""sphere""#.to_string(), "analytic shape"),
        (aniso.clone(), blob, "`flip_normals`"),
    ];
    for (i, (bsdf, shape, expected)) in cases.iter().enumerate() {
        let text = format!(
            r#"<scene version="3.0.0">
<sensor type="perspective"><film type="hdrfilm"><rfilter type="box"/></film></sensor>
<shape type="rectangle"><emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>
<shape type={shape}>
{bsdf}
</shape>
</scene>
"#
        );
        let path = dir.path().join(format!("r{i}.xml"));
        std::fs::write(&path, text).unwrap();
        let error = Scene::load(&path).unwrap_err().to_string();
        assert!(
            error.contains(expected) && error.contains(&format!("r{i}.xml:")),
            "{bsdf}: {error}"
        );
    }
}

/// Samples of the textures agreement test: its reference has 4096 (64 × as many).
const TEXTURES_SPP: u32 = 64;

/// Textures: `textures.xml` (a checkerboard and an 8-bit sRGB bitmap on diffuse and rough
/// plastic BSDFs, on rectangles, an OBJ with texture coordinates, an analytic sphere turned
/// by its to_world and a cube) agrees with Mitsuba's render; the same scene with the OBJ's
/// texture coordinates not flipped (`flip_tex_coords` false: the texture upside down) or
/// with the wall's bitmap read `raw` (its sRGB decoding skipped) must not.
#[test]
fn pt_agrees_with_mitsuba_on_textures_and_a_flipped_or_undecoded_texture_does_not() {
    let scene = Scene::load(&scene_path("textures.xml")).unwrap();
    let (_, reference, z) = agrees_with_reference("textures.xml", &scene, TEXTURES_SPP);
    twin_is_rejected(
        "textures.xml",
        &[("obj_flip", "false")],
        TEXTURES_SPP,
        &reference,
        z,
        "with the OBJ's texture coordinates not flipped",
    );
    twin_is_rejected(
        "textures.xml",
        &[("wall_raw", "true")],
        TEXTURES_SPP,
        &reference,
        z,
        "with the wall's bitmap not sRGB-decoded",
    );
}

/// As for `glass.xml`: every method renders `textures.xml` at 32² without a bad pixel, with
/// the mixture of a wrong density seen.
#[cfg(feature = "testing")]
#[test]
fn every_method_renders_textures_as_pt_does_and_a_wrong_density_is_seen() {
    every_method_renders_as_pt_does("textures.xml");
}

/// Smooth plastic and textured rough glass: `plastic.xml` (a `plastic` floor over a
/// checkerboard, a `plastic` sphere of index 1.9 whose coating's reflectance is a
/// checkerboard, a GGX `roughdielectric` pane whose transmittance is an 8-bit sRGB bitmap and
/// whose reflectance a checkerboard) agrees with Mitsuba's render; the same scene with the
/// floor's `nonlinear` true, or with the pane's bitmap read `raw` (its sRGB decoding
/// skipped), must not. (The sphere's `int_ior` 3 % or even 10 % off goes unseen here, max
/// |z| 3.85 and 2.61 against a critical 4.56: it moves the sphere's diffuse light by 0.9 %
/// and 3 %, and its coating reflects little. The index is pinned by the lobe's values
/// against Mitsuba's, `tests/brdf_sampler/plastic.rs`, and by the binomial test of the
/// choice, `tests/dielectric.rs`, which sees 3 %.)
#[test]
fn pt_agrees_with_mitsuba_on_smooth_plastic_and_textured_rough_glass_and_wrong_ones_do_not() {
    let scene = Scene::load(&scene_path("plastic.xml")).unwrap();
    let (_, reference, z) = agrees_with_reference("plastic.xml", &scene, SPP);
    for (defines, what) in [
        (
            ("floor_nonlinear", "true"),
            "with the floor's `nonlinear` true",
        ),
        (
            ("pane_raw", "true"),
            "with the pane's bitmap not sRGB-decoded",
        ),
    ] {
        twin_is_rejected("plastic.xml", &[defines], SPP, &reference, z, what);
    }
}

/// As for `glass.xml`: every method renders `plastic.xml` at 32² without a bad pixel, with
/// the mixture of a wrong density seen.
#[cfg(feature = "testing")]
#[test]
fn every_method_renders_plastic_as_pt_does_and_a_wrong_density_is_seen() {
    every_method_renders_as_pt_does("plastic.xml");
}

/// The textures' refusals, each naming the file and line: a missing file, an unreadable
/// one, a texel that is NaN, infinite or negative, a reflectance texture above 1, an unknown
/// filter or wrap mode, an unknown texture plugin, a textured roughness, and a rough glass's
/// transmittance texture above 1.
#[test]
fn texture_refusals_name_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("garbage.png"), b"not a png at all").unwrap();
    let exr = |name: &str, texel: f32| {
        let mut img = genpath::image::Image::new(2, 2);
        img.set(1, 0, [0.5, texel, 0.5]);
        genpath::image::rust_writers::write_exr(&d.join(name), &img).unwrap();
    };
    exr("nan.exr", f32::NAN);
    exr("inf.exr", f32::INFINITY);
    exr("negative.exr", -0.25);
    exr("bright.exr", 2.0);
    let bitmap = |file: &str, extra: &str| {
        format!(
            r#"<bsdf type="diffuse"><texture type="bitmap" name="reflectance"><string name="filename" value="{file}"/>{extra}</texture></bsdf>"#
        )
    };
    let cases = [
        (bitmap("missing.png", ""), "missing.png"),
        (bitmap("garbage.png", ""), "garbage.png"),
        (bitmap("nan.exr", ""), "texel (1, 0)"),
        (bitmap("inf.exr", ""), "finite and non-negative"),
        (bitmap("negative.exr", ""), "negative.exr"),
        (bitmap("bright.exr", ""), "beyond 1"),
        (bitmap("nan.exr", r#"<string name="filter_type" value="cubic"/>"#), "`filter_type` \"cubic\""),
        (bitmap("nan.exr", r#"<string name="wrap_mode" value="wrap"/>"#), "`wrap_mode` \"wrap\""),
        (
            r#"<bsdf type="diffuse"><texture type="noise" name="reflectance"/></bsdf>"#.to_string(),
            "`noise` texture",
        ),
        (
            r#"<bsdf type="roughconductor"><texture type="checkerboard" name="alpha"/></bsdf>"#.to_string(),
            "textured roughness",
        ),
        (
            r#"<bsdf type="roughdielectric"><texture type="bitmap" name="specular_transmittance"><string name="filename" value="bright.exr"/></texture></bsdf>"#.to_string(),
            "beyond 1",
        ),
    ];
    for (i, (bsdf, expected)) in cases.iter().enumerate() {
        let text = format!(
            r#"<scene version="3.0.0">
<sensor type="perspective"><film type="hdrfilm"><rfilter type="box"/></film></sensor>
<shape type="rectangle"><emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>
<shape type="cube">
{bsdf}
</shape>
</scene>
"#
        );
        let path = d.join(format!("t{i}.xml"));
        std::fs::write(&path, text).unwrap();
        let error = Scene::load(&path).unwrap_err().to_string();
        assert!(
            error.contains(expected) && error.contains(&format!("t{i}.xml:5")),
            "{bsdf}: {error}"
        );
    }
}

/// Samples of the maps agreement test: its reference has 4096 (64 × as many).
const MAPS_SPP: u32 = 64;

/// Normal and bump maps: `maps.xml` (a `normalmap` around a rough plastic, a `bumpmap`
/// around a diffuse BSDF and, on a smooth-shaded OBJ under a `twosided`, around a rough
/// conductor; two cards seen from behind, a normal map around a `twosided` and a `twosided`
/// around a normal map) agrees with Mitsuba's render; the same scene with the normal map's
/// green channel flipped, or with the floor's bump scale 30 % off, must not (at 64 spp a
/// scale 3 % off gives a largest |z| of 2.53, 10 % off 3.00, 20 % off 6.83, against a
/// critical 4.56: the bumps of a diffuse floor move little light).
#[test]
fn pt_agrees_with_mitsuba_on_normal_and_bump_maps_and_a_flipped_or_rescaled_map_does_not() {
    let scene = Scene::load(&scene_path("maps.xml")).unwrap();
    let (_, reference, z) = agrees_with_reference("maps.xml", &scene, MAPS_SPP);
    twin_is_rejected(
        "maps.xml",
        &[("nmap", "normals_gflip")],
        MAPS_SPP,
        &reference,
        z,
        "with the normal map's green channel flipped",
    );
    twin_is_rejected(
        "maps.xml",
        &[("bump_scale", "0.13")],
        MAPS_SPP,
        &reference,
        z,
        "with the floor's bump scale 30 % off",
    );
}

/// As for `glass.xml`: every method renders `maps.xml` at 32² without a bad pixel, with the
/// mixture of a wrong density seen.
#[cfg(feature = "testing")]
#[test]
fn every_method_renders_maps_as_pt_does_and_a_wrong_density_is_seen() {
    every_method_renders_as_pt_does("maps.xml");
}

/// The refusals of `normalmap` and `bumpmap`, each naming the file and line: no nested BSDF,
/// a delta, transmitting or anisotropic one, a map inside a map, a twosided both around and
/// inside, `flip_invalid_normals` or `use_shadowing_function` false, no normal-map texture
/// or one that is not a texture, a normal map whose blue channel reaches 1/2, a bump map
/// without a texture or with a checkerboard, a scale that is not finite, and a map on an
/// analytic shape or on a mesh without texture coordinates under `flip_normals`.
#[test]
fn map_refusals_name_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let maps = scene_path("maps");
    let normals = maps.join("normals.png");
    let heights = maps.join("heights.png");
    let mut low = genpath::image::Image::new(2, 2);
    low.set(1, 1, [0.5, 0.5, 0.5]);
    genpath::image::rust_writers::write_exr(&d.join("low.exr"), &low).unwrap();
    let nmap = |inner: &str, extra: &str| {
        format!(
            r#"<bsdf type="normalmap"><texture type="bitmap" name="normalmap"><string name="filename" value="{}"/></texture>{extra}{inner}</bsdf>"#,
            normals.display()
        )
    };
    let bump = |inner: &str, extra: &str| {
        format!(
            r#"<bsdf type="bumpmap"><texture type="bitmap"><string name="filename" value="{}"/></texture>{extra}{inner}</bsdf>"#,
            heights.display()
        )
    };
    let diffuse = r#"<bsdf type="diffuse"/>"#;
    let cases = [
        ("cube", nmap("", ""), "exactly one nested BSDF"),
        (
            "cube",
            nmap(r#"<bsdf type="conductor"/>"#, ""),
            "not `conductor`",
        ),
        (
            "cube",
            bump(r#"<bsdf type="roughdielectric"/>"#, ""),
            "not `roughdielectric`",
        ),
        (
            "cube",
            nmap(r#"<bsdf type="plastic"/>"#, ""),
            "not `plastic`",
        ),
        (
            "cube",
            nmap(
                r#"<bsdf type="twosided"><bsdf type="conductor"/></bsdf>"#,
                "",
            ),
            "not `twosided`",
        ),
        (
            "cube",
            bump(
                r#"<bsdf type="roughconductor"><float name="alpha_u" value="0.1"/><float name="alpha_v" value="0.3"/></bsdf>"#,
                "",
            ),
            "anisotropic",
        ),
        ("cube", nmap(&bump(diffuse, ""), ""), "inside a `normalmap`"),
        (
            "cube",
            format!(
                r#"<bsdf type="twosided">{}</bsdf>"#,
                nmap(r#"<bsdf type="twosided"><bsdf type="diffuse"/></bsdf>"#, "")
            ),
            "both around and inside",
        ),
        (
            "cube",
            nmap(
                diffuse,
                r#"<boolean name="flip_invalid_normals" value="false"/>"#,
            ),
            "`flip_invalid_normals` false",
        ),
        (
            "cube",
            bump(
                diffuse,
                r#"<boolean name="use_shadowing_function" value="false"/>"#,
            ),
            "`use_shadowing_function` false",
        ),
        (
            "cube",
            format!(r#"<bsdf type="normalmap">{diffuse}</bsdf>"#),
            "needs a texture `normalmap`",
        ),
        (
            "cube",
            format!(
                r#"<bsdf type="normalmap"><rgb name="normalmap" value="0.5, 0.5, 1"/>{diffuse}</bsdf>"#
            ),
            "must be a <texture>",
        ),
        (
            "cube",
            format!(
                r#"<bsdf type="normalmap"><texture type="bitmap" name="normalmap"><string name="filename" value="{}"/></texture>{diffuse}</bsdf>"#,
                d.join("low.exr").display()
            ),
            "blue channel reaches 0",
        ),
        (
            "cube",
            format!(r#"<bsdf type="bumpmap">{diffuse}</bsdf>"#),
            "exactly one nested texture",
        ),
        (
            "cube",
            format!(r#"<bsdf type="bumpmap"><texture type="checkerboard"/>{diffuse}</bsdf>"#),
            "checkerboard has no gradient",
        ),
        (
            "cube",
            bump(diffuse, r#"<float name="scale" value="1e9"/>"#),
            "`scale` 1000000000",
        ),
        ("sphere", nmap(diffuse, ""), "analytic shape"),
        (
            "ply",
            bump(diffuse, ""),
            "without texture coordinates and with `flip_normals`",
        ),
    ];
    let ply = scene_path("smooth_blob.ply");
    for (i, (shape, bsdf, expected)) in cases.iter().enumerate() {
        let shape = match *shape {
            "ply" => format!(
                r#""ply"><string name="filename" value="{}"/><boolean name="flip_normals" value="true"/"#,
                ply.display()
            ),
            s => format!(r#""{s}""#),
        };
        let text = format!(
            r#"<scene version="3.0.0">
<sensor type="perspective"><film type="hdrfilm"><rfilter type="box"/></film></sensor>
<shape type="rectangle"><emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>
<shape type={shape}>
{bsdf}
</shape>
</scene>
"#
        );
        let path = d.join(format!("m{i}.xml"));
        std::fs::write(&path, text).unwrap();
        let error = Scene::load(&path).unwrap_err().to_string();
        assert!(
            error.contains(expected) && error.contains(&format!("m{i}.xml:")),
            "{bsdf}: {error}"
        );
    }
}

/// Samples of the mask agreement test: its reference has 65 536 (1024 × as many, since
/// Mitsuba's `path`, whose shadow rays stop at every mask, is far noisier on it).
const MASK_SPP: u32 = 64;

/// Opacity masks: `mask.xml` (Mitsuba's `mask` with a bitmap opacity around a twosided
/// diffuse leaf under the light, a checkerboard one around a one-sided diffuse card seen
/// from behind, a constant one around a rough plastic sphere) agrees with Mitsuba's render;
/// the same scene with the card's and the sphere's opacities inverted must not, nor (with
/// feature `testing`) a render whose shadow rays stop at every masked surface while the
/// directions that find light pass through them.
#[test]
fn pt_agrees_with_mitsuba_on_masks_and_inverted_opacities_or_opaque_shadows_do_not() {
    let scene = Scene::load(&scene_path("mask.xml")).unwrap();
    let (_, reference, z) = agrees_with_reference("mask.xml", &scene, MASK_SPP);
    twin_is_rejected(
        "mask.xml",
        &[
            ("card_op0", "0.85"),
            ("card_op1", "0.1"),
            ("sphere_op", "0.55"),
        ],
        MASK_SPP,
        &reference,
        z,
        "with the card's and the sphere's opacities inverted",
    );
    #[cfg(feature = "testing")]
    {
        let accel = accel::build(AccelKind::default_available(), &scene.mesh).unwrap();
        let mut view = SceneView::new(&scene, accel.as_ref());
        view.fault_masks_block_shadows = true;
        let settings = RenderSettings {
            method: Method::Pt,
            spp: MASK_SPP,
            max_bounces: scene.render.max_bounces,
            seed: 3,
            progress: false,
            shard: Default::default(),
            control: Default::default(),
            learning: None,
        };
        let film = PathTracing {
            max_bounces: scene.render.max_bounces,
        }
        .render(&view, &settings);
        let (z_twin, _) = max_z(&film, &reference, false);
        eprintln!(
            "mask.xml: shadow rays stopped by masks {z_twin:.2} (critical {:.2})",
            z.1
        );
        assert!(
            z_twin > z.1,
            "mask.xml with masks opaque to shadow rays: max |z| {z_twin:.2} < {:.2}",
            z.1
        );
    }
}

/// As for `glass.xml`: every method renders `mask.xml` at 32² without a bad pixel, with the
/// mixture of a wrong density seen.
#[cfg(feature = "testing")]
#[test]
fn every_method_renders_mask_as_pt_does_and_a_wrong_density_is_seen() {
    every_method_renders_as_pt_does("mask.xml");
}

/// The refusals of `mask`, each naming the file and line: no nested BSDF or two, a mask
/// inside a mask, a twosided around a mask, an opacity outside [0, 1], one that is an
/// `<rgb>`, a texture beyond 1 or not grey, a missing bitmap, and a mask on an area emitter.
#[test]
fn mask_refusals_name_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let diffuse = r#"<bsdf type="diffuse"/>"#;
    let mask = |inner: &str, opacity: &str| format!(r#"<bsdf type="mask">{opacity}{inner}</bsdf>"#);
    let cases = [
        (mask("", ""), "", "exactly one nested BSDF"),
        (
            mask(&format!("{diffuse}{diffuse}"), ""),
            "",
            "exactly one nested BSDF",
        ),
        (mask(&mask(diffuse, ""), ""), "", "inside a `mask`"),
        (
            format!(r#"<bsdf type="twosided">{}</bsdf>"#, mask(diffuse, "")),
            "",
            "a mask transmits",
        ),
        (
            mask(diffuse, r#"<float name="opacity" value="1.5"/>"#),
            "",
            "1.5 is not within [0, 1]",
        ),
        (
            mask(diffuse, r#"<float name="opacity" value="-0.1"/>"#),
            "",
            "is not within [0, 1]",
        ),
        (
            mask(diffuse, r#"<rgb name="opacity" value="0.5"/>"#),
            "",
            "expected a float",
        ),
        (
            mask(
                diffuse,
                r#"<texture type="checkerboard" name="opacity"><float name="color0" value="2"/></texture>"#,
            ),
            "",
            "the texture reaches 2, beyond 1",
        ),
        (
            mask(
                diffuse,
                r#"<texture type="checkerboard" name="opacity"><rgb name="color0" value="0.1, 0.2, 0.3"/></texture>"#,
            ),
            "",
            "must be grey",
        ),
        (
            mask(
                diffuse,
                r#"<texture type="bitmap" name="opacity"><string name="filename" value="no_such.png"/></texture>"#,
            ),
            "",
            "no_such.png",
        ),
        (
            mask(diffuse, ""),
            r#"<emitter type="area"><rgb name="radiance" value="1"/></emitter>"#,
            "a `mask` on an area emitter",
        ),
    ];
    for (i, (bsdf, emitter, expected)) in cases.iter().enumerate() {
        let text = format!(
            r#"<scene version="3.0.0">
<sensor type="perspective"><film type="hdrfilm"><rfilter type="box"/></film></sensor>
<shape type="rectangle"><emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>
<shape type="cube">
{bsdf}{emitter}
</shape>
</scene>
"#
        );
        let path = d.join(format!("k{i}.xml"));
        std::fs::write(&path, text).unwrap();
        let error = Scene::load(&path).unwrap_err().to_string();
        assert!(
            error.contains(expected) && error.contains(&format!("k{i}.xml:")),
            "{bsdf}: {error}"
        );
    }
}
