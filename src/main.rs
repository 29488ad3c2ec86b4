//! The `genpath` command line.

use anyhow::{bail, Context, Result};
use clap::{Args, Parser, Subcommand};
use genpath::accel::{self, AccelKind};
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
        Method::Pt => None,
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
    let estimator = mixture.as_ref().map_or(Estimator::Pt, Estimator::Mixture);
    let view = SceneView::new(&scene, accel.as_ref());
    let film = pool.install(|| render::render(&view, &settings, estimator));
    let render_s = film.elapsed.as_secs_f64();

    let t_write = Instant::now();
    for output in &args.outputs {
        genpath::image::write(output, &film.image)?;
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
        "times_s": { "load": load_s, "accel_build": accel_s, "render": render_s, "write": write_s },
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
