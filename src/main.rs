//! The `genpath` command line.

use anyhow::{bail, Context, Result};
use clap::{Args, Parser, Subcommand};
use genpath::accel::{self, AccelKind};
use genpath::genetic::plan::{Plan, PlanConfig};
use genpath::genetic::GaConfig;
use genpath::path::generator::{PathGenerator, ABSORPTION_MAX, ABSORPTION_MIN};
use genpath::path::mixture::Mixture;
use genpath::path::mixture_file;
use genpath::path::{Method, SceneView};
use genpath::render::{self, Estimator, RenderSettings};
use genpath::scene::{Scene, MAX_BOUNCES_LIMIT, MAX_IMAGE_SIDE};
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Parser)]
#[command(
    name = "genpath",
    version,
    about = "Genetic path generation: a Monte Carlo renderer that evolves per-pixel path generators"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene to one or more images (format by extension: .exr, .png, …).
    Render(RenderArgs),
    /// Compare an image with a reference: relMSE, MSE, MAPE, fraction of NaN/Inf/negative pixels.
    Compare(CompareArgs),
}

#[derive(Args)]
struct CompareArgs {
    /// The image to judge (EXR).
    image: PathBuf,
    /// The reference (EXR).
    reference: PathBuf,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

#[derive(Args)]
struct RenderArgs {
    /// Scene description (TOML).
    scene: PathBuf,
    /// Output image; repeat for several formats. A `<FILE>.json` with statistics is written beside each.
    #[arg(short, long = "output", value_name = "FILE", required = true)]
    outputs: Vec<PathBuf>,
    /// Rendering method.
    #[arg(long, value_enum, default_value_t = Method::Pt)]
    method: Method,
    /// Mixture of path generators for `--method mixture` (TOML or JSON; see the README).
    #[arg(long, value_name = "FILE")]
    generators: Option<PathBuf>,
    /// Absorption (Russian-roulette probability) of the `srt` generator at each vertex.
    #[arg(long, default_value_t = 0.5, value_parser = parse_absorption)]
    srt_absorption: f64,
    /// Samples (paths) per pixel.
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..=1 << 24))]
    spp: u32,
    /// Scattering events per path; defaults to the scene's `render.max_bounces`.
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=MAX_BOUNCES_LIMIT as i64))]
    max_bounces: Option<u32>,
    /// Seed of every random stream; the same seed gives the same image for any thread count.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Worker threads (default: all cores).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=4096))]
    threads: Option<u32>,
    /// Ray-tracing back-end.
    #[arg(long, value_enum, default_value_t = AccelKind::default_available())]
    accel: AccelKind,
    /// Override the scene's image width (the horizontal field of view is kept).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_IMAGE_SIDE as i64))]
    width: Option<u32>,
    /// Override the scene's image height.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_IMAGE_SIDE as i64))]
    height: Option<u32>,
    /// No progress bar and no warnings on stderr.
    #[arg(short, long)]
    quiet: bool,
    /// With `--method ga`: also write an image of the GA pixels with their evolved anchor
    /// points and cones drawn over the render.
    #[arg(long, value_name = "FILE")]
    explain: Option<PathBuf>,
    #[command(flatten)]
    ga: GaArgs,
}

/// Settings of `--method ga` (paper §4–5, design §6–7); defaults from `GaConfig::default()`.
#[derive(Args)]
#[command(next_help_heading = "Genetic algorithm (--method ga)")]
struct GaArgs {
    /// Individuals per generation (the paper: 150).
    #[arg(long, default_value_t = GaConfig::default().population as u32, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    population: u32,
    /// Generations, the random first one included (the paper: 200).
    #[arg(long, default_value_t = GaConfig::default().generations as u32, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    generations: u32,
    /// Evolved generators per individual (S), besides the defensive srt one.
    #[arg(long, value_name = "S", default_value_t = GaConfig::default().generators as u32, value_parser = clap::value_parser!(u32).range(1..=64))]
    ga_generators: u32,
    /// Test paths per GA pixel (M of eq. 10), zero-contribution paths included.
    #[arg(long, value_name = "M", default_value_t = GaConfig::default().test_paths as u32, value_parser = clap::value_parser!(u32).range(1..=100_000_000))]
    test_paths: u32,
    /// Best individuals copied unchanged into the next generation (E).
    #[arg(long, value_name = "E", default_value_t = GaConfig::default().elitism)]
    elitism: usize,
    /// Crossover probability per pair of parents.
    #[arg(long, default_value_t = GaConfig::default().p_cross, value_parser = parse_probability)]
    p_cross: f64,
    /// Mutation probability per sampler.
    #[arg(long, default_value_t = GaConfig::default().p_sampler_mutate, value_parser = parse_probability)]
    p_mutate: f64,
    /// Probability per individual that two generators switch positions.
    #[arg(long, default_value_t = GaConfig::default().p_switch, value_parser = parse_probability)]
    p_switch: f64,
    /// Probability per individual of a weight mutation.
    #[arg(long, default_value_t = GaConfig::default().p_weight, value_parser = parse_probability)]
    p_weight: f64,
    /// Probability per generator of an absorption mutation.
    #[arg(long, default_value_t = GaConfig::default().p_absorb, value_parser = parse_probability)]
    p_absorb: f64,
    /// Smallest weight of the defensive srt component of every evolved mixture.
    #[arg(long, default_value_t = GaConfig::default().defensive_weight)]
    defensive_weight: f64,
    /// Standard deviation of an anchor shift, relative to the scene's size.
    #[arg(long, default_value_t = GaConfig::default().anchor_shift)]
    anchor_shift: f64,
    /// Distance between GA pixels on the grid, in pixels.
    #[arg(long, default_value_t = PlanConfig::default().grid, value_parser = clap::value_parser!(u32).range(1..=MAX_IMAGE_SIDE as i64))]
    ga_grid: u32,
    /// Extra GA pixels where the baseline variance is high, as a fraction of the grid's.
    #[arg(long, default_value_t = PlanConfig::default().extra)]
    ga_extra: f64,
    /// srt samples per pixel of the baseline pass that places the extra GA pixels.
    #[arg(long, default_value_t = PlanConfig::default().baseline_spp, value_parser = clap::value_parser!(u32).range(1..=65_536))]
    baseline_spp: u32,
    /// Nearest GA pixels whose mixtures each pixel combines.
    #[arg(long, default_value_t = PlanConfig::default().neighbours)]
    ga_neighbours: usize,
}

impl GaArgs {
    fn configs(&self, srt_absorption: f64) -> Result<(GaConfig, PlanConfig)> {
        let ga = GaConfig {
            population: self.population as usize,
            generations: self.generations as usize,
            generators: self.ga_generators as usize,
            test_paths: self.test_paths as usize,
            elitism: self.elitism,
            p_cross: self.p_cross,
            p_sampler_mutate: self.p_mutate,
            p_switch: self.p_switch,
            p_weight: self.p_weight,
            p_absorb: self.p_absorb,
            defensive_weight: self.defensive_weight,
            srt_absorption,
            anchor_shift: self.anchor_shift,
        };
        let plan = PlanConfig {
            grid: self.ga_grid,
            extra: self.ga_extra,
            baseline_spp: self.baseline_spp,
            neighbours: self.ga_neighbours,
        };
        ga.validate()?;
        plan.validate()?;
        Ok((ga, plan))
    }
}

fn parse_probability(text: &str) -> Result<f64, String> {
    let p: f64 = text.parse().map_err(|e| format!("{e}"))?;
    if (0.0..=1.0).contains(&p) {
        Ok(p)
    } else {
        Err("must be in [0, 1]".into())
    }
}

fn parse_absorption(text: &str) -> Result<f64, String> {
    let a: f64 = text.parse().map_err(|e| format!("{e}"))?;
    if (ABSORPTION_MIN..=ABSORPTION_MAX).contains(&a) {
        Ok(a)
    } else {
        Err(format!("must be in [{ABSORPTION_MIN}, {ABSORPTION_MAX}]"))
    }
}

fn main() {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render(args) => run_render(args),
        Command::Compare(args) => run_compare(args),
    };
    if let Err(error) = result {
        eprintln!("genpath: error: {error:#}");
        std::process::exit(1);
    }
}

/// Fails before any work when an output cannot possibly be written.
fn check_output(path: &Path) -> Result<()> {
    genpath::image::check_format(path)?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        bail!(
            "{}: directory {} does not exist",
            path.display(),
            dir.display()
        );
    }
    Ok(())
}

fn run_render(args: RenderArgs) -> Result<()> {
    for output in &args.outputs {
        check_output(output)?;
    }
    if let Some(explain) = &args.explain {
        if args.method != Method::Ga {
            bail!("--explain is only used with --method ga");
        }
        check_output(explain)?;
    }
    let (ga_config, plan_config) = args.ga.configs(args.srt_absorption)?;
    let t_load = Instant::now();
    let mut scene = Scene::load(&args.scene)?;
    if args.width.is_some() || args.height.is_some() {
        scene.resize(
            args.width.unwrap_or(scene.camera.width),
            args.height.unwrap_or(scene.camera.height),
        );
    }
    if !args.quiet {
        for warning in &scene.warnings {
            eprintln!("genpath: warning: {warning}");
        }
    }
    let load_s = t_load.elapsed().as_secs_f64();

    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.unwrap_or(0) as usize)
        .build()
        .context("cannot start the worker threads")?;
    let t_accel = Instant::now();
    let accel = accel::build(args.accel, &scene.mesh)?;
    let accel_s = t_accel.elapsed().as_secs_f64();

    let settings = RenderSettings {
        method: args.method,
        spp: args.spp,
        max_bounces: args.max_bounces.unwrap_or(scene.render.max_bounces),
        seed: args.seed,
        progress: !args.quiet,
    };
    let mixture = match settings.method {
        Method::Pt | Method::Ga => None,
        Method::Srt => Some(Mixture::new(
            vec![PathGenerator::srt(
                settings.max_bounces,
                args.srt_absorption,
                mixture_file::uniform_light(&scene),
            )],
            vec![1.0],
        )),
        Method::Mixture => {
            let Some(file) = &args.generators else {
                bail!("--method mixture needs --generators FILE");
            };
            Some(mixture_file::load(
                file,
                &scene,
                settings.max_bounces,
                args.srt_absorption,
            )?)
        }
    };
    if args.generators.is_some() && settings.method != Method::Mixture {
        bail!("--generators is only used with --method mixture");
    }
    let view = SceneView::new(&scene, accel.as_ref());
    let plan = if settings.method == Method::Ga {
        Some(pool.install(|| {
            Plan::build(
                &view,
                &ga_config,
                &plan_config,
                settings.max_bounces,
                settings.seed,
                settings.progress,
            )
        })?)
    } else {
        None
    };
    let estimator = match (&plan, &mixture) {
        (Some(plan), _) => Estimator::Ga(plan),
        (None, Some(mixture)) => Estimator::Mixture(mixture),
        (None, None) => Estimator::Pt,
    };
    let film = pool.install(|| render::render(&view, &settings, estimator));
    let render_s = film.elapsed.as_secs_f64();
    let plan_s = plan.as_ref().map_or(0.0, |p| p.elapsed().as_secs_f64());

    let t_write = Instant::now();
    for output in &args.outputs {
        genpath::image::write(output, &film.image)?;
    }
    if let (Some(file), Some(plan)) = (&args.explain, &plan) {
        let picture = genpath::genetic::explain::draw(&view, &film.image, plan);
        genpath::image::write(file, &picture)?;
    }
    let write_s = t_write.elapsed().as_secs_f64();

    let stats = serde_json::json!({
        "genpath_version": env!("CARGO_PKG_VERSION"),
        "command_line": std::env::args().collect::<Vec<_>>(),
        "scene": scene.path,
        "settings": settings,
        "threads": pool.current_num_threads(),
        "accel": accel.name(),
        "mixture": mixture,
        "width": scene.camera.width,
        "height": scene.camera.height,
        "ga": plan.as_ref().map(|p| ga_stats(p, &ga_config, &plan_config)),
        "times_s": {
            "load": load_s,
            "accel_build": accel_s,
            "baseline": plan.as_ref().map(|p| p.stats.baseline_seconds),
            "ga": plan.as_ref().map(|p| p.stats.ga_seconds),
            "render": render_s,
            "write": write_s,
            "total_render": plan_s + render_s,
        },
        "rays": { "closest": film.rays.closest, "shadow": film.rays.shadow, "total": film.rays.total() },
        "rays_per_s": film.rays.total() as f64 / render_s.max(1e-9),
        "warnings": scene.warnings,
    });
    let text = serde_json::to_string_pretty(&stats)?;
    for output in &args.outputs {
        let mut json_path = output.clone().into_os_string();
        json_path.push(".json");
        genpath::image::write_bytes_atomic(Path::new(&json_path), text.as_bytes())?;
    }
    if !args.quiet {
        if let Some(plan) = &plan {
            let improved = plan.pixels.iter().filter(|p| !p.kept_srt).count();
            eprintln!(
                "genpath: GA on {} pixels ({improved} improved on srt) in {plan_s:.2} s",
                plan.pixels.len()
            );
        }
        eprintln!(
            "genpath: {}×{} {} spp in {render_s:.2} s ({:.2} Mrays/s) → {}",
            scene.camera.width,
            scene.camera.height,
            settings.spp,
            film.rays.total() as f64 / render_s.max(1e-9) / 1e6,
            args.outputs
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    Ok(())
}

/// What the JSON statistics record of a GA plan: settings, per-phase totals, every GA
/// pixel's evolved mixture, and the fitness curves of a few pixels spread over the list.
fn ga_stats(plan: &Plan, ga: &GaConfig, config: &PlanConfig) -> serde_json::Value {
    const CURVES: usize = 8;
    let n = plan.pixels.len();
    let curves: Vec<_> = (0..n.min(CURVES))
        .map(|i| {
            let p = &plan.pixels[i * n / n.min(CURVES)];
            serde_json::json!({ "x": p.x, "y": p.y, "history": p.history })
        })
        .collect();
    let pixels: Vec<_> = plan
        .pixels
        .iter()
        .map(|p| {
            serde_json::json!({
                "x": p.x, "y": p.y, "origin": p.origin,
                "v_srt": p.v_srt, "v_best": p.v_best, "kept_srt": p.kept_srt,
                "test_paths": p.test_paths, "light_paths": p.light_paths,
                "test_path_seconds": p.test_path_seconds, "ga_seconds": p.ga_seconds,
                "mixture": p.mixture,
            })
        })
        .collect();
    let evolve_s = plan.stats.evolve_cpu_seconds.max(1e-9);
    serde_json::json!({
        "config": ga,
        "plan": config,
        "stats": plan.stats,
        "ga_pixels": n,
        "improved_pixels": plan.pixels.iter().filter(|p| !p.kept_srt).count(),
        "individual_evaluations_per_cpu_s": plan.stats.individual_evaluations as f64 / evolve_s,
        "fitness_curves": curves,
        "pixels": pixels,
    })
}

fn run_compare(args: CompareArgs) -> Result<()> {
    let image = genpath::image::read_exr(&args.image)?;
    let reference = genpath::image::read_exr(&args.reference)?;
    let Some(m) = genpath::image::metrics::compare(&image, &reference) else {
        bail!(
            "{} is {}×{} but the reference {} is {}×{}",
            args.image.display(),
            image.width,
            image.height,
            args.reference.display(),
            reference.width,
            reference.height
        );
    };
    if args.json {
        println!("{}", serde_json::to_string_pretty(&m)?);
    } else {
        println!(
            "relMSE {:.6e}  MSE {:.6e}  MAPE {:.6e}  bad pixels {:.4}%",
            m.relmse,
            m.mse,
            m.mape,
            100.0 * m.bad_fraction
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    /// Clap's own consistency checks (duplicate names, defaults that fail their parsers).
    #[test]
    fn command_line_is_consistent() {
        Cli::command().debug_assert();
    }
}
