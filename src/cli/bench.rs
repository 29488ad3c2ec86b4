//! `genpath bench`: ray throughput per back-end, test paths and fitness per second, thread scaling.

use super::args::{load_mixture, MethodArgs};
use super::check_dir;
use anyhow::{Context, Result};
use clap::{ArgMatches, Args};
use genpath::accel::{self, AccelKind, Coherence};
use genpath::genetic::GaConfig;
use genpath::integrators::{prepare, RenderSettings, Settings};
use genpath::path::mixture_file;
use genpath::path::SceneView;
use genpath::report::bench::{
    accel_label, best, best_interleaved, camera_rays, random_rays, ray_rates,
};
use genpath::scene::Scene;
use std::path::PathBuf;
use std::time::Instant;

#[derive(Args)]
pub struct BenchArgs {
    /// Scene whose camera gives the coherent rays and whose bounds the incoherent ones.
    #[arg(default_value = "scenes/fig5/scene.toml")]
    pub scene: PathBuf,
    /// A Mitsuba XML scene parameter, `NAME=VALUE` (its `$NAME`); repeatable.
    #[arg(short = 'D', value_name = "NAME=VALUE", value_parser = super::args::parse_define)]
    pub define: Vec<(String, String)>,
    /// Rays per set: the camera's image is resized to N × N.
    #[arg(long, value_name = "N", default_value_t = 512, value_parser = clap::value_parser!(u32).range(4..=8192))]
    pub rays: u32,
    /// Each figure is the best of this many passes.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..=100))]
    pub passes: u32,
    /// Thread counts of the scaling measurement (default: 1, 2, 4, … up to the cores).
    #[arg(long, value_delimiter = ',', value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub threads: Vec<u32>,
    /// Samples per pixel of each scaling render (at the scene's size).
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..=1 << 16))]
    pub spp: u32,
    /// The method of the scaling renders (prepared once, untimed) and its settings; the GA's
    /// and the estimator's (`--nee`, `--population`, `--test-paths`, …) also set the fitness
    /// measurement's, but for its 10 generations.
    #[command(flatten)]
    pub method: MethodArgs,
    /// Also write the figures as JSON to FILE.
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
}

pub fn run_bench(args: BenchArgs, matches: &ArgMatches) -> Result<()> {
    if let Some(json) = &args.json {
        check_dir(json)?;
    }
    // Settings first, before any loading.
    let mut config = args.method.settings(matches)?;
    let scene = Scene::load_with(&args.scene, &args.define)?;
    let passes = args.passes as usize;
    let rays = ray_throughput(&scene, args.rays, passes)?;
    let accel = accel::build(AccelKind::default_available(), &scene.mesh)?;
    let view = SceneView::new(&scene, accel.as_ref());
    let ga = ga_throughput(&view, &config, passes);
    load_mixture(&mut config, &scene, scene.render.max_bounces)?;
    let scaling = thread_scaling(&view, &args, &config)?;
    if let Some(json) = &args.json {
        let value = serde_json::json!({
            "genpath_version": env!("CARGO_PKG_VERSION"),
            "scene": scene.path,
            "rays_per_set": args.rays * args.rays,
            "passes": passes,
            "cores": cores(),
            "rays": rays,
            "test_paths_per_s": ga["test_paths_per_s"],
            "fitness_evaluations_per_s": ga["fitness_evaluations_per_s"],
            "scaling": scaling,
        });
        genpath::image::write_bytes_atomic(json, serde_json::to_string_pretty(&value)?.as_bytes())?;
    }
    Ok(())
}

fn cores() -> u32 {
    std::thread::available_parallelism().map_or(1, |n| n.get()) as u32
}

/// Mrays/s of every back-end built, single rays and packets, on `n × n` coherent (camera)
/// and incoherent (random in the scene's box) rays, one thread; printed, and as JSON.
fn ray_throughput(scene: &Scene, n: u32, passes: usize) -> Result<Vec<serde_json::Value>> {
    let (lo, hi) = scene.mesh.bounds();
    let sets = [
        (
            "coherent",
            camera_rays(&scene.camera, n, n),
            Coherence::Coherent,
        ),
        (
            "incoherent",
            random_rays(lo, hi, (n * n) as usize, 11),
            Coherence::Incoherent,
        ),
    ];
    println!(
        "{}: {} triangles, {} rays per set, best of {passes}, one thread",
        scene.path.display(),
        scene.mesh.triangles.len(),
        n * n
    );
    println!(
        "{:<11} {:<11} {:>15} {:>15} {:>16} {:>16} {:>6}",
        "back/lanes",
        "rays",
        "closest Mray/s",
        "closest pkt16",
        "occluded Mray/s",
        "occluded pkt16",
        "hit %"
    );
    let mut rays_json = Vec::new();
    for kind in [AccelKind::Embree, AccelKind::Bvh] {
        let accel = match accel::build(kind, &scene.mesh) {
            Ok(accel) => accel,
            Err(accel::AccelError::NotBuilt(name, feature)) => {
                println!("{name:<11} not built (feature `{feature}`)");
                continue;
            }
            Err(e) => return Err(e.into()),
        };
        for (set, rays, coherence) in &sets {
            let r = ray_rates(accel.as_ref(), rays, *coherence, passes);
            println!(
                "{:<11} {set:<11} {:>15.2} {:>15.2} {:>16.2} {:>16.2} {:>6.1}",
                accel_label(accel.as_ref()),
                r.closest_single,
                r.closest_packet,
                r.occluded_single,
                r.occluded_packet,
                100.0 * r.hit_fraction
            );
            rays_json
                .push(serde_json::json!({ "accel": accel.name(), "packet_lanes": accel.packet_lanes(), "rays": set, "mrays_per_s": r }));
        }
    }
    Ok(rays_json)
}

/// Test paths (packets and single rays) and fitness evaluations per second at the image's
/// centre, one thread, with the GA's and the estimator's settings of `config` (the render's
/// flags, e.g. `--nee end`) but 10 generations; printed, and as JSON.
fn ga_throughput(view: &SceneView, config: &Settings, passes: usize) -> serde_json::Value {
    use genpath::genetic::population::evolve;
    use genpath::genetic::test_paths::TestPaths;
    let scene = view.scene;
    let nee = config.srt.nee;
    let ga = GaConfig {
        generations: 10,
        nee,
        srt_absorption: config.srt.absorption(nee),
        ..config.ga.clone()
    };
    let max_bounces = scene.render.max_bounces;
    let q = mixture_file::srt(scene, max_bounces, ga.srt_absorption).with_nee(ga.nee);
    let pixel = (scene.camera.width / 2, scene.camera.height / 2);
    let m = ga.test_paths;
    let [(packet_t, _), (single_t, _)] = best_interleaved(
        passes,
        [
            &mut || {
                TestPaths::sample(view, &q, pixel, m, max_bounces, 1)
                    .0
                    .len()
            },
            &mut || {
                TestPaths::sample_single(view, &q, pixel, m, max_bounces, 1)
                    .0
                    .len()
            },
        ],
    );
    let paths = TestPaths::sample(view, &q, pixel, m, max_bounces, 1).0;
    let start = Instant::now();
    let mut rng = genpath::sampling::sample_rng(1, 0, 0);
    let evolution = evolve(&ga, &paths, view, &mut rng);
    let evolve_s = start.elapsed().as_secs_f64();
    let evaluations = evolution.individual_evaluations as f64 / evolve_s;
    println!(
        "\ntest paths at pixel {pixel:?} ({}): {:.0} k/s in packets, {:.0} k/s single ({} of {m} carry light)",
        view.accel.name(),
        m as f64 / packet_t.as_secs_f64() / 1e3,
        m as f64 / single_t.as_secs_f64() / 1e3,
        paths.len()
    );
    println!(
        "fitness: {evaluations:.0} individual evaluations/s ({} generators evaluated, population {}, M = {m})",
        evolution.generator_evaluations, ga.population
    );
    serde_json::json!({
        "test_paths_per_s": { "packet": m as f64 / packet_t.as_secs_f64(), "single": m as f64 / single_t.as_secs_f64(), "accel": view.accel.name() },
        "fitness_evaluations_per_s": evaluations,
    })
}

/// Render time of `args.method` against the number of threads (prepared once, on every
/// core, untimed), with its rays per second (for `lt`, its light paths' and camera
/// connections' rays); printed, and as JSON.
fn thread_scaling(
    view: &SceneView,
    args: &BenchArgs,
    config: &Settings,
) -> Result<serde_json::Value> {
    let scene = view.scene;
    let passes = args.passes as usize;
    let cores = cores();
    let threads = if args.threads.is_empty() {
        std::iter::successors(Some(1u32), |t| Some(t * 2))
            .take_while(|&t| t < cores)
            .chain([cores])
            .collect()
    } else {
        args.threads.clone()
    };
    let settings = RenderSettings {
        method: args.method.method_or(genpath::integrators::Method::Pt),
        spp: args.spp,
        max_bounces: scene.render.max_bounces,
        seed: 1,
        progress: false,
        shard: Default::default(),
        control: Default::default(),
        learning: None,
    };
    let integrator = prepare(view, config, &settings)?;
    println!(
        "\n{:>7} {:>9} {:>8} {:>10} {:>8}",
        "threads", "seconds", "speedup", "efficiency", "Mrays/s"
    );
    let mut scaling = Vec::new();
    let mut base = None;
    for &t in &threads {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(t as usize)
            .build()
            .context("cannot start the worker threads")?;
        let (elapsed, rays) = best(passes, || {
            pool.install(|| integrator.render(view, &settings))
                .rays
                .total() as usize
        });
        let seconds = elapsed.as_secs_f64();
        let base = *base.get_or_insert(seconds * f64::from(threads[0]));
        let speedup = base / seconds;
        let rays_per_s = rays as f64 / seconds;
        println!(
            "{t:>7} {seconds:>9.3} {speedup:>8.2} {:>10.2} {:>8.3}",
            speedup / f64::from(t),
            rays_per_s / 1e6
        );
        scaling.push(serde_json::json!({ "threads": t, "seconds": seconds, "speedup": speedup, "rays_per_s": rays_per_s }));
    }
    Ok(
        serde_json::json!({ "method": settings.method, "spp": args.spp, "width": scene.camera.width, "height": scene.camera.height, "runs": scaling }),
    )
}
