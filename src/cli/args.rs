//! The arguments every command that renders shares: the scene, the method and its settings.

use anyhow::{bail, Context, Result};
use clap::{ArgMatches, Args};
use genpath::accel::{AccelKind, EmbreeIsa};
use genpath::film::Shard;
use genpath::integrators::{Method, Settings};
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

/// What the methods other than `pt` are made of: `--config`, `--set`, and a flag for every
/// setting of [`genpath::integrators::Settings`], named after its one name (the key with
/// dashes), with the help, default and range its table declares ([`SettingFlags`]).
#[derive(Args)]
pub struct SettingsArgs {
    /// Settings from a TOML file, one table per concern (`[ga] test_paths = 4000`; see
    /// docs/settings.md); flags and --set override it.
    #[arg(long, value_name = "FILE", help_heading = "Settings")]
    pub config: Option<PathBuf>,
    /// A setting by its name, `KEY=VALUE` (`test_paths=4000` or `ga.test_paths=4000`),
    /// after --config and the flags; repeatable.
    #[arg(long = "set", value_name = "KEY=VALUE", help_heading = "Settings")]
    pub set: Vec<String>,
    #[command(flatten)]
    pub flags: SettingFlags,
}

/// The flags of every setting, from the tables' declarations ([`Settings::args`]). They are
/// read from the command line's matches by [`SettingsArgs::settings`], after `--config`, so
/// this holds nothing.
pub struct SettingFlags;

impl clap::FromArgMatches for SettingFlags {
    fn from_arg_matches(_: &ArgMatches) -> Result<Self, clap::Error> {
        Ok(Self)
    }
    fn update_from_arg_matches(&mut self, _: &ArgMatches) -> Result<(), clap::Error> {
        Ok(())
    }
}

impl Args for SettingFlags {
    fn augment_args(command: clap::Command) -> clap::Command {
        command.args(Settings::args())
    }
    fn augment_args_for_update(command: clap::Command) -> clap::Command {
        Self::augment_args(command)
    }
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
        settings.read_flags(matches)?;
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
