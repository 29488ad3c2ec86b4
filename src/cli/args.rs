//! The arguments every command that renders shares: the scene, the method and its settings.

use anyhow::{bail, Context, Result};
use clap::parser::ValueSource;
use clap::{ArgMatches, Args};
use genpath::accel::{AccelKind, EmbreeIsa};
use genpath::film::Shard;
use genpath::genetic::plan::{GateConfig, PlanConfig};
use genpath::genetic::GaConfig;
use genpath::integrators::settings::{SpatialConfig, SrtConfig};
use genpath::integrators::{Method, Settings};
use genpath::path::generator::{Nee, ABSORPTION_MAX, ABSORPTION_MIN};
use genpath::path::mixture_file;
use genpath::scene::{Scene, MAX_BOUNCES_LIMIT, MAX_IMAGE_SIDE};
use std::path::{Path, PathBuf};

/// What every command that renders needs: the scene, how to trace it, and the seed.
#[derive(Args)]
pub struct SceneArgs {
    /// Scene description: genpath TOML, or Mitsuba 3 XML (`.xml`).
    pub scene: PathBuf,
    /// A Mitsuba XML scene parameter, `NAME=VALUE` (its `$NAME`); repeatable.
    #[arg(short = 'D', value_name = "NAME=VALUE", value_parser = parse_define)]
    pub define: Vec<(String, String)>,
    /// Scattering events per path; defaults to the scene's `render.max_bounces`.
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=MAX_BOUNCES_LIMIT as i64))]
    pub max_bounces: Option<u32>,
    /// Seed of every random stream; the same seed gives the same image for any thread count.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Worker threads (default: all cores).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub threads: Option<u32>,
    /// Ray-tracing back-end.
    #[arg(long, value_enum, default_value_t = AccelKind::default_available())]
    pub accel: AccelKind,
    /// Embree's kernels: the instruction set they use [default: the best this CPU runs].
    /// Kernels for different instruction sets may round a hit differently, so shards to be
    /// merged must use the same (their identity records it): pin it when the nodes differ.
    #[arg(long, value_enum, value_name = "ISA")]
    pub embree_isa: Option<EmbreeIsa>,
    /// Override the scene's image width (the horizontal field of view is kept).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_IMAGE_SIDE as i64))]
    pub width: Option<u32>,
    /// Override the scene's image height.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_IMAGE_SIDE as i64))]
    pub height: Option<u32>,
    /// No progress bar and no warnings on stderr.
    #[arg(short, long)]
    pub quiet: bool,
}

/// The method and its own settings.
#[derive(Args)]
pub struct MethodArgs {
    /// Rendering method [default: ga-pt, the GA's best method, for `render` and `learn`;
    /// pt for `reference` and `bench`].
    #[arg(long, value_enum)]
    pub method: Option<Method>,
    #[command(flatten)]
    pub settings: SettingsArgs,
}

/// What the methods other than `pt` are made of: every setting of
/// [`genpath::integrators::Settings`], each a flag named after its one name (the key with
/// dashes). Flags are read by their ids from the command line's matches
/// ([`SettingsArgs::settings`]), so the fields themselves are never read.
#[derive(Args)]
#[allow(dead_code)]
pub struct SettingsArgs {
    /// Settings from a TOML file, one table per concern (`[ga] test_paths = 4000`; see
    /// docs/settings.md); flags and --set override it.
    #[arg(long, value_name = "FILE", help_heading = "Settings")]
    pub config: Option<PathBuf>,
    /// A setting by its name, `KEY=VALUE` (`test_paths=4000` or `ga.test_paths=4000`),
    /// after --config and the flags; repeatable.
    #[arg(long = "set", value_name = "KEY=VALUE", help_heading = "Settings")]
    pub set: Vec<String>,
    /// Mixture of path generators for `--method mixture` (TOML or JSON; see docs/scenes.md).
    #[arg(long, value_name = "FILE", help_heading = "Mixture (--method mixture)")]
    pub generators: Option<PathBuf>,
    /// Absorption (Russian-roulette probability) of the `srt` generator at each vertex.
    /// Default: with next-event estimation at every vertex none before the fifth vertex and
    /// 0.1 from it (as pt's roulette), the paper's 0.5 at every vertex with `--nee end` (and
    /// for ga-pt's GA, whose test paths are end-only)
    #[arg(long, value_parser = parse_absorption, help_heading = "srt (--method srt, and the defensive generator of ga)")]
    pub srt_absorption: Option<f64>,
    /// Where srt, mixture and ga do next-event estimation: at every non-delta vertex
    /// (balance heuristic over each generator's direction and light-point techniques), or
    /// only at the path's end (the paper's, for its Fig. 7).
    #[arg(long, value_enum, default_value_t = SrtConfig::default().nee, help_heading = "srt (--method srt, and the defensive generator of ga)")]
    pub nee: Nee,
    #[command(flatten)]
    pub ga: GaArgs,
    #[command(flatten)]
    pub plan: PlanArgs,
    #[command(flatten)]
    pub gate: GateArgs,
    #[command(flatten)]
    pub spatial: SpatialArgs,
}

/// Settings of the genetic algorithm (paper §4–5, design §6–7), table `[ga]`.
#[derive(Args)]
#[command(next_help_heading = "Genetic algorithm (--method ga, ga-pt)")]
#[allow(dead_code)]
pub struct GaArgs {
    /// Individuals per generation (the paper: 150).
    #[arg(long, default_value_t = GaConfig::default().population as u32, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub population: u32,
    /// Generations, the random first one included (the paper: 200).
    #[arg(long, default_value_t = GaConfig::default().generations as u32, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub generations: u32,
    /// Evolved generators per individual (S), besides the defensive srt one.
    #[arg(long, value_name = "S", default_value_t = GaConfig::default().generators as u32, value_parser = clap::value_parser!(u32).range(1..=64))]
    pub ga_generators: u32,
    /// Test paths per GA pixel (M of eq. 10), zero-contribution paths included.
    #[arg(long, value_name = "M", default_value_t = GaConfig::default().test_paths as u32, value_parser = clap::value_parser!(u32).range(1..=100_000_000))]
    pub test_paths: u32,
    /// Best individuals copied unchanged into the next generation (E).
    #[arg(long, value_name = "E", default_value_t = GaConfig::default().elitism)]
    pub elitism: usize,
    /// Crossover probability per pair of parents.
    #[arg(long, default_value_t = GaConfig::default().p_cross, value_parser = parse_probability)]
    pub p_cross: f64,
    /// Mutation probability per sampler.
    #[arg(long, default_value_t = GaConfig::default().p_sampler_mutate, value_parser = parse_probability)]
    pub p_mutate: f64,
    /// Probability per individual that two generators switch positions.
    #[arg(long, default_value_t = GaConfig::default().p_switch, value_parser = parse_probability)]
    pub p_switch: f64,
    /// Probability per individual of a weight mutation.
    #[arg(long, default_value_t = GaConfig::default().p_weight, value_parser = parse_probability)]
    pub p_weight: f64,
    /// Probability per generator of an absorption mutation.
    #[arg(long, default_value_t = GaConfig::default().p_absorb, value_parser = parse_probability)]
    pub p_absorb: f64,
    /// Smallest weight of the defensive srt component of every evolved mixture.
    #[arg(long, default_value_t = GaConfig::default().defensive_weight)]
    pub defensive_weight: f64,
    /// Standard deviation of an anchor shift, relative to the scene's size.
    #[arg(long, default_value_t = GaConfig::default().anchor_shift)]
    pub anchor_shift: f64,
    /// After evolution, set each GA pixel's mixture weights to the optimum of eq. 10 for its
    /// evolved generators (convex optimisation, beyond the paper).
    #[arg(long, default_value_t = GaConfig::default().convex_weights, action = clap::ArgAction::Set, value_name = "BOOL")]
    pub convex_weights: bool,
    /// Share of random anchor points drawn where light-carrying test paths went (0: the
    /// paper's, uniform by area on all surfaces).
    #[arg(long, default_value_t = GaConfig::default().data_anchors, value_parser = parse_probability)]
    pub data_anchors: f64,
    /// Share of data-driven directional samplers that are patches (parallelograms where the
    /// light-carrying test paths' directions arrived on one plane) rather than cones (0:
    /// the paper's cones only).
    #[arg(long, default_value_t = GaConfig::default().patches, value_parser = parse_probability)]
    pub patches: f64,
    /// Place the data-driven anchors and patches from a second, independent set of test
    /// paths, so that the set eq. 10 is measured on never placed them (`false`: one set for
    /// both, which lets the GA fit its samplers to the few paths that dominate eq. 10).
    /// Default: on for ga, off for ga-pt (whose end-only test paths seldom carry light, so
    /// that a second set costs as much as the first)
    #[arg(long, action = clap::ArgAction::Set, value_name = "BOOL")]
    pub held_out: Option<bool>,
    /// Stop sampling a pixel's test paths once this many carry light.
    #[arg(long, value_name = "L", default_value_t = GaConfig::default().max_light_paths as u32, value_parser = clap::value_parser!(u32).range(1..=100_000_000))]
    pub max_light_paths: u32,
}

/// Where the GA runs and how its results spread over the image, table `[plan]`.
#[derive(Args)]
#[command(next_help_heading = "GA plan (--method ga, ga-pt)")]
#[allow(dead_code)]
pub struct PlanArgs {
    /// Distance between GA pixels on the grid, in pixels. Default: 32 for ga, 64 for ga-pt
    #[arg(long, value_name = "PIXELS", value_parser = clap::value_parser!(u32).range(1..=MAX_IMAGE_SIDE as i64))]
    pub ga_grid: Option<u32>,
    /// Extra GA pixels where the baseline variance is high, as a fraction of the grid's.
    #[arg(long, default_value_t = PlanConfig::default().extra)]
    pub ga_extra: f64,
    /// srt samples per pixel of the baseline pass that places the extra GA pixels.
    #[arg(long, default_value_t = PlanConfig::default().baseline_spp, value_parser = clap::value_parser!(u32).range(1..=65_536))]
    pub baseline_spp: u32,
    /// ga: the image keeps the baseline's samples (they count among --spp, which must hold
    /// them) where the GA pixels' test paths show srt's variance at most this many times the
    /// evolved mixtures' (median); 0: never, inf: always.
    #[arg(long, default_value_t = PlanConfig::default().baseline_keep_ratio)]
    pub baseline_keep_ratio: f64,
    /// Nearest GA pixels whose mixtures each pixel combines. Default: 2 for ga, 4 for ga-pt
    #[arg(long, value_name = "K")]
    pub ga_neighbours: Option<usize>,
    /// Grid cells whose pooled baseline relative variance (of one srt sample, Var/(mean² +
    /// 0.01)) is below this get no GA pixel.
    #[arg(long, default_value_t = PlanConfig::default().prune_variance)]
    pub prune_variance: f64,
    /// Leave out of the GA the grid cells of low baseline variance and the generator steps
    /// past the depth the test paths need, and out of `ga`'s evolved mixtures the components
    /// that lower the variance on the test paths by less than their densities cost; `false`
    /// runs it everywhere with every step and component (ga-pt: still at most --guide-steps).
    #[arg(long, default_value_t = PlanConfig::default().prune, action = clap::ArgAction::Set, value_name = "BOOL")]
    pub prune: bool,
    /// Alias of `--prune false` (the first line of work's spelling).
    #[arg(long)]
    pub no_prune: bool,
    /// Evolve half the GA pixels (a checkerboard of grid cells) first and the others from
    /// their evolved neighbours' best individuals, with half the generations.
    #[arg(long, default_value_t = PlanConfig::default().warm_start, action = clap::ArgAction::Set, value_name = "BOOL")]
    pub warm_start: bool,
    /// Seconds the GA plan may take (baseline included); GA pixels not evolved by then are
    /// left out. The plan then depends on timing, not only on the seed.
    #[arg(long, value_name = "SECONDS")]
    pub ga_time_limit: Option<f64>,
    /// ga-pt: vertices the evolved guide steers (the GA evolves that many directional steps,
    /// at most as many as the test paths need); path tracing's own sampling beyond.
    #[arg(long, default_value_t = PlanConfig::default().guide_steps as u32, value_parser = clap::value_parser!(u32).range(1..=64))]
    pub guide_steps: u32,
    /// A GA pixel's test paths start in the square of this many grid spacings (--ga-grid)
    /// centred on it: the pixels its mixture renders, not that pixel alone (0: the pixel,
    /// the paper's). Default: 1 for ga, 0 for ga-pt
    #[arg(long, value_name = "GRID_SPACINGS")]
    pub footprint: Option<f64>,
}

/// The gate, table `[gate]`.
#[derive(Args)]
#[command(next_help_heading = "Gate (--method ga, ga-pt)")]
#[allow(dead_code)]
pub struct GateArgs {
    /// A pilot of the GA predicts whether it pays, and each pixel renders with its evolved
    /// mixture only where it is predicted to beat pt (see docs/methods.md, "the gate");
    /// `false` is the paper's method everywhere.
    #[arg(long, default_value_t = GateConfig::default().gate, action = clap::ArgAction::Set, value_name = "BOOL")]
    pub gate: bool,
    /// Alias of `--gate false` (the first line of work's spelling).
    #[arg(long)]
    pub no_gate: bool,
}

/// The spatial guide, table `[spatial]`.
#[derive(Args)]
#[command(next_help_heading = "Spatial guide (--method pg, ga-pt)")]
#[allow(dead_code)]
pub struct SpatialArgs {
    /// ga-pt: guide the vertices the GA does not steer with a spatial guide learned from
    /// path-traced training passes (see --spatial-passes), as --method pg does everywhere
    /// (beyond the paper). `false`: path tracing's own sampling there.
    #[arg(long, default_value_t = SpatialConfig::default().spatial_guide, action = clap::ArgAction::Set, value_name = "BOOL")]
    pub spatial_guide: bool,
    /// pg, and ga-pt with the spatial guide: passes of path tracing that train the spatial
    /// guide, pass i with 2^i samples per pixel; their samples count in --spp and stay in
    /// the image. Default: as many as fit in half of --spp.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=12))]
    pub spatial_passes: Option<u32>,
}

/// `--shard K/N`, of `render` and `reference`.
#[derive(Args)]
pub struct ShardArgs {
    /// Render shard K of N: of every pixel's samples, those s with s mod N = K, from the
    /// same random streams as the whole render, and write their per-pixel sums to
    /// `<FILE>.shard` beside the (first) output for `genpath merge` (docs/shards.md).
    /// Methods that learn (pg, ga, ga-pt) shard with --plan only.
    #[arg(long, value_name = "K/N")]
    pub shard: Option<Shard>,
    /// Continue the render from FILE, the shard file it wrote when a signal (SIGINT,
    /// SIGTERM) stopped it or at a checkpoint, to the image an uninterrupted render makes:
    /// the same command, with this flag added. Methods that learn: with --plan only.
    #[arg(long, value_name = "FILE")]
    pub resume: Option<PathBuf>,
    /// Write the shard file `<FILE>.shard` (as a stopped render does) every SECONDS while
    /// rendering, so that a render killed outright loses at most that much work: continue
    /// it with --resume. Methods that learn: with --plan only.
    #[arg(long, value_name = "SECONDS", value_parser = parse_seconds)]
    pub checkpoint: Option<f64>,
}

impl ShardArgs {
    /// Refuses, before anything loads, a plan file (`plan`) for a method that learns nothing,
    /// and a shard, a resume or a checkpoint of a method that learns unless its learned state
    /// comes from a plan file; `command`: `render` or `reference`, which learn their plans
    /// differently.
    pub fn check_method(&self, method: Method, plan: Option<&Path>, command: &str) -> Result<()> {
        if let (Some(plan), false) = (plan, method.learns()) {
            bail!(
                "--plan {}: --method {} learns nothing (plans are for pg, ga and ga-pt)",
                plan.display(),
                method.name()
            );
        }
        let learns = method.learns() && plan.is_none();
        let learn = match command {
            "reference" => "genpath learn --for-reference",
            _ => "genpath learn",
        };
        if self.shard.is_some() && learns {
            if command != "reference" {
                return Err(genpath::integrators::PrepareError::ShardLearns(method).into());
            }
            bail!(
                "--shard: --method {} learns in every reference (each half its GA plan or \
                 spatial guide), so shards of it would not be parts of one reference: the \
                 learned states must be trained once and shared with every shard: `{learn} … \
                 -o plan.bin`, then `reference --plan plan.bin --shard K/N` (docs/shards.md); \
                 or shard pt, srt or mixture",
                method.name()
            );
        }
        for (flag, given) in [
            ("--resume", self.resume.is_some()),
            ("--checkpoint", self.checkpoint.is_some()),
        ] {
            if given && learns {
                bail!(
                    "{flag}: --method {} learns in every {command} (its GA plan or spatial \
                     guide), which a resumed {command} would learn anew: learn once with \
                     `{learn} … -o plan.bin` and run {command} with --plan plan.bin, or resume \
                     pt, srt or mixture",
                    method.name()
                );
            }
        }
        if let Some(file) = &self.resume {
            if !file.is_file() {
                bail!("--resume {}: no such file", file.display());
            }
        }
        Ok(())
    }

    /// The shard of a render with `spp` samples per pixel (`what`: the flag that sets it).
    pub fn shard(&self, spp: u32, what: &str) -> Result<Shard> {
        let shard = self.shard.unwrap_or(Shard::WHOLE);
        if shard.count > spp {
            bail!(
                "--shard {shard}: {} shards of {spp} samples per pixel ({what}) leave some \
                 shards without a sample",
                shard.count
            );
        }
        Ok(shard)
    }
}

/// A checkpoint interval: a finite number of seconds, at least 0.
pub fn parse_seconds(text: &str) -> Result<f64, String> {
    let t: f64 = text.parse().map_err(|e| format!("{e}"))?;
    if (0.0..1e9).contains(&t) {
        Ok(t)
    } else {
        Err("must be a number of seconds, at least 0".into())
    }
}

pub fn parse_probability(text: &str) -> Result<f64, String> {
    let p: f64 = text.parse().map_err(|e| format!("{e}"))?;
    if (0.0..=1.0).contains(&p) {
        Ok(p)
    } else {
        Err("must be in [0, 1]".into())
    }
}

pub fn parse_absorption(text: &str) -> Result<f64, String> {
    let a: f64 = text.parse().map_err(|e| format!("{e}"))?;
    if (ABSORPTION_MIN..=ABSORPTION_MAX).contains(&a) {
        Ok(a)
    } else {
        Err(format!("must be in [{ABSORPTION_MIN}, {ABSORPTION_MAX}]"))
    }
}

impl SettingsArgs {
    /// The settings: the defaults, then `--config FILE`, then the flags given on the
    /// command line (`matches`: this command's), then each `--set`, in order.
    pub fn settings(&self, matches: &ArgMatches) -> Result<Settings> {
        let mut settings = match &self.config {
            Some(file) => {
                let text = std::fs::read_to_string(file)
                    .with_context(|| format!("cannot read {}", file.display()))?;
                Settings::from_toml(&text, &file.display().to_string())?
            }
            None => Settings::default(),
        };
        let ids = SettingsArgs::augment_args(clap::Command::new("settings"));
        for arg in ids.get_arguments() {
            let id = arg.get_id().as_str();
            if matches.value_source(id) != Some(ValueSource::CommandLine) {
                continue;
            }
            match id {
                "config" | "set" => {}
                "no_gate" => settings.gate.gate = false,
                "no_prune" => settings.plan.prune = false,
                "generators" => settings.mixture.generators = self.generators.clone(),
                _ => {
                    let raw = matches.get_raw(id).and_then(|mut v| v.next());
                    let value = raw.and_then(|v| v.to_str()).unwrap_or_default();
                    settings.set(id, value)?;
                }
            }
        }
        for assignment in &self.set {
            settings
                .assign(assignment)
                .with_context(|| format!("--set {assignment}"))?;
        }
        Ok(settings)
    }
}

impl MethodArgs {
    /// The method asked for, else the command's `default`.
    pub fn method_or(&self, default: Method) -> Method {
        self.method.unwrap_or(default)
    }

    /// The settings of the method ([`SettingsArgs::settings`]), checked before anything
    /// loads; `generators` goes with `--method mixture` only ([`load_mixture`] loads it).
    pub fn settings(&self, matches: &ArgMatches) -> Result<Settings> {
        let settings = self.settings.settings(matches)?;
        match (&settings.mixture.generators, self.method) {
            (Some(_), m) if m != Some(Method::Mixture) => {
                bail!("--generators is only used with --method mixture")
            }
            (None, Some(Method::Mixture)) => bail!("--method mixture needs --generators FILE"),
            _ => {}
        }
        Ok(settings)
    }
}

/// Loads `settings.mixture.generators`, if set, for `scene`.
pub fn load_mixture(settings: &mut Settings, scene: &Scene, max_bounces: u32) -> Result<()> {
    if let Some(file) = &settings.mixture.generators {
        let absorption = settings.srt.absorption(settings.srt.nee);
        settings.loaded_mixture = Some(mixture_file::load(file, scene, max_bounces, absorption)?);
    }
    Ok(())
}

/// `-D NAME=VALUE`.
pub fn parse_define(text: &str) -> Result<(String, String), String> {
    match text.split_once('=') {
        Some((name, value)) if !name.is_empty() => Ok((name.to_string(), value.to_string())),
        _ => Err(format!("`{text}` is not NAME=VALUE")),
    }
}
