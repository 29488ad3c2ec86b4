//! Furnace known answer: inside a closed box whose every face has albedo ρ and emits Le,
//! the radiance with at most n scattering events is Le·Σ_{k=0..n} ρ^k everywhere.

mod common;

use genpath::accel::{self, AccelKind};
use genpath::integrators::pt::PathTracing;
use genpath::integrators::{Integrator, Method, RenderSettings};
use genpath::path::SceneView;
use genpath::scene::Scene;

const RHO: f32 = 0.5;
const LE: f32 = 1.0;
/// Two-sided 99.9 % normal quantile.
const Z: f64 = 3.29;

/// Renders the furnace with albedo `rho` and returns (estimate, standard error).
fn furnace(rho: f32, max_bounces: u32) -> (f64, f64) {
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
    let accel = accel::build(AccelKind::default_available(), &scene.mesh).unwrap();
    let view = SceneView::new(&scene, accel.as_ref());
    let settings = RenderSettings {
        method: Method::Pt,
        spp: 64,
        max_bounces,
        seed: 7,
        progress: false,
        shard: Default::default(),
    };
    let film = PathTracing { max_bounces }.render(&view, &settings);
    let n = film.image.pixels.len() as f64;
    let mean = film.image.pixels.iter().map(|p| p[0] as f64).sum::<f64>() / n;
    let var_of_grand_mean = film.variance_of_mean.iter().map(|v| v[0]).sum::<f64>() / (n * n);
    (mean, var_of_grand_mean.sqrt())
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
    for max_bounces in [0, 1, 3, 5] {
        let (estimate, stderr) = furnace(RHO, max_bounces);
        let expected = analytic(max_bounces);
        assert!(
            within_interval(estimate, stderr, expected),
            "n={max_bounces}: {estimate} ± {stderr} vs {expected}"
        );
        // The test must be sharp enough to see the 2 % perturbation below.
        assert!(
            stderr < 0.002 * expected,
            "n={max_bounces}: interval too wide ({stderr})"
        );
    }
}

#[test]
fn furnace_rejects_albedo_off_by_two_percent() {
    for max_bounces in [3, 5] {
        let (estimate, stderr) = furnace(RHO * 1.02, max_bounces);
        let expected = analytic(max_bounces);
        assert!(
            !within_interval(estimate, stderr, expected),
            "n={max_bounces}: perturbed albedo not detected: {estimate} ± {stderr} vs {expected}"
        );
    }
}
