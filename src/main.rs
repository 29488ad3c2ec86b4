//! The `genpath` command line.

use anyhow::{bail, Context, Result};
use clap::{Args, Parser, Subcommand};
use genpath::accel::{self, Accel, AccelKind, Coherence};
use genpath::genetic::plan::{Plan, PlanConfig};
use genpath::genetic::GaConfig;
use genpath::integrators::pt::PathTracing;
use genpath::integrators::{prepare, Integrator, Method, MethodConfig, RenderSettings};
use genpath::path::generator::{ABSORPTION_MAX, ABSORPTION_MIN};
use genpath::path::mixture_file;
use genpath::path::{RayCounts, SceneView};
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
    /// Render a long path-tracing reference in two independent halves, with its own noise
    /// estimate (relMSE between the halves / 4) in the JSON.
    Reference(ReferenceArgs),
    /// Error against run time: render methods at increasing budgets, compare each render with
    /// a reference, write PREFIX.csv and PREFIX.svg (relMSE against seconds, log-log).
    Sweep(SweepArgs),
    /// Throughput: rays/s per back-end (coherent/incoherent, single/packet), test paths and
    /// fitness evaluations per second, and render time against the number of threads.
    Bench(BenchArgs),
    /// Check the numerical invariants on a scene at a small size: no NaN/Inf/negative pixel
    /// with any method, finite positive sampled densities, finite fitness values, and image
    /// means that agree with pt's. Exits with status 1 when one fails.
    Check(CheckArgs),
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
    /// Also compare every channel bit for bit; exits with status 1 if any differs.
    #[arg(long)]
    bits: bool,
}

/// What every command that renders needs: the scene, how to trace it, and the seed.
#[derive(Args)]
struct SceneArgs {
    /// Scene description (TOML).
    scene: PathBuf,
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

/// The method and its own settings.
#[derive(Args)]
struct MethodArgs {
    /// Rendering method.
    #[arg(long, value_enum, default_value_t = Method::Pt)]
    method: Method,
    #[command(flatten)]
    settings: SettingsArgs,
}

/// What the methods other than `pt` are made of.
#[derive(Args)]
struct SettingsArgs {
    /// Mixture of path generators for `--method mixture` (TOML or JSON; see the README).
    #[arg(long, value_name = "FILE")]
    generators: Option<PathBuf>,
    /// Absorption (Russian-roulette probability) of the `srt` generator at each vertex.
    #[arg(long, default_value_t = 0.5, value_parser = parse_absorption)]
    srt_absorption: f64,
    #[command(flatten)]
    ga: GaArgs,
}

#[derive(Args)]
struct RenderArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Output image; repeat for several formats. A `<FILE>.json` with statistics is written beside each.
    #[arg(short, long = "output", value_name = "FILE", required = true)]
    outputs: Vec<PathBuf>,
    /// Samples (paths) per pixel.
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..=1 << 24))]
    spp: u32,
    /// With `--method ga`: also write an image of the GA pixels with their evolved anchor
    /// points and cones drawn over the render.
    #[arg(long, value_name = "FILE")]
    explain: Option<PathBuf>,
    #[command(flatten)]
    method: MethodArgs,
}

#[derive(Args)]
struct ReferenceArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// The reference image (EXR); `<FILE>.json` beside it holds its noise estimate.
    #[arg(short, long = "output", value_name = "FILE")]
    output: PathBuf,
    /// Path-tracing samples per pixel, split into two independent halves.
    #[arg(long, default_value_t = 4096, value_parser = clap::value_parser!(u32).range(2..=1 << 24))]
    spp: u32,
}

#[derive(Args)]
struct SweepArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// The reference (EXR), e.g. from `genpath reference`, of the size rendered.
    #[arg(long = "ref", value_name = "REF.exr")]
    reference: PathBuf,
    /// Methods, comma-separated: pt, srt, mixture (with --generators), ga, ga-pt, pg, or
    /// ga:key=value:… (ga-pt:…, pg:sp=N) with keys m, l, pop, gen, s, e, grid, extra,
    /// neighbours, cw, gate, warm, da, pa, gs, spatial, sp (e.g. ga:m=10000:grid=32,
    /// ga-pt:gate=0, ga-pt:spatial=1; an unknown key lists them).
    #[arg(long, value_delimiter = ',', default_value = "pt,srt,ga")]
    methods: Vec<String>,
    /// Budgets, comma-separated: samples per pixel, or seconds per image with --time.
    #[arg(long, value_delimiter = ',', default_value = "4,16,64,256")]
    budgets: Vec<f64>,
    /// Budgets are wall-clock seconds per image, every phase included.
    #[arg(long)]
    time: bool,
    /// Repetitions of every render, with seeds seed, seed + 1, …
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=10_000))]
    reps: u32,
    /// Writes PREFIX.csv and PREFIX.svg.
    #[arg(short, long = "output", value_name = "PREFIX")]
    output: PathBuf,
    #[command(flatten)]
    settings: SettingsArgs,
}

#[derive(Args)]
struct CheckArgs {
    /// The scene is rendered 32 pixels wide (aspect kept) unless --width/--height are given.
    #[command(flatten)]
    scene: SceneArgs,
    /// Samples per pixel of each method's render.
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(2..=1 << 20))]
    spp: u32,
    /// Also write the report as JSON to FILE.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

#[derive(Args)]
struct BenchArgs {
    /// Scene whose camera gives the coherent rays and whose bounds the incoherent ones.
    #[arg(default_value = "scenes/fig5/scene.toml")]
    scene: PathBuf,
    /// Rays per set: the camera's image is resized to N × N.
    #[arg(long, value_name = "N", default_value_t = 512, value_parser = clap::value_parser!(u32).range(4..=8192))]
    rays: u32,
    /// Each figure is the best of this many passes.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..=100))]
    passes: u32,
    /// Thread counts of the scaling measurement (default: 1, 2, 4, … up to the cores).
    #[arg(long, value_delimiter = ',', value_parser = clap::value_parser!(u32).range(1..=4096))]
    threads: Vec<u32>,
    /// Samples per pixel of each scaling render (pt, at the scene's size).
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..=1 << 16))]
    spp: u32,
    /// Also write the figures as JSON to FILE.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
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
    /// After evolution, set each GA pixel's mixture weights to the optimum of eq. 10 for its
    /// evolved generators (convex optimisation, beyond the paper).
    #[arg(long, default_value_t = GaConfig::default().convex_weights, action = clap::ArgAction::Set, value_name = "BOOL")]
    convex_weights: bool,
    /// Share of random anchor points drawn where light-carrying test paths went (0: the
    /// paper's, uniform by area on all surfaces).
    #[arg(long, default_value_t = GaConfig::default().data_anchors, value_parser = parse_probability)]
    data_anchors: f64,
    /// Share of data-driven directional samplers that are patches (parallelograms where the
    /// light-carrying test paths' directions arrived on one plane) rather than cones (0:
    /// the paper's cones only).
    #[arg(long, default_value_t = GaConfig::default().patches, value_parser = parse_probability)]
    patches: f64,
    /// Stop sampling a pixel's test paths once this many carry light.
    #[arg(long, value_name = "L", default_value_t = GaConfig::default().max_light_paths as u32, value_parser = clap::value_parser!(u32).range(1..=100_000_000))]
    max_light_paths: u32,
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
    /// Run the GA everywhere and with every step: no cells left out for low baseline
    /// variance, no generator steps cut at the depth the test paths need (ga-pt: still at
    /// most --guide-steps).
    #[arg(long)]
    no_prune: bool,
    /// Grid cells whose pooled baseline relative variance (of one srt sample, Var/(mean² +
    /// 0.01)) is below this get no GA pixel.
    #[arg(long, default_value_t = PlanConfig::default().prune_variance)]
    prune_variance: f64,
    /// The paper's method everywhere: no pilot, and every pixel renders with its evolved
    /// mixture even where pt is predicted to do better (see the README's "gate").
    #[arg(long)]
    no_gate: bool,
    /// Evolve half the GA pixels (a checkerboard of grid cells) first and the others from
    /// their evolved neighbours' best individuals, with half the generations.
    #[arg(long, default_value_t = PlanConfig::default().warm_start, action = clap::ArgAction::Set, value_name = "BOOL")]
    warm_start: bool,
    /// Seconds the GA plan may take (baseline included); GA pixels not evolved by then are
    /// left out. The plan then depends on timing, not only on the seed.
    #[arg(long, value_name = "SECONDS")]
    ga_time_limit: Option<f64>,
    /// ga-pt: vertices the evolved guide steers (the GA evolves that many directional steps,
    /// at most as many as the test paths need); path tracing's own sampling beyond.
    #[arg(long, default_value_t = PlanConfig::default().guide_steps as u32, value_parser = clap::value_parser!(u32).range(1..=64))]
    guide_steps: u32,
    /// ga-pt: guide the vertices the GA does not steer with a spatial guide learned from
    /// path-traced training passes (see --spatial-passes), as --method pg does everywhere
    /// (beyond the paper). `false`: path tracing's own sampling there.
    #[arg(long, default_value_t = PlanConfig::default().spatial, action = clap::ArgAction::Set, value_name = "BOOL")]
    spatial_guide: bool,
    /// pg, and ga-pt with the spatial guide: passes of path tracing that train the spatial
    /// guide, pass i with 2^i samples per pixel; their samples count in --spp and stay in
    /// the image. Default: as many as fit in half of --spp.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=12))]
    spatial_passes: Option<u32>,
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
            max_steps: None,
            convex_weights: self.convex_weights,
            max_light_paths: self.max_light_paths as usize,
            data_anchors: self.data_anchors,
            patches: self.patches,
            directions_only: false,
        };
        let plan = PlanConfig {
            grid: self.ga_grid,
            extra: self.ga_extra,
            baseline_spp: self.baseline_spp,
            neighbours: self.ga_neighbours,
            prune: !self.no_prune,
            prune_variance: self.prune_variance,
            gate: !self.no_gate,
            warm_start: self.warm_start,
            time_limit: self.ga_time_limit,
            guide_steps: self.guide_steps as usize,
            spatial: self.spatial_guide,
            spatial_passes: self.spatial_passes,
            spatial_time_limit: None,
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
        Command::Reference(args) => run_reference(args),
        Command::Sweep(args) => run_sweep(args),
        Command::Bench(args) => run_bench(args),
        Command::Check(args) => run_check(args),
    };
    if let Err(error) = result {
        eprintln!("genpath: error: {error:#}");
        std::process::exit(1);
    }
}

/// Fails before any work when an output cannot possibly be written.
fn check_output(path: &Path) -> Result<()> {
    genpath::image::check_format(path)?;
    check_dir(path)
}

/// Fails when the directory `path` would be written into does not exist.
fn check_dir(path: &Path) -> Result<()> {
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

/// A loaded scene with its accelerator and worker pool, and how long loading took.
struct Session {
    scene: Scene,
    accel: Box<dyn Accel>,
    pool: rayon::ThreadPool,
    load_s: f64,
    accel_s: f64,
}

impl Session {
    fn open(args: &SceneArgs) -> Result<Self> {
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
        Ok(Self {
            scene,
            accel,
            pool,
            load_s,
            accel_s: t_accel.elapsed().as_secs_f64(),
        })
    }

    fn settings(&self, args: &SceneArgs, method: Method, spp: u32) -> RenderSettings {
        RenderSettings {
            method,
            spp,
            max_bounces: args.max_bounces.unwrap_or(self.scene.render.max_bounces),
            seed: args.seed,
            progress: !args.quiet,
        }
    }

    /// What the JSON of every render records first.
    fn stats(&self, settings: &RenderSettings) -> serde_json::Map<String, serde_json::Value> {
        let value = serde_json::json!({
            "genpath_version": env!("CARGO_PKG_VERSION"),
            "command_line": std::env::args().collect::<Vec<_>>(),
            "scene": self.scene.path,
            "settings": settings,
            "threads": self.pool.current_num_threads(),
            "accel": self.accel.name(),
            "width": self.scene.camera.width,
            "height": self.scene.camera.height,
            "warnings": self.scene.warnings,
        });
        match value {
            serde_json::Value::Object(map) => map,
            _ => unreachable!("a JSON object literal"),
        }
    }
}

fn rays_json(rays: RayCounts) -> serde_json::Value {
    serde_json::json!({
        "closest": rays.closest, "shadow": rays.shadow, "total": rays.total(),
        "densities": rays.densities, "cost": rays.cost(),
    })
}

/// Writes `stats` as `<output>.json` beside each output.
fn write_stats(outputs: &[PathBuf], stats: &serde_json::Value) -> Result<()> {
    let text = serde_json::to_string_pretty(stats)?;
    for output in outputs {
        let mut json_path = output.clone().into_os_string();
        json_path.push(".json");
        genpath::image::write_bytes_atomic(Path::new(&json_path), text.as_bytes())?;
    }
    Ok(())
}

impl SettingsArgs {
    /// `method`'s configuration; loads the mixture file when one is given.
    fn config(&self, scene: &Scene, max_bounces: u32) -> Result<MethodConfig> {
        let mixture = match &self.generators {
            Some(file) => Some(mixture_file::load(
                file,
                scene,
                max_bounces,
                self.srt_absorption,
            )?),
            None => None,
        };
        let (ga, plan) = self.ga.configs(self.srt_absorption)?;
        Ok(MethodConfig {
            srt_absorption: self.srt_absorption,
            mixture,
            ga,
            plan,
        })
    }
}

impl MethodArgs {
    /// The method's configuration; `--generators` goes with `--method mixture` only.
    fn config(&self, scene: &Scene, max_bounces: u32) -> Result<MethodConfig> {
        match (&self.settings.generators, self.method) {
            (Some(_), m) if m != Method::Mixture => {
                bail!("--generators is only used with --method mixture")
            }
            (None, Method::Mixture) => bail!("--method mixture needs --generators FILE"),
            _ => self.settings.config(scene, max_bounces),
        }
    }
}

fn run_render(args: RenderArgs) -> Result<()> {
    for output in &args.outputs {
        check_output(output)?;
    }
    if let Some(explain) = &args.explain {
        if !matches!(args.method.method, Method::Ga | Method::GaPt) {
            bail!("--explain is only used with --method ga or ga-pt");
        }
        check_output(explain)?;
    }
    // Flag ranges first, before any loading.
    args.method
        .settings
        .ga
        .configs(args.method.settings.srt_absorption)?;
    let session = Session::open(&args.scene)?;
    let settings = session.settings(&args.scene, args.method.method, args.spp);
    let config = args.method.config(&session.scene, settings.max_bounces)?;
    let view = SceneView::new(&session.scene, session.accel.as_ref());
    let prepared = session
        .pool
        .install(|| prepare(&view, &config, &settings))?;
    let plan = prepared.plan();
    let film = session.pool.install(|| prepared.render(&view, &settings));
    let render_s = film.elapsed.as_secs_f64();
    let plan_s = plan.map_or(0.0, |p| p.elapsed().as_secs_f64());
    let spatial_s = prepared.spatial().map_or(0.0, |s| s.stats.seconds);

    let t_write = Instant::now();
    for output in &args.outputs {
        genpath::image::write(output, &film.image)?;
    }
    if let (Some(file), Some(plan)) = (&args.explain, plan) {
        let picture = genpath::genetic::explain::draw(&view, &film.image, plan);
        genpath::image::write(file, &picture)?;
    }
    let write_s = t_write.elapsed().as_secs_f64();

    let mut stats = session.stats(&settings);
    stats.insert("mixture".into(), serde_json::json!(prepared.mixture()));
    stats.insert(
        "ga".into(),
        serde_json::json!(plan.map(|p| ga_stats(p, &config.ga, &config.plan))),
    );
    stats.insert(
        "times_s".into(),
        serde_json::json!({
            "load": session.load_s,
            "accel_build": session.accel_s,
            "baseline": plan.map(|p| p.stats.baseline_seconds),
            "ga": plan.map(|p| p.stats.ga_seconds),
            "spatial": spatial_s,
            "render": render_s,
            "write": write_s,
            "total_render": plan_s + spatial_s + render_s,
        }),
    );
    stats.insert(
        "spatial".into(),
        serde_json::json!(prepared.spatial().map(|s| &s.stats)),
    );
    stats.insert("rays".into(), rays_json(film.rays));
    stats.insert(
        "rays_per_s".into(),
        serde_json::json!(film.rays.total() as f64 / render_s.max(1e-9)),
    );
    write_stats(&args.outputs, &serde_json::Value::Object(stats))?;
    if !args.scene.quiet {
        if let Some(plan) = plan {
            let improved = plan.pixels.iter().filter(|p| !p.kept_srt).count();
            eprintln!(
                "genpath: GA on {} pixels ({improved} improved on srt) in {plan_s:.2} s",
                plan.pixels.len()
            );
        }
        if let Some(s) = prepared.spatial() {
            eprintln!(
                "genpath: spatial guide: {} of {} regions trained on {} records from {} passes ({} spp of the image) in {:.2} s",
                s.stats.trained_cells, s.stats.cells, s.stats.records, s.stats.passes, s.stats.spp, s.stats.seconds
            );
        }
        eprintln!(
            "genpath: {}×{} {} spp in {render_s:.2} s ({:.2} Mrays/s) → {}",
            session.scene.camera.width,
            session.scene.camera.height,
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

/// Two independent `pt` halves, averaged; their relMSE against each other is about four
/// times the average's own relMSE (each half has twice its variance, and both count).
fn run_reference(args: ReferenceArgs) -> Result<()> {
    let is_exr = args
        .output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    if !is_exr {
        bail!(
            "{}: a reference must be an EXR (float) image",
            args.output.display()
        );
    }
    check_output(&args.output)?;
    let session = Session::open(&args.scene)?;
    let view = SceneView::new(&session.scene, session.accel.as_ref());
    let half = |seed: u64| {
        let settings = RenderSettings {
            seed,
            ..session.settings(&args.scene, Method::Pt, args.spp / 2)
        };
        let pt = PathTracing {
            max_bounces: settings.max_bounces,
        };
        session.pool.install(|| pt.render(&view, &settings))
    };
    // The halves use seeds derived from the given one, so neither shares random numbers with
    // a render made with the same `--seed` (that would correlate its error with the
    // reference's and understate it).
    let seeds = [0x05ee_d0f5_ec00_da1f, 0x7e5e_ed00_fa11_0b0b]
        .map(|tag| genpath::sampling::derive_seed(args.scene.seed, tag));
    let (a, b) = (half(seeds[0]), half(seeds[1]));
    let Some(between) = genpath::image::metrics::compare(&a.image, &b.image) else {
        unreachable!("both halves have the scene's size");
    };
    let mut image = a.image.clone();
    for (p, q) in image.pixels.iter_mut().zip(&b.image.pixels) {
        *p = std::array::from_fn(|c| 0.5 * (p[c] + q[c]));
    }
    genpath::image::write(&args.output, &image)?;
    let settings = session.settings(&args.scene, Method::Pt, args.spp / 2 * 2);
    let seconds = a.elapsed.as_secs_f64() + b.elapsed.as_secs_f64();
    let mut stats = session.stats(&settings);
    stats.insert(
        "reference".into(),
        serde_json::json!({
            "half_seeds": seeds,
            "spp_per_half": args.spp / 2,
            "relmse_between_halves": between.relmse,
            "relmse_estimate": between.relmse / 4.0,
            "mse_estimate": between.mse / 4.0,
            "bad_fraction": between.bad_fraction,
        }),
    );
    stats.insert(
        "times_s".into(),
        serde_json::json!({ "load": session.load_s, "accel_build": session.accel_s, "render": seconds }),
    );
    let mut rays = a.rays;
    rays.add(b.rays);
    stats.insert("rays".into(), rays_json(rays));
    write_stats(
        std::slice::from_ref(&args.output),
        &serde_json::Value::Object(stats),
    )?;
    if !args.scene.quiet {
        eprintln!(
            "genpath: reference {} spp in {seconds:.1} s, estimated relMSE {:.3e} → {}",
            args.spp / 2 * 2,
            between.relmse / 4.0,
            args.output.display()
        );
    }
    Ok(())
}

fn run_sweep(args: SweepArgs) -> Result<()> {
    use genpath::report::{self, Budgets, MethodSpec, Sweep};
    let with_ext = |ext: &str| {
        let mut p = args.output.clone().into_os_string();
        p.push(ext);
        PathBuf::from(p)
    };
    let (csv_path, svg_path) = (with_ext(".csv"), with_ext(".svg"));
    for p in [&csv_path, &svg_path] {
        check_dir(p)?;
    }
    let budgets = if args.time {
        if let Some(b) = args.budgets.iter().find(|b| !(b.is_finite() && **b > 0.0)) {
            bail!("--budgets: {b} is not a positive number of seconds");
        }
        Budgets::Seconds(args.budgets.clone())
    } else {
        let spp = args
            .budgets
            .iter()
            .map(|&b| {
                if b.fract() == 0.0 && (1.0..=f64::from(1u32 << 24)).contains(&b) {
                    Ok(b as u32)
                } else {
                    Err(anyhow::anyhow!(
                        "--budgets: {b} is not a whole number of samples per pixel in [1, 2^24] (use --time for seconds)"
                    ))
                }
            })
            .collect::<Result<Vec<_>>>()?;
        Budgets::Spp(spp)
    };
    args.settings.ga.configs(args.settings.srt_absorption)?;
    let reference = genpath::image::read_exr(&args.reference)?;
    let session = Session::open(&args.scene)?;
    let settings = session.settings(&args.scene, Method::Pt, 1);
    let base = args.settings.config(&session.scene, settings.max_bounces)?;
    let methods = args
        .methods
        .iter()
        .map(|m| MethodSpec::parse(m.trim(), &base).map_err(|e| anyhow::anyhow!("--methods: {e}")))
        .collect::<Result<Vec<_>>>()?;
    if methods.iter().any(|m| m.method == Method::Mixture) && base.mixture.is_none() {
        bail!("--methods mixture needs --generators FILE");
    }
    let scene_name = args
        .scene
        .scene
        .parent()
        .and_then(|d| d.file_name())
        .map_or_else(|| "scene".to_string(), |n| n.to_string_lossy().into_owned());
    let sweep = Sweep {
        scene_name: scene_name.clone(),
        reference: &reference,
        methods,
        budgets,
        reps: args.reps,
        settings,
        progress: !args.scene.quiet,
    };
    let view = SceneView::new(&session.scene, session.accel.as_ref());
    let quiet = args.scene.quiet;
    let rows = session.pool.install(|| {
        sweep.run(&view, |r| {
            if !quiet {
                eprintln!(
                    "genpath: {:<24} {:>6} spp {:>8.2} s (GA {:>6.2} s)  relMSE {:.4e}",
                    r.method, r.spp, r.seconds, r.ga_seconds, r.relmse
                );
            }
        })
    })?;
    genpath::image::write_bytes_atomic(&csv_path, report::csv(&rows).as_bytes())?;
    let title = format!(
        "{scene_name}: relMSE against time ({}×{}, max bounces {})",
        session.scene.camera.width, session.scene.camera.height, sweep.settings.max_bounces
    );
    let svg = report::plot::svg(&title, &rows).map_err(|e| anyhow::anyhow!(e))?;
    genpath::image::write_bytes_atomic(&svg_path, svg.as_bytes())?;
    println!("{}", report::summary(&rows));
    Ok(())
}

fn run_bench(args: BenchArgs) -> Result<()> {
    use genpath::genetic::population::evolve;
    use genpath::genetic::test_paths::TestPaths;
    use genpath::report::bench::{
        accel_label, best, best_interleaved, camera_rays, random_rays, ray_rates,
    };
    if let Some(json) = &args.json {
        check_dir(json)?;
    }
    let scene = Scene::load(&args.scene)?;
    let passes = args.passes as usize;
    let n = args.rays;
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

    // Test paths and fitness evaluations at the image's centre, one thread.
    let accel = accel::build(AccelKind::default_available(), &scene.mesh)?;
    let view = SceneView::new(&scene, accel.as_ref());
    let ga = GaConfig {
        generations: 10,
        ..GaConfig::default()
    };
    let max_bounces = scene.render.max_bounces;
    let q = mixture_file::srt(&scene, max_bounces, ga.srt_absorption);
    let pixel = (scene.camera.width / 2, scene.camera.height / 2);
    let m = ga.test_paths;
    let [(packet_t, _), (single_t, _)] = best_interleaved(
        passes,
        [
            &mut || {
                TestPaths::sample(&view, &q, pixel, m, max_bounces, 1)
                    .0
                    .len()
            },
            &mut || {
                TestPaths::sample_single(&view, &q, pixel, m, max_bounces, 1)
                    .0
                    .len()
            },
        ],
    );
    let paths = TestPaths::sample(&view, &q, pixel, m, max_bounces, 1).0;
    let start = Instant::now();
    let mut rng = genpath::sampling::sample_rng(1, 0, 0);
    let evolution = evolve(&ga, &paths, &view, &mut rng);
    let evolve_s = start.elapsed().as_secs_f64();
    let evaluations = evolution.individual_evaluations as f64 / evolve_s;
    println!(
        "\ntest paths at pixel {pixel:?} ({}): {:.0} k/s in packets, {:.0} k/s single ({} of {m} carry light)",
        accel.name(),
        m as f64 / packet_t.as_secs_f64() / 1e3,
        m as f64 / single_t.as_secs_f64() / 1e3,
        paths.len()
    );
    println!(
        "fitness: {evaluations:.0} individual evaluations/s ({} generators evaluated, population {}, M = {m})",
        evolution.generator_evaluations, ga.population
    );

    // Thread scaling of a pt render.
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get()) as u32;
    let threads = if args.threads.is_empty() {
        std::iter::successors(Some(1u32), |t| Some(t * 2))
            .take_while(|&t| t < cores)
            .chain([cores])
            .collect()
    } else {
        args.threads.clone()
    };
    let settings = RenderSettings {
        method: Method::Pt,
        spp: args.spp,
        max_bounces,
        seed: 1,
        progress: false,
    };
    println!(
        "\n{:>7} {:>9} {:>8} {:>10}",
        "threads", "seconds", "speedup", "efficiency"
    );
    let mut scaling = Vec::new();
    let mut base = None;
    for &t in &threads {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(t as usize)
            .build()
            .context("cannot start the worker threads")?;
        let pt = PathTracing { max_bounces };
        let (elapsed, _) = best(passes, || {
            pool.install(|| pt.render(&view, &settings)).rays.total() as usize
        });
        let seconds = elapsed.as_secs_f64();
        let base = *base.get_or_insert(seconds * f64::from(threads[0]));
        let speedup = base / seconds;
        println!(
            "{t:>7} {seconds:>9.3} {speedup:>8.2} {:>10.2}",
            speedup / f64::from(t)
        );
        scaling.push(serde_json::json!({ "threads": t, "seconds": seconds, "speedup": speedup }));
    }
    if let Some(json) = &args.json {
        let value = serde_json::json!({
            "genpath_version": env!("CARGO_PKG_VERSION"),
            "scene": scene.path,
            "rays_per_set": n * n,
            "passes": passes,
            "cores": cores,
            "rays": rays_json,
            "test_paths_per_s": { "packet": m as f64 / packet_t.as_secs_f64(), "single": m as f64 / single_t.as_secs_f64(), "accel": accel.name() },
            "fitness_evaluations_per_s": evaluations,
            "scaling": { "method": "pt", "spp": args.spp, "width": scene.camera.width, "height": scene.camera.height, "runs": scaling },
        });
        genpath::image::write_bytes_atomic(json, serde_json::to_string_pretty(&value)?.as_bytes())?;
    }
    Ok(())
}

fn run_check(mut args: CheckArgs) -> Result<()> {
    if let Some(json) = &args.json {
        check_dir(json)?;
    }
    if args.scene.width.is_none() && args.scene.height.is_none() {
        args.scene.width = Some(32);
    }
    let session = Session::open(&args.scene)?;
    let max_bounces = args
        .scene
        .max_bounces
        .unwrap_or(session.scene.render.max_bounces);
    let config = genpath::check::CheckConfig::new(args.spp, max_bounces, args.scene.seed);
    let view = SceneView::new(&session.scene, session.accel.as_ref());
    let report = session
        .pool
        .install(|| genpath::check::check(&view, &config))?;
    println!(
        "{}: {}×{}, {} spp, max bounces {max_bounces}",
        session.scene.path.display(),
        session.scene.camera.width,
        session.scene.camera.height,
        args.spp
    );
    println!("| method | bad pixels | mean (R, G, B) | |z| vs pt | seconds |");
    println!("|---|---|---|---|---|");
    for m in &report.methods {
        println!(
            "| {:?} | {} | {:.4e}, {:.4e}, {:.4e} | {:.2} | {:.2} |",
            m.method, m.bad_pixels, m.mean[0], m.mean[1], m.mean[2], m.z_vs_pt, m.seconds
        );
    }
    println!(
        "densities: {} sampled, min {:.3e}, max {:.3e}, {} not finite and positive",
        report.pdf_samples, report.pdf_min, report.pdf_max, report.pdf_bad
    );
    println!(
        "fitness: {} values, {} not finite; critical |z| {:.2}",
        report.fitness_values, report.fitness_bad, report.z_critical
    );
    if let Some(json) = &args.json {
        genpath::image::write_bytes_atomic(
            json,
            serde_json::to_string_pretty(&report)?.as_bytes(),
        )?;
    }
    if !report.passed() {
        bail!("check failed:\n  {}", report.failures.join("\n  "));
    }
    println!("check passed");
    Ok(())
}

/// What the GA plan and the renderer left out for this scene, and why (design §8).
fn left_out(
    plan: &Plan,
    config: &PlanConfig,
    analysis: &genpath::scene::SceneAnalysis,
) -> Vec<String> {
    let mut out = Vec::new();
    if analysis.glossy_triangles == 0 {
        out.push("Phong-lobe evaluation and sampling: no glossy material (the BRDF code runs only the lobes a material has)".to_string());
    }
    if analysis.mirror_triangles == 0 {
        out.push("delta (mirror) vertices: no mirror material".to_string());
    }
    let s = &plan.stats;
    out.push(format!(
        "GA at {} pixels that see only background or emitters ({} grid cells without a scattering pixel)",
        s.skipped_pixels, s.empty_cells
    ));
    if !config.prune {
        out.push("nothing else: pruning is off (--no-prune)".to_string());
        return out;
    }
    if !s.baseline_ran {
        out.push(format!(
            "the baseline and the GA at {} grid pixels: the gate's pilot predicted no gain",
            s.gated_pixels
        ));
        return out;
    }
    out.push(format!(
        "GA in {} grid cells whose pooled baseline relative variance is below {} (cells: min {:.3}, median {:.3}, max {:.3})",
        s.low_variance_cells, config.prune_variance, s.cell_variance[0], s.cell_variance[1], s.cell_variance[2]
    ));
    let max_steps = plan.pixels.iter().map(|p| p.steps).max().unwrap_or(0);
    let cut = plan.pixels.iter().filter(|p| p.steps < max_steps).count();
    out.push(format!(
        "generator steps past the depth the test paths need (all but {} of Σ F²/q): {} of {} GA pixels evolve fewer steps than the deepest ({max_steps}); steps per pixel {:?}",
        genpath::genetic::plan::PRUNE_SHARE,
        cut,
        plan.pixels.len(),
        {
            let mut h = std::collections::BTreeMap::new();
            for p in &plan.pixels {
                *h.entry(p.steps).or_insert(0usize) += 1;
            }
            h
        }
    ));
    out
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
                "v_srt": p.v_srt, "v_best": p.v_best, "v_evolved": p.v_evolved, "kept_srt": p.kept_srt,
                "trial": p.trial, "warm": p.warm,
                "test_paths": p.test_paths, "light_paths": p.light_paths, "steps": p.steps,
                "test_path_seconds": p.test_path_seconds, "ga_seconds": p.ga_seconds,
                "mixture": p.mixture,
            })
        })
        .collect();
    let evolve_s = plan.stats.evolve_cpu_seconds.max(1e-9);
    let analysis = plan.analysis.clone();
    serde_json::json!({
        "config": ga,
        "plan": config,
        "left_out": left_out(plan, config, &analysis),
        "scene_analysis": analysis,
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
    let differing = image
        .pixels
        .iter()
        .zip(&reference.pixels)
        .filter(|(a, b)| a.map(f32::to_bits) != b.map(f32::to_bits))
        .count();
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
    if args.bits {
        if differing > 0 {
            bail!("{differing} of {} pixels differ in their bits", image.pixels.len());
        }
        println!("bit-identical: all {} pixels", image.pixels.len());
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
