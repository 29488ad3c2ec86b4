//! Unbiasedness: `srt` and `ga` with next-event estimation at every vertex and at the path's
//! end only, a hand-made anchor mixture, `ga-pt` (with and without the spatial guide), `pg`
//! and `pt` estimate the same image. Per block of pixels, the difference of two methods'
//! means must lie inside a 99.9 % interval (Šidák-corrected over all blocks and channels)
//! computed from their sample variances; and the same comparison must reject a mixture whose
//! one component's density is off by 10 %, an `srt` and a `ga` whose light technique's
//! densities were left out of the balance heuristic, and a `ga` render whose interpolation
//! weights were left unnormalised. On cbox, whose quiet grid cells lend `srt` to the
//! interpolation (fallback points), `ga` agrees with `pt` and its unnormalised weights are
//! rejected. On `spheres.xml` (an emitting sphere, which `pt` samples
//! by its visible cone and the mixtures' light points by area, a disk light, glass and
//! diffuse spheres) the same agreement, and an `srt` without its light technique's density
//! rejected. On a smooth-shaded scene (`scenes/mitsuba/smooth.xml`), the methods agree with
//! `pt` in the shading frame, and `srt` with the shading normals dropped (geometric normals:
//! another image) or with its densities evaluated in the geometric frame (a biased
//! estimator) must be rejected. On `lights.xml` (an environment map, a point, a directional and
//! an area light) every method agrees with `pt`, and an `srt` that leaves a delta light's pick
//! out of its densities is rejected. On `roughglass.xml` (rough glass, GGX and Beckmann)
//! every method agrees with `pt`, and an `srt` whose densities fold refracted directions
//! above the surface is rejected. On `textures.xml` (checkerboard and bitmap textures on
//! diffuse and rough plastic BSDFs) every method agrees with `pt`, and `srt` on the scene
//! with its meshes' texture coordinates dropped is rejected. On `maps.xml` (normal and bump
//! maps) every method agrees with `pt`, and `srt` on the scene with its maps dropped is
//! rejected. On `mask.xml` (opacity masks) every method agrees with `pt`, and an `srt`
//! whose shadow rays stop at every mask is rejected. On `plastic.xml` (smooth plastics, whose
//! vertices choose between a delta reflection and a diffuse lobe, and textured rough glass)
//! every method agrees with `pt`, and an `srt` whose densities count the plastics' diffuse
//! choices is rejected. The GA plan's baseline samples, which the image keeps, agree with
//! `pt` on their own, and the same sums miscounted are rejected.

// The must-reject twins use the fault injections of feature `testing`.
#![cfg(feature = "testing")]

use genpath::accel::{self, AccelKind};
use genpath::film::Film;
use genpath::genetic::plan::{GateConfig, Plan, PlanConfig, PlanFor, PlanInputs};
use genpath::genetic::GaConfig;
use genpath::guiding::selection::Selection;
use genpath::integrators::ga::Ga;
use genpath::integrators::ga_pt::{GaPt, GuidesTrialPolicy};
use genpath::integrators::mixture::MixtureIntegrator;
use genpath::integrators::pg::{train_spatial, Beside, SpatialIntegrator, TrainingSchedule};
use genpath::integrators::pt::PathTracing;
use genpath::integrators::settings::SpatialConfig;
use genpath::integrators::{Integrator, Method, RenderSettings};
use genpath::path::generator::{Nee, PathGenerator};
use genpath::path::mixture::Mixture;
use genpath::path::{mixture_file, SceneView};
use genpath::scene::Scene;
use statrs::distribution::{ContinuousCDF, Normal};
use std::path::{Path, PathBuf};
use std::sync::Arc;

const SIZE: u32 = 64;
const BLOCK: u32 = 32;
const SPP: u32 = 2048;
const SRT_ABSORPTION: f64 = 0.5;

fn scene_dir(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name)
}

enum Which {
    Pt,
    /// `srt` (next-event estimation at every vertex) whose densities are evaluated in the
    /// geometric frame, while its paths are sampled in the shading frame.
    SrtGeometricDensity,
    /// `srt` (next-event estimation at every vertex) on the scene with its shading normals
    /// dropped: every vertex shades with its geometric normal.
    SrtShadedFlat,
    /// `srt` (next-event estimation at every vertex) on the scene with its meshes' texture
    /// coordinates dropped: every triangle's texture coordinates are its barycentrics.
    SrtUvDropped,
    /// `srt` (next-event estimation at every vertex) on the scene with its normal and bump
    /// maps dropped: every vertex scatters about its unperturbed shading normal, as a method
    /// that ignored the maps would.
    SrtMapsDropped,
    /// `srt` (next-event estimation at every vertex) whose shadow rays stop at every masked
    /// surface, while the directions it samples pass through them (fault injection).
    SrtMasksBlockShadows,
    /// `srt` with the estimator `nee`, optionally with the light technique's densities left
    /// out of the balance heuristic's denominator.
    Srt {
        nee: Nee,
        light_dropped: bool,
    },
    /// `srt` (next-event estimation at every vertex) with the probability of a delta light's
    /// pick left out of the densities of the paths that end at one.
    SrtDeltaPickDropped,
    /// `srt` (next-event estimation at every vertex) whose densities evaluate every
    /// direction that went through rough glass at its mirror image above the surface.
    SrtTransmissionFolded,
    /// `srt` (next-event estimation at every vertex) whose densities count the probability
    /// of every smooth plastic's diffuse choice on the path (which the path's value already
    /// divides by).
    SrtPlasticChoiceCounted,
    Anchors {
        pdf_error: Option<f64>,
    },
    /// A small GA (cheap test paths and generations; unbiasedness does not depend on how
    /// well it converged), optionally with unnormalised interpolation weights.
    Ga {
        nee: Nee,
        unnormalised: bool,
        light_dropped: bool,
    },
    /// Path tracing guided by the same small GA's mixtures (`ga-pt`), optionally with the
    /// spatial guide past the GA's vertices.
    GaPt {
        spatial: bool,
    },
    /// Path tracing guided by the spatial guide alone (`pg`), optionally with every cell
    /// dark (next-event estimation at the dark share everywhere, lit cells included).
    Pg {
        every_cell_dark: bool,
    },
    /// `pg` with the share of guided sampling learned per region, optionally with the
    /// densities computed with the fixed share (a deliberately wrong estimator).
    PgLearned {
        fixed_share_density: bool,
    },
}

/// A small GA's plan for `plan_for` with the estimator `nee`, without the gate: every pixel
/// renders with evolved mixtures, the estimator under test.
fn small_plan(
    view: &SceneView,
    (plan_for, nee): (PlanFor, Nee),
    max_bounces: u32,
    seed: u64,
) -> Plan {
    let plan = PlanConfig {
        grid: Some(16),
        ..PlanConfig::default()
    };
    small_plan_with(view, (plan_for, nee), max_bounces, seed, plan)
}

/// [`small_plan`] with the plan's settings `plan`.
fn small_plan_with(
    view: &SceneView,
    (plan_for, nee): (PlanFor, Nee),
    max_bounces: u32,
    seed: u64,
    plan: PlanConfig,
) -> Plan {
    let ga = GaConfig {
        population: 16,
        generations: 8,
        test_paths: 4000,
        ..GaConfig::default()
    };
    let inputs = PlanInputs {
        gate: GateConfig { gate: false },
        srt_absorption: SRT_ABSORPTION.into(),
        nee,
        ..PlanInputs::new(&ga, &plan, plan_for, max_bounces)
    };
    Plan::build(view, &inputs, seed, false).unwrap()
}

/// The scene `name`: `scenes/<name>/scene.toml`, or `scenes/mitsuba/<name>` for an XML one.
fn scene_file(name: &str) -> PathBuf {
    match name.ends_with(".xml") {
        true => scene_dir("mitsuba").join(name),
        false => scene_dir(name).join("scene.toml"),
    }
}

fn render_with(name: &str, which: Which, max_bounces: u32, spp: u32, seed: u64) -> Film {
    let mut scene = Scene::load(&scene_file(name)).unwrap();
    scene.resize(SIZE, SIZE);
    let mut block_shadows = false;
    let which = match which {
        Which::SrtShadedFlat => {
            assert!(
                !scene.shading.normals.is_empty(),
                "{name} has no shading normals"
            );
            scene.shading.normals.clear();
            Which::Srt {
                nee: Nee::Every,
                light_dropped: false,
            }
        }
        Which::SrtUvDropped => {
            assert!(
                !scene.shading.uvs.is_empty(),
                "{name} has no texture coordinates"
            );
            scene.shading.uvs.clear();
            Which::Srt {
                nee: Nee::Every,
                light_dropped: false,
            }
        }
        Which::SrtMapsDropped => {
            let mut dropped = 0;
            for m in &mut scene.materials {
                let Some(textures) = m.textures.as_mut() else {
                    continue;
                };
                if textures.perturbation.is_some() {
                    Arc::make_mut(textures).perturbation = None;
                    dropped += 1;
                }
            }
            assert!(dropped > 0, "{name} has no normal or bump maps");
            Which::Srt {
                nee: Nee::Every,
                light_dropped: false,
            }
        }
        Which::SrtMasksBlockShadows => {
            block_shadows = true;
            Which::Srt {
                nee: Nee::Every,
                light_dropped: false,
            }
        }
        which => which,
    };
    let accel = accel::build(AccelKind::default_available(), &scene.mesh).unwrap();
    let mut view = SceneView::new(&scene, accel.as_ref());
    if block_shadows {
        assert!(view.has_masks(), "{name} has no masks");
        view.fault_masks_block_shadows = true;
    }
    let view = view;
    let mut plan = None;
    let mut guided = false;
    let mut spatial = None;
    let settings = RenderSettings {
        method: Method::Pt,
        spp,
        max_bounces,
        seed,
        progress: false,
        shard: Default::default(),
        control: Default::default(),
        learning: None,
    };
    // The guide trains on half the samples (the default), which stay in the image.
    let train_with = |plan: Option<&Plan>, selection| {
        let schedule = TrainingSchedule::new(&SpatialConfig::default(), spp);
        let beside = plan.map(|plan| Beside {
            plan,
            trial: &GuidesTrialPolicy,
        });
        let t = train_spatial(&view, &settings, (schedule, selection), beside).unwrap();
        assert!(
            t.guide.stats.trained_cells > 0 && t.samples.spp > 1,
            "{name}: the spatial guide did not train"
        );
        Some(t)
    };
    let train = |plan| train_with(plan, Selection::Fixed);
    let mixture = match which {
        Which::Pt => None,
        Which::Pg { every_cell_dark } => {
            let mut t = train(None).unwrap();
            // fig1's lower room never sees the light: next-event estimation there runs at
            // the dark cells' share, and this test covers its weights.
            assert!(
                name != "fig1" || t.guide.stats.dark_cells > 0,
                "{name}: no dark cells"
            );
            if every_cell_dark {
                t.guide = Arc::new(Arc::unwrap_or_clone(t.guide).with_every_cell_dark());
            }
            spatial = Some(t);
            None
        }
        Which::PgLearned {
            fixed_share_density,
        } => {
            let mut t = train_with(None, Selection::Learned).unwrap();
            let stats = t.guide.stats.selection.clone().expect("shares learned");
            eprintln!("{name}: learned shares {stats:?}");
            assert!(
                stats.at_min > 0,
                "{name}: no region learned to leave its directions to the BSDF"
            );
            if fixed_share_density {
                t.guide = Arc::new(Arc::unwrap_or_clone(t.guide).with_fixed_share_density());
            }
            spatial = Some(t);
            None
        }
        Which::GaPt { spatial: with } => {
            plan = Some(small_plan(
                &view,
                (PlanFor::Guide, Nee::default()),
                max_bounces,
                seed,
            ));
            guided = true;
            if with {
                spatial = train(plan.as_ref());
            }
            None
        }
        Which::Ga {
            nee,
            unnormalised,
            light_dropped,
        } => {
            let mut p = small_plan(&view, (PlanFor::Mixture, nee), max_bounces, seed);
            assert!(
                p.pixels.iter().any(|p| !p.kept_srt),
                "{name}: the GA improved on srt nowhere, so the test would only test srt"
            );
            assert!(p.pixels.iter().all(|p| p.mixture.nee == nee));
            if light_dropped {
                p = p.with_light_density_dropped();
            }
            plan = Some(if unnormalised {
                p.with_unnormalised_interpolation()
            } else {
                p
            });
            None
        }
        Which::Srt { nee, light_dropped } => {
            let srt = Mixture::new(
                vec![PathGenerator::srt(
                    max_bounces,
                    nee.default_srt_absorption(),
                    mixture_file::uniform_light(&scene),
                )],
                vec![1.0],
            )
            .with_nee(nee);
            Some(match light_dropped {
                true => srt.with_light_density_dropped(),
                false => srt,
            })
        }
        Which::SrtShadedFlat
        | Which::SrtUvDropped
        | Which::SrtMapsDropped
        | Which::SrtMasksBlockShadows => {
            unreachable!("replaced above")
        }
        Which::SrtDeltaPickDropped => Some(
            Mixture::new(
                vec![PathGenerator::srt(
                    max_bounces,
                    SRT_ABSORPTION,
                    mixture_file::uniform_light(&scene),
                )],
                vec![1.0],
            )
            .with_nee(Nee::Every)
            .with_delta_pick_dropped(),
        ),
        Which::SrtTransmissionFolded => Some(
            Mixture::new(
                vec![PathGenerator::srt(
                    max_bounces,
                    SRT_ABSORPTION,
                    mixture_file::uniform_light(&scene),
                )],
                vec![1.0],
            )
            .with_nee(Nee::Every)
            .with_transmission_folded_density(),
        ),
        Which::SrtPlasticChoiceCounted => Some(
            Mixture::new(
                vec![PathGenerator::srt(
                    max_bounces,
                    Nee::Every.default_srt_absorption(),
                    mixture_file::uniform_light(&scene),
                )],
                vec![1.0],
            )
            .with_nee(Nee::Every)
            .with_plastic_choice_in_density(),
        ),
        Which::SrtGeometricDensity => Some(
            Mixture::new(
                vec![PathGenerator::srt(
                    max_bounces,
                    SRT_ABSORPTION,
                    mixture_file::uniform_light(&scene),
                )],
                vec![1.0],
            )
            .with_nee(Nee::Every)
            .with_geometric_frame_density(),
        ),
        Which::Anchors { pdf_error } => {
            let m = mixture_file::load(
                &scene_dir(name).join("anchors.toml"),
                &scene,
                max_bounces,
                SRT_ABSORPTION,
            )
            .unwrap();
            Some(match pdf_error {
                Some(factor) => m.with_pdf_error(1, factor),
                None => m,
            })
        }
    };
    let integrator: Box<dyn Integrator> = match (plan, mixture, spatial) {
        (plan, _, Some(training)) => Box::new(SpatialIntegrator {
            method: if plan.is_some() {
                Method::GaPt
            } else {
                Method::Pg
            },
            plan,
            training,
            max_bounces,
            keeps_taken: true,
            from_plan_file: false,
        }),
        (Some(plan), _, None) if guided => Box::new(GaPt {
            plan,
            max_bounces,
            from_plan_file: false,
        }),
        // The plan's baseline samples (`srt`) stay in the image.
        (Some(plan), _, None) => Box::new(Ga {
            plan,
            max_bounces,
            keeps_taken: true,
            from_plan_file: false,
        }),
        (None, Some(mixture), None) => Box::new(MixtureIntegrator {
            mixture,
            max_bounces,
        }),
        (None, None, None) => Box::new(PathTracing { max_bounces }),
    };
    integrator.render(&view, &settings)
}

/// Per block and channel: (mean, variance of that mean).
fn block_means(film: &Film) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    for by in (0..SIZE).step_by(BLOCK as usize) {
        for bx in (0..SIZE).step_by(BLOCK as usize) {
            for c in 0..3 {
                let (mut sum, mut var) = (0.0, 0.0);
                for y in by..by + BLOCK {
                    for x in bx..bx + BLOCK {
                        sum += film.image.get(x, y)[c] as f64;
                        var += film.variance_of_mean[(y * SIZE + x) as usize][c];
                    }
                }
                let n = (BLOCK * BLOCK) as f64;
                out.push((sum / n, var / (n * n)));
            }
        }
    }
    out
}

/// Critical |z| of a two-sided 99.9 % interval, Šidák-corrected over `comparisons`.
fn z_critical(comparisons: usize) -> f64 {
    let alpha = 1.0 - 0.999f64.powf(1.0 / comparisons as f64);
    Normal::new(0.0, 1.0)
        .unwrap()
        .inverse_cdf(1.0 - alpha / 2.0)
}

/// Largest |z| over blocks and channels, and the largest relative standard error.
fn compare(a: &Film, b: &Film) -> (f64, f64, usize) {
    let (a, b) = (block_means(a), block_means(b));
    let mut max_z = 0.0f64;
    let mut max_rel = 0.0f64;
    for ((ma, va), (mb, vb)) in a.iter().zip(&b) {
        let se = (va + vb).sqrt();
        if se > 0.0 {
            max_z = max_z.max((ma - mb).abs() / se);
            max_rel = max_rel.max(se / ma.abs().max(mb.abs()).max(1e-12));
        } else {
            assert_eq!(ma, mb, "zero variance but different means");
        }
    }
    (max_z, max_rel, a.len())
}

/// `film` (`what`) estimates what `pt` does: every block inside its interval, and sharp
/// enough to mean something (every block known to 2.5 % or better).
fn assert_agrees(what: &str, film: &Film, pt: &Film) {
    let (z, rel, n) = compare(film, pt);
    let zc = z_critical(n);
    eprintln!("{what} vs pt: max |z| {z:.2} (critical {zc:.2}), worst relative se {rel:.4}");
    assert!(z <= zc, "{what} vs pt: max |z| {z:.2} > {zc:.2}");
    assert!(
        rel < 0.025,
        "{what}: relative standard error {rel:.4} too wide"
    );
}

/// A deliberately wrong `film` (`what`) is told apart from `pt`: some block outside its
/// interval.
fn assert_rejected(what: &str, film: &Film, pt: &Film) {
    let (z, _, n) = compare(film, pt);
    let zc = z_critical(n);
    eprintln!("{what}: max |z| {z:.2} (critical {zc:.2})");
    assert!(z > zc, "{what} went unnoticed (max |z| {z:.2})");
}

fn check_agree(name: &str, max_bounces: u32) {
    let pt = render_with(name, Which::Pt, max_bounces, SPP, 11);
    let srt = |nee| Which::Srt {
        nee,
        light_dropped: false,
    };
    let ga = |nee| Which::Ga {
        nee,
        unnormalised: false,
        light_dropped: false,
    };
    for (label, which, spp) in [
        ("srt", srt(Nee::Every), SPP),
        ("srt, nee end", srt(Nee::End), SPP),
        ("anchors", Which::Anchors { pdf_error: None }, SPP),
        ("ga", ga(Nee::Every), SPP),
        ("ga, nee end", ga(Nee::End), SPP),
        ("ga-pt", Which::GaPt { spatial: false }, SPP / 2),
        ("ga-pt, spatial", Which::GaPt { spatial: true }, SPP / 2),
        (
            "pg",
            Which::Pg {
                every_cell_dark: false,
            },
            SPP / 2,
        ),
        (
            "pg, every cell dark",
            Which::Pg {
                every_cell_dark: true,
            },
            SPP / 2,
        ),
    ] {
        let film = render_with(name, which, max_bounces, spp, 23);
        assert_agrees(&format!("{name} n={max_bounces}: {label}"), &film, &pt);
    }
}

fn check_rejects_wrong_pdf(name: &str) {
    let pt = render_with(name, Which::Pt, 5, SPP, 11);
    let wrong = render_with(
        name,
        Which::Anchors {
            pdf_error: Some(1.1),
        },
        5,
        SPP,
        23,
    );
    assert_rejected(&format!("{name}: a component density ×1.1"), &wrong, &pt);
}

#[test]
fn fig5_rejects_unnormalised_interpolation_weights() {
    let pt = render_with("fig5", Which::Pt, 5, SPP / 8, 11);
    let which = Which::Ga {
        nee: Nee::default(),
        unnormalised: true,
        light_dropped: false,
    };
    let wrong = render_with("fig5", which, 5, SPP / 8, 23);
    assert_rejected("fig5: ga with unnormalised interpolation", &wrong, &pt);
}

/// On cbox most grid cells are quiet under the baseline's `srt` samples: without the gate
/// their pixels are fallback points, which lend `srt` to the interpolation beside the GA
/// pixels' mixtures. `ga` so agrees with `pt`, and the same plan with unnormalised
/// interpolation weights (the fallback's among them) is rejected.
#[test]
fn cbox_ga_with_srt_fallback_points_agrees_and_unnormalised_weights_do_not() {
    let mut scene = Scene::load(&scene_file("cbox")).unwrap();
    scene.resize(SIZE, SIZE);
    let accel = accel::build(AccelKind::default_available(), &scene.mesh).unwrap();
    let view = SceneView::new(&scene, accel.as_ref());
    let plan = small_plan(&view, (PlanFor::Mixture, Nee::Every), 5, 23);
    eprintln!(
        "cbox: {} GA pixels, {} fallback points",
        plan.pixels.len(),
        plan.fallback_points.len()
    );
    assert!(
        !plan.fallback_points.is_empty() && !plan.pixels.is_empty(),
        "cbox's plan must have both for this test"
    );
    let pt = render_with("cbox", Which::Pt, 5, SPP / 4, 11);
    let ga = |unnormalised| Which::Ga {
        nee: Nee::Every,
        unnormalised,
        light_dropped: false,
    };
    let film = render_with("cbox", ga(false), 5, SPP / 4, 23);
    assert_agrees("cbox: ga with srt fallback points", &film, &pt);
    let wrong = render_with("cbox", ga(true), 5, SPP / 4, 23);
    assert_rejected("cbox: ga with unnormalised interpolation", &wrong, &pt);
}

/// The GA plan's baseline samples (`srt`, which the image of `ga` keeps) are
/// samples of the image like any other: on fig5 and on `lights.xml` (whose camera rays that
/// miss see the environment map), an image of the baseline's samples alone (a render of
/// as many samples as the baseline took) agrees with `pt`; the same sums counted as half as
/// many samples (the render then adds the other half from the GA's mixtures) are rejected.
#[test]
fn baseline_samples_agree_and_miscounted_ones_do_not() {
    let spp = SPP / 2;
    for name in ["fig5", "lights.xml"] {
        let mut scene = Scene::load(&scene_file(name)).unwrap();
        scene.resize(SIZE, SIZE);
        let accel = accel::build(AccelKind::default_available(), &scene.mesh).unwrap();
        let view = SceneView::new(&scene, accel.as_ref());
        let config = PlanConfig {
            grid: Some(16),
            baseline_spp: spp,
            ..PlanConfig::default()
        };
        let plan = small_plan_with(&view, (PlanFor::Mixture, Nee::Every), 5, 23, config);
        assert_eq!(plan.baseline().map(|b| b.spp), Some(spp), "{name}");
        let settings = RenderSettings {
            method: Method::Ga,
            spp,
            max_bounces: 5,
            seed: 23,
            progress: false,
            shard: Default::default(),
            control: Default::default(),
            learning: None,
        };
        let render = |plan: Plan| {
            let ga = Ga {
                plan,
                max_bounces: 5,
                keeps_taken: true,
                from_plan_file: false,
            };
            ga.render(&view, &settings)
        };
        let pt = render_with(name, Which::Pt, 5, spp, 11);
        let film = render(plan.clone());
        assert_eq!(film.spp, spp, "{name}: the image is the baseline's alone");
        assert_agrees(&format!("{name}: the baseline's samples"), &film, &pt);
        let mut miscounted = plan;
        miscounted.baseline.spp /= 2;
        let wrong = render(miscounted);
        assert_rejected(&format!("{name}: the baseline miscounted"), &wrong, &pt);
    }
}

/// With next-event estimation at every vertex, `srt` and `ga` whose mixtures leave the light
/// technique's densities out of the balance heuristic (each path then counts about twice
/// where both techniques can make it) must be told apart from `pt`.
#[test]
fn fig5_rejects_a_dropped_light_density() {
    let pt = render_with("fig5", Which::Pt, 5, SPP / 8, 11);
    for (label, which) in [
        (
            "srt",
            Which::Srt {
                nee: Nee::Every,
                light_dropped: true,
            },
        ),
        (
            "ga",
            Which::Ga {
                nee: Nee::Every,
                unnormalised: false,
                light_dropped: true,
            },
        ),
    ] {
        let wrong = render_with("fig5", which, 5, SPP / 8, 23);
        let what = format!("fig5: {label} without the light technique's density");
        assert_rejected(&what, &wrong, &pt);
    }
}

#[test]
fn fig5_methods_agree() {
    check_agree("fig5", 3);
    check_agree("fig5", 5);
}

#[test]
fn fig1_methods_agree() {
    check_agree("fig1", 3);
    check_agree("fig1", 5);
}

#[test]
fn fig5_rejects_a_wrong_component_density() {
    check_rejects_wrong_pdf("fig5");
}

#[test]
fn fig1_rejects_a_wrong_component_density() {
    check_rejects_wrong_pdf("fig1");
}

/// Spheres and a disk: `srt` (either estimator), `ga`, `ga-pt` and `pg` estimate what `pt`
/// does, and an `srt` whose light technique's densities were left out of the balance
/// heuristic does not.
#[test]
fn spheres_methods_agree_and_a_dropped_light_density_does_not() {
    let name = "spheres.xml";
    let spp = SPP / 4;
    let pt = render_with(name, Which::Pt, 4, spp, 11);
    let srt = |nee, light_dropped| Which::Srt { nee, light_dropped };
    for (label, which) in [
        ("srt", srt(Nee::Every, false)),
        ("srt, nee end", srt(Nee::End, false)),
        (
            "ga",
            Which::Ga {
                nee: Nee::Every,
                unnormalised: false,
                light_dropped: false,
            },
        ),
        ("ga-pt", Which::GaPt { spatial: false }),
        (
            "pg",
            Which::Pg {
                every_cell_dark: false,
            },
        ),
    ] {
        let film = render_with(name, which, 4, spp, 23);
        assert_agrees(&format!("{name}: {label}"), &film, &pt);
    }
    let wrong = render_with(name, srt(Nee::Every, true), 4, spp, 23);
    let what = format!("{name}: srt without the light technique's density");
    assert_rejected(&what, &wrong, &pt);
}

/// Shading normals: on `smooth.xml` (a diffuse sphere and a copper icosphere, smooth-shaded)
/// `srt` and `ga` with either estimator, `ga-pt` with the spatial guide and `pg` agree with
/// `pt`, every one sampling and weighing BSDFs in the shading frame; `srt` on the scene
/// shaded flat (its shading normals dropped) must not, nor `srt` whose mixture densities
/// are evaluated in the geometric frame (the balance heuristic's frame not the sampler's).
#[test]
fn smooth_shading_methods_agree_and_a_wrong_frame_does_not() {
    let name = "smooth.xml";
    let bounces = 3;
    let pt = render_with(name, Which::Pt, bounces, SPP / 2, 11);
    let srt = |nee| Which::Srt {
        nee,
        light_dropped: false,
    };
    let ga = |nee| Which::Ga {
        nee,
        unnormalised: false,
        light_dropped: false,
    };
    for (label, which) in [
        ("srt", srt(Nee::Every)),
        ("srt, nee end", srt(Nee::End)),
        ("ga", ga(Nee::Every)),
        ("ga, nee end", ga(Nee::End)),
        ("ga-pt, spatial", Which::GaPt { spatial: true }),
        (
            "pg",
            Which::Pg {
                every_cell_dark: false,
            },
        ),
    ] {
        let film = render_with(name, which, bounces, SPP / 2, 23);
        assert_agrees(&format!("{name}: {label}"), &film, &pt);
    }
    for (label, which) in [
        ("srt shaded flat", Which::SrtShadedFlat),
        (
            "srt with densities in the geometric frame",
            Which::SrtGeometricDensity,
        ),
    ] {
        let wrong = render_with(name, which, bounces, SPP / 2, 23);
        assert_rejected(&format!("{name}: {label}"), &wrong, &pt);
    }
}

/// Every method beside `pt` with its defaults: `srt` and `ga` with either estimator, `ga-pt`
/// with and without the spatial guide, and `pg`.
fn every_method() -> [(&'static str, Which); 7] {
    let srt = |nee| Which::Srt {
        nee,
        light_dropped: false,
    };
    let ga = |nee| Which::Ga {
        nee,
        unnormalised: false,
        light_dropped: false,
    };
    [
        ("srt", srt(Nee::Every)),
        ("srt, nee end", srt(Nee::End)),
        ("ga", ga(Nee::Every)),
        ("ga, nee end", ga(Nee::End)),
        ("ga-pt", Which::GaPt { spatial: false }),
        ("ga-pt, spatial", Which::GaPt { spatial: true }),
        (
            "pg",
            Which::Pg {
                every_cell_dark: false,
            },
        ),
    ]
}

/// Every kind of emitter at once (`lights.xml`: an environment map with a small bright sun, a
/// point light, a directional light and an area light, each picked by light sampling with
/// probability 1/4): `srt` and `ga` with either estimator, `ga-pt` (with and without the
/// spatial guide) and `pg` estimate what `pt` does, and an `srt` that leaves a delta light's
/// pick out of its densities (as if it were the only emitter) does not.
#[test]
fn lights_methods_agree_and_a_dropped_delta_pick_does_not() {
    let name = "lights.xml";
    let (bounces, spp) = (4, SPP / 4);
    let pt = render_with(name, Which::Pt, bounces, spp, 11);
    for (label, which) in every_method() {
        let film = render_with(name, which, bounces, spp, 23);
        assert_agrees(&format!("{name}: {label}"), &film, &pt);
    }
    let wrong = render_with(name, Which::SrtDeltaPickDropped, bounces, spp, 23);
    let what = format!("{name}: srt without the delta lights' pick in its densities");
    assert_rejected(&what, &wrong, &pt);
}

/// Rough glass (`roughglass.xml`: a GGX `roughdielectric` slab with a light and a diffuse
/// block behind it, a Beckmann sphere sampled from the whole distribution), the first
/// non-delta BSDF that transmits: `srt` and `ga` with either estimator, `ga-pt` (with and
/// without the spatial guide) and `pg` estimate what `pt` does, through next-event
/// estimation of lights behind the surface, refraction's `|cos|` and the guide's and the
/// generators' densities below the surface; an `srt` whose densities take every refracted
/// direction for its mirror image above the surface does not.
#[test]
fn roughglass_methods_agree_and_a_folded_transmission_density_does_not() {
    let name = "roughglass.xml";
    let (bounces, spp) = (5, SPP);
    let pt = render_with(name, Which::Pt, bounces, spp, 11);
    let srt = |nee| Which::Srt {
        nee,
        light_dropped: false,
    };
    let ga = |nee| Which::Ga {
        nee,
        unnormalised: false,
        light_dropped: false,
    };
    // The end-only estimator, whose light is found at the paths' ends alone, twice the
    // samples (at `SPP` its worst block is known to 2.6 % only).
    for (label, which, spp) in [
        ("srt", srt(Nee::Every), spp),
        ("srt, nee end", srt(Nee::End), 2 * spp),
        ("ga", ga(Nee::Every), spp),
        ("ga, nee end", ga(Nee::End), 2 * spp),
        ("ga-pt", Which::GaPt { spatial: false }, spp),
        ("ga-pt, spatial", Which::GaPt { spatial: true }, spp),
        (
            "pg",
            Which::Pg {
                every_cell_dark: false,
            },
            spp,
        ),
    ] {
        let film = render_with(name, which, bounces, spp, 23);
        assert_agrees(&format!("{name}: {label}"), &film, &pt);
    }
    let wrong = render_with(name, Which::SrtTransmissionFolded, bounces, spp, 23);
    let what = format!("{name}: srt with refracted directions' densities folded above the surface");
    assert_rejected(&what, &wrong, &pt);
}

/// Textures (`textures.xml`: checkerboards and a bitmap on diffuse and rough plastic BSDFs,
/// on rectangles, an OBJ, an analytic sphere and a cube): `srt` and `ga` with either
/// estimator, `ga-pt` (with and without the spatial guide) and `pg` estimate what `pt`
/// does, each evaluating the textured BSDF at every vertex, its own and the other
/// generators'; `srt` on the scene with its meshes' texture coordinates dropped does not.
#[test]
fn textures_methods_agree_and_dropped_texture_coordinates_do_not() {
    let name = "textures.xml";
    let (bounces, spp) = (3, SPP / 4);
    let pt = render_with(name, Which::Pt, bounces, spp, 11);
    for (label, which) in every_method() {
        let film = render_with(name, which, bounces, spp, 23);
        assert_agrees(&format!("{name}: {label}"), &film, &pt);
    }
    let wrong = render_with(name, Which::SrtUvDropped, bounces, spp, 23);
    assert_rejected(
        &format!("{name}: srt without texture coordinates"),
        &wrong,
        &pt,
    );
}

/// Normal and bump maps (`maps.xml`: a `normalmap` and a `bumpmap` around diffuse, rough
/// plastic and rough conductor BSDFs, with `twosided` around and inside them): `srt` and
/// `ga` with either estimator, `ga-pt` (with and without the spatial guide) and `pg`
/// estimate what `pt` does, each scattering in the perturbed frame at every vertex, its own
/// and the other generators'; `srt` on the scene with its maps dropped (what a method that
/// ignored them would render) does not. (An `srt` whose densities alone leave the maps out,
/// `SrtGeometricDensity`, goes unnoticed here: max |z| 1.44 at these samples; its error is
/// a rare, heavy-tailed weight near grazing directions.)
#[test]
fn maps_methods_agree_and_dropped_maps_do_not() {
    let name = "maps.xml";
    let (bounces, spp) = (3, SPP / 4);
    let pt = render_with(name, Which::Pt, bounces, spp, 11);
    for (label, which) in every_method() {
        let film = render_with(name, which, bounces, spp, 23);
        assert_agrees(&format!("{name}: {label}"), &film, &pt);
    }
    let wrong = render_with(name, Which::SrtMapsDropped, bounces, spp, 23);
    assert_rejected(
        &format!("{name}: srt without the normal and bump maps"),
        &wrong,
        &pt,
    );
}

/// Opacity masks (`mask.xml`: Mitsuba's `mask` with a bitmap, a checkerboard and a constant
/// opacity around twosided diffuse, one-sided diffuse and rough plastic BSDFs): `srt` and
/// `ga` with either estimator, `ga-pt` (with and without the spatial guide) and `pg`
/// estimate what `pt` does, their rays passing through the masks at random; an `srt` whose
/// shadow rays stop at every masked surface (while its sampled directions pass through
/// them) does not.
#[test]
fn mask_methods_agree_and_opaque_shadow_rays_do_not() {
    let name = "mask.xml";
    let (bounces, spp) = (3, SPP / 4);
    let pt = render_with(name, Which::Pt, bounces, spp, 11);
    for (label, which) in every_method() {
        let film = render_with(name, which, bounces, spp, 23);
        assert_agrees(&format!("{name}: {label}"), &film, &pt);
    }
    let wrong = render_with(name, Which::SrtMasksBlockShadows, bounces, spp, 23);
    assert_rejected(
        &format!("{name}: srt with masks opaque to shadow rays"),
        &wrong,
        &pt,
    );
}

/// Smooth plastics (`plastic.xml`: a plastic floor over a checkerboard, a plastic sphere
/// with a textured coating, and a pane of rough glass with textured transmittance and
/// reflectance), whose vertices choose between a delta reflection and a diffuse lobe where a
/// ray meets them: `srt` and `ga` with either estimator, `ga-pt` (with and without the
/// spatial guide) and `pg` estimate what `pt` does, each taking the same choice at a vertex
/// (a delta vertex, or a diffuse one with its light sample, step or guide); an `srt` whose
/// densities count the diffuse choices' probabilities (already in the paths' values) does
/// not.
#[test]
fn plastic_methods_agree_and_a_counted_choice_does_not() {
    let name = "plastic.xml";
    let (bounces, spp) = (3, SPP / 4);
    let pt = render_with(name, Which::Pt, bounces, spp, 11);
    for (label, which) in every_method() {
        let film = render_with(name, which, bounces, spp, 23);
        assert_agrees(&format!("{name}: {label}"), &film, &pt);
    }
    let wrong = render_with(name, Which::SrtPlasticChoiceCounted, bounces, spp, 23);
    assert_rejected(
        &format!("{name}: srt with the plastics' choices in its densities"),
        &wrong,
        &pt,
    );
}

/// `pg` with the share of guided sampling learned per region estimates what `pt` does on
/// glossy (Phong lobes, where a region of the guide learns to leave directions to the
/// BSDF), and the same guide sampling with its learned shares but weighing with the fixed
/// one is told apart.
#[test]
fn glossy_learned_guide_shares_agree_and_fixed_share_densities_do_not() {
    // Three bounces and an eighth of the samples of the tests above keep it to seconds: the
    // worst block is still known to 0.7 %, and the wrong estimate lies far outside (|z| 26).
    let pt = render_with("glossy", Which::Pt, 3, SPP / 4, 11);
    let learned = |fixed_share_density| Which::PgLearned {
        fixed_share_density,
    };
    let film = render_with("glossy", learned(false), 3, SPP / 8, 23);
    assert_agrees("glossy: pg, learned shares", &film, &pt);
    let wrong = render_with("glossy", learned(true), 3, SPP / 8, 23);
    assert_rejected("glossy: pg, learned shares weighed as 1/2", &wrong, &pt);
}
