//! Furnace known answer: inside a closed box whose every face has albedo ρ and emits Le,
//! the radiance with at most n scattering events is Le·Σ_{k=0..n} ρ^k everywhere: for `pt`,
//! and for `srt` and `ga` with next-event estimation at every vertex (where every path has
//! both techniques, so the balance heuristic over them is what is tested).
//!
//! And the white furnace under an environment (Mitsuba's `constant` emitter, radiance L):
//! an open box of albedo 1 (two-sided) looks exactly L from everywhere, inside and out, for
//! `pt`, `srt` (either estimator) and `ga`, per block of pixels; with the environment's
//! density 50 % off where it is evaluated (`Environment::with_pdf_error`: `pt`'s light
//! sampling, the mixtures' density of paths that escaped) it must not.

mod common;

use genpath::accel::{self, AccelKind};
use genpath::film::Film;
use genpath::integrators::{prepare, Method, RenderSettings, Settings};
use genpath::path::generator::Nee;
use genpath::path::SceneView;
use genpath::scene::Scene;

const RHO: f32 = 0.5;
const LE: f32 = 1.0;
/// Two-sided 99.9 % normal quantile.
const Z: f64 = 3.29;

/// The methods under test, with their samples per pixel (enough for each to see the 2 %
/// perturbation below: `srt`'s Russian roulette at every vertex costs it samples against
/// `pt`). The paper's end-only estimator is left out: a light point alone at the last bounce
/// has unbounded variance in the furnace's corners, where emitters meet the surfaces.
const METHODS: [(Method, Nee, u32); 3] = [
    (Method::Pt, Nee::Every, 64),
    (Method::Srt, Nee::Every, 256),
    (Method::Ga, Nee::Every, 256),
];

/// Renders the furnace with albedo `rho` by `method` with the estimator `nee` (for `srt`
/// and `ga`) and returns (estimate, standard error).
fn furnace(rho: f32, max_bounces: u32, (method, nee, spp): (Method, Nee, u32)) -> (f64, f64) {
    let dir = tempfile::tempdir().unwrap();
    let mtl = format!("newmtl box\nKd {RHO} {RHO} {RHO}\nKe {LE} {LE} {LE}\n");
    let path = common::write_files(
        dir.path(),
        &[
            (
                "box.toml",
                &common::scene_toml("box.obj", [0.1, -0.2, 0.3], [0.5, 0.2, -1.0], 32),
            ),
            ("box.obj", &common::closed_box_obj()),
            ("box.mtl", &mtl),
        ],
    );
    let mut scene = Scene::load(&path).unwrap();
    // The renderer sees `rho`, the analytic answer below uses RHO: a deliberate perturbation.
    for m in &mut scene.materials {
        m.kd = glam::Vec3::splat(rho);
    }
    let film = render_small_ga(&scene, (method, nee, spp), max_bounces, 7, &[]);
    let n = film.image.pixels.len() as f64;
    let mean = film.image.pixels.iter().map(|p| p[0] as f64).sum::<f64>() / n;
    let var_of_grand_mean = film.variance_of_mean.iter().map(|v| v[0]).sum::<f64>() / (n * n);
    (mean, var_of_grand_mean.sqrt())
}

/// `scene` rendered by `method` (`srt` and `ga` with the estimator `nee`) at `spp`, with a
/// small GA without the gate (every pixel renders with evolved mixtures) and the settings
/// `extra`.
fn render_small_ga(
    scene: &Scene,
    (method, nee, spp): (Method, Nee, u32),
    max_bounces: u32,
    seed: u64,
    extra: &[&str],
) -> Film {
    let accel = accel::build(AccelKind::default_available(), &scene.mesh).unwrap();
    let view = SceneView::new(scene, accel.as_ref());
    let settings = RenderSettings {
        method,
        spp,
        max_bounces,
        seed,
        progress: false,
        shard: Default::default(),
        control: Default::default(),
        learning: None,
    };
    let mut config = Settings::default();
    config.srt.nee = nee;
    let small_ga = [
        "gate=false",
        "ga_grid=8",
        "population=12",
        "generations=6",
        "test_paths=2000",
    ];
    for setting in small_ga.iter().chain(extra) {
        config.assign(setting).unwrap();
    }
    prepare(&view, &config, &settings)
        .unwrap()
        .render(&view, &settings)
}

fn analytic(max_bounces: u32) -> f64 {
    (0..=max_bounces)
        .map(|k| (LE * RHO.powi(k as i32)) as f64)
        .sum()
}

fn within_interval(estimate: f64, stderr: f64, expected: f64) -> bool {
    (estimate - expected).abs() <= Z * stderr
}

#[test]
fn furnace_matches_the_geometric_series() {
    for method in METHODS {
        for max_bounces in [0, 1, 3, 5] {
            let (estimate, stderr) = furnace(RHO, max_bounces, method);
            let expected = analytic(max_bounces);
            let m = (method.0, method.1);
            eprintln!("{m:?} n={max_bounces}: {estimate} ± {stderr} vs {expected}");
            assert!(
                within_interval(estimate, stderr, expected),
                "{m:?} n={max_bounces}: {estimate} ± {stderr} vs {expected}"
            );
            // The test must be sharp enough to see the 2 % perturbation below.
            assert!(
                stderr < 0.002 * expected,
                "{m:?} n={max_bounces}: interval too wide ({stderr})"
            );
        }
    }
}

#[test]
fn furnace_rejects_albedo_off_by_two_percent() {
    for method in METHODS {
        for max_bounces in [3, 5] {
            let (estimate, stderr) = furnace(RHO * 1.02, max_bounces, method);
            let expected = analytic(max_bounces);
            assert!(
                !within_interval(estimate, stderr, expected),
                "{:?} n={max_bounces}: perturbed albedo not detected: {estimate} ± {stderr} vs {expected}",
                (method.0, method.1)
            );
        }
    }
}

/// The environment's radiance in the white furnace.
const L_ENV: f32 = 0.8;
/// Pixels per side of a block of the white furnace's per-block test.
const ENV_BLOCK: u32 = 8;

/// An open box (`[-1, 1] × [0, 0.5] × [-1, 1]` without its top) of two-sided albedo 1 under a
/// `constant` emitter of radiance `L_ENV`, seen from above at 32²; unbounded depth.
fn white_furnace_xml() -> String {
    let wall = |transform: &str| {
        format!(
            r#"<shape type="rectangle"><transform name="to_world">{transform}</transform><ref id="white"/></shape>"#
        )
    };
    let walls = [
        wall(r#"<rotate x="1" angle="-90"/>"#),
        wall(r#"<scale y="0.25"/><translate y="0.25" z="-1"/>"#),
        wall(r#"<scale y="0.25"/><translate y="0.25" z="1"/>"#),
        wall(r#"<scale y="0.25"/><rotate y="1" angle="90"/><translate x="-1" y="0.25"/>"#),
        wall(r#"<scale y="0.25"/><rotate y="1" angle="90"/><translate x="1" y="0.25"/>"#),
    ]
    .concat();
    format!(
        r#"<scene version="3.0.0">
    <sensor type="perspective">
        <float name="fov" value="55"/>
        <transform name="to_world"><lookat origin="0.5, 2.4, 1.6" target="0, 0.2, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="32"/><rfilter type="box"/></film>
    </sensor>
    <bsdf type="twosided" id="white"><bsdf type="diffuse"><rgb name="reflectance" value="1"/></bsdf></bsdf>
    <emitter type="constant"><rgb name="radiance" value="{L_ENV}"/></emitter>
    {walls}
</scene>
"#
    )
}

/// The white furnace rendered by `method` (`srt` and `ga` with the estimator `nee`), the
/// environment's density scaled by `pdf_error` where evaluated; the largest |z| of a block
/// mean against `L_ENV` (grey: the first channel), and the Šidák-corrected critical |z|.
fn white_furnace((method, nee, spp): (Method, Nee, u32), pdf_error: Option<f64>) -> (f64, f64) {
    let dir = tempfile::tempdir().unwrap();
    let path = common::write_files(dir.path(), &[("cup.xml", &white_furnace_xml())]);
    let mut scene = Scene::load(&path).unwrap();
    assert!(scene.emitters.prims.is_empty() && scene.environment.is_some());
    if let Some(factor) = pdf_error {
        scene.environment = scene.environment.map(|e| e.with_pdf_error(factor));
    }
    // With albedo 1 a path's weight grows by 1 / (1 − a) per vertex: `srt`'s default
    // absorption of 1/2 would give its estimate infinite variance where paths stay inside
    // the box, and the test's standard errors would mean nothing.
    let bounces = scene.render.max_bounces;
    let film = render_small_ga(
        &scene,
        (method, nee, spp),
        bounces,
        11,
        &["srt_absorption=0.1"],
    );
    let side = scene.camera.width;
    let (mut max_z, mut blocks) = (0.0f64, 0);
    for by in (0..side).step_by(ENV_BLOCK as usize) {
        for bx in (0..side).step_by(ENV_BLOCK as usize) {
            let (mut sum, mut var) = (0.0, 0.0);
            for y in by..by + ENV_BLOCK {
                for x in bx..bx + ENV_BLOCK {
                    sum += f64::from(film.image.get(x, y)[0]);
                    var += film.variance_of_mean[(y * side + x) as usize][0];
                }
            }
            let k = f64::from(ENV_BLOCK * ENV_BLOCK);
            let diff = (sum / k - f64::from(L_ENV)).abs();
            let se = var.sqrt() / k;
            let z = if se > 0.0 {
                diff / se
            } else if diff < 1e-6 {
                0.0
            } else {
                f64::INFINITY
            };
            max_z = max_z.max(z);
            blocks += 1;
        }
    }
    let alpha = 1.0 - 0.999f64.powf(1.0 / f64::from(blocks));
    let critical = statrs::distribution::ContinuousCDF::inverse_cdf(
        &statrs::distribution::Normal::new(0.0, 1.0).unwrap(),
        1.0 - alpha / 2.0,
    );
    (max_z, critical)
}

/// The white furnace's methods, with their samples per pixel.
const ENV_METHODS: [(Method, Nee, u32); 4] = [
    (Method::Pt, Nee::Every, 64),
    (Method::Srt, Nee::Every, 64),
    (Method::Srt, Nee::End, 64),
    (Method::Ga, Nee::Every, 64),
];

#[test]
fn white_furnace_under_an_environment_looks_like_the_environment() {
    for method in ENV_METHODS {
        let (z, critical) = white_furnace(method, None);
        eprintln!("{method:?}: max |z| {z:.2} (critical {critical:.2})");
        assert!(z < critical, "{method:?}: max |z| {z:.2} ≥ {critical:.2}");
    }
}

#[cfg(feature = "testing")]
#[test]
fn white_furnace_rejects_an_environment_density_50_percent_off() {
    for method in ENV_METHODS {
        let (z, critical) = white_furnace(method, Some(1.5));
        eprintln!("{method:?} with the density 50 % off: max |z| {z:.2} (critical {critical:.2})");
        assert!(
            z > critical,
            "{method:?}: an environment density 50 % off went unnoticed: max |z| {z:.2} < {critical:.2}"
        );
    }
}
