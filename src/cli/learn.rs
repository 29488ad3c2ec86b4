//! `genpath learn`: prepares a method that learns (`ga`, `ga-pt`, `pg`) exactly as `render`
//! does and saves what it learned in a plan file ([`genpath::shard::plan_file`]), with the
//! training's samples (pg, ga-pt) in a training shard beside it; and `render --plan`'s side
//! of it, [`super::saved_plan::read_plan`]: "learn once, render everywhere" (docs/shards.md). With
//! `--for-reference` it learns the two halves of `genpath reference` instead, each as the
//! reference does (its own derived seed, half the samples), into one plan file and one
//! training shard with a layer per half, for `reference --plan`.
//!
//! Learning keeps what it finished in a folder ([`LearnDir`]): a GA plan's waves of GA
//! pixels as they finish, the spatial guide's training after each pass. Learning stopped by
//! SIGINT or SIGTERM goes on from there when the command runs again, and `learn --shard K/N`
//! splits the GA over jobs: each job evolves its share of the first wave not yet complete
//! and stops there (the waves are the barriers between the steps of a job array); `learn`
//! without `--shard` then builds the plan from every share.

use super::args::{MethodArgs, SceneArgs};
use super::check_dir;
use super::saved_plan::training_layer;
use super::session::{beside, shard_path, write_stats, Session};
use anyhow::{bail, Context, Result};
use clap::{ArgMatches, Args};
use genpath::film::{LayerSums, Shard, Stop};
use genpath::genetic::plan::{LearnStore, PlanError, StoreError, WaveEntry};
use genpath::integrators::{prepare, Learned, Method, PrepareError, RenderSettings};
use genpath::path::SceneView;
use genpath::shard::plan_file::{self, PlanHeader, TrainingHeader, WaveHeader};
use genpath::shard::{Identity, Part, PlanRef};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

#[derive(Args)]
pub struct LearnArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// The plan file to write (any name; `plan.bin`). Where the training took samples (pg,
    /// ga-pt with the spatial guide), they go to the training shard `<FILE>.shard`, which
    /// `genpath merge` adds to the render's shards; a `<FILE>.json` summarises the plan.
    #[arg(short, long = "output", value_name = "FILE")]
    pub output: PathBuf,
    /// Samples per pixel of the render the plan is for (pass the same to `render --plan`)
    /// [default: a Mitsuba scene's `sample_count`, else 64; with --for-reference,
    /// reference's 4096].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1 << 24))]
    pub spp: Option<u32>,
    /// Learn for `genpath reference` (same flags; --spp is the reference's, split into two
    /// halves) instead of `render`: each half as the reference learns it, from its own seed
    /// at half the samples, both in the plan file and their training samples in one
    /// training shard, for `reference --plan FILE` (docs/shards.md).
    #[arg(long)]
    pub for_reference: bool,
    /// Split the GA (ga, ga-pt) over N jobs: this one evolves the GA pixels j of the first
    /// wave not yet complete with j mod N = K, keeps them in the learning folder, and stops.
    /// The GA has four waves (the gate's pilot, the pilot going on, the first wave, the
    /// warm-started second), each a barrier: run the N jobs four times, one step after
    /// another (a job array per step), then `learn` without --shard to build the plan from
    /// the waves (docs/shards.md; scripts/slurm/submit.sh does it).
    #[arg(long, value_name = "K/N")]
    pub shard: Option<Shard>,
    /// The folder where learning keeps what it finished: the GA's waves of GA pixels as
    /// they finish (shared by every job of a split GA) and the spatial guide's training
    /// after each pass [default: `<FILE>.learning`, removed once the plan is written].
    /// Learning stopped by SIGINT or SIGTERM goes on from it when the same command runs
    /// again.
    #[arg(long, value_name = "DIR")]
    pub learn_dir: Option<PathBuf>,
    #[command(flatten)]
    pub method: MethodArgs,
}

pub fn run_learn(args: LearnArgs, matches: &ArgMatches) -> Result<()> {
    check_dir(&args.output)?;
    let method = args.method.method_or(Method::GaPt);
    let shard = args.shard.unwrap_or(Shard::WHOLE);
    check_learns(method, shard)?;
    if let (true, Some(spp @ 0..=1)) = (args.for_reference, args.spp) {
        bail!("--spp {spp}: a reference's two halves need at least 2 samples per pixel");
    }
    let config = args.method.settings(matches)?;
    let session = Session::open(&args.scene)?;
    let stop = super::resume::stop_on_signals()?;
    let dir = (args.learn_dir.clone()).unwrap_or_else(|| beside(&args.output, ".learning"));
    let (identity, targets) = targets(&args, &session, method, &config, &dir)?;
    let view = SceneView::new(&session.scene, session.accel.as_ref());
    let t_learn = Instant::now();
    let mut learned = Vec::new();
    for target in targets {
        let quiet = args.scene.quiet;
        if let Some(one) = learn_one(&session, &view, &config, target, (shard, &stop), quiet)? {
            learned.push(one);
        }
    }
    if !shard.is_whole() {
        return Ok(());
    }
    let learn_s = t_learn.elapsed().as_secs_f64();
    let payload = match &learned[..] {
        [one] => plan_file::payload(one),
        [a, b] => plan_file::payload_halves(a, b),
        _ => unreachable!("a render learns one state, a reference two"),
    };
    let payload = payload
        .map_err(|e| anyhow::anyhow!("{}: cannot encode the plan: {e}", args.output.display()))?;
    let reference = PlanRef {
        hash: genpath::shard::hash_bytes(&payload),
        training_spp: learned.iter().map(Learned::training_spp).max().unwrap_or(0),
    };
    let summary = match &learned[..] {
        [one] => one.summary(),
        halves => {
            serde_json::json!({ "halves": halves.iter().map(Learned::summary).collect::<Vec<_>>() })
        }
    };
    let header = PlanHeader {
        identity: identity.clone(),
        training_spp: reference.training_spp,
        summary,
        scene_path: session.scene.path.clone(),
        command_line: std::env::args().collect(),
    };
    plan_file::write(&args.output, &header, &payload)?;
    let training = training_shard(&session, &args.output, &learned, identity, &reference)?;
    let json = serde_json::json!({
        "genpath_version": env!("CARGO_PKG_VERSION"),
        "command_line": header.command_line,
        "scene": header.scene_path,
        "identity": header.identity,
        "plan_file": { "file": args.output, "hash": reference.hash, "bytes": payload.len() },
        "training_spp": reference.training_spp,
        "training_shard": training,
        "summary": header.summary,
        "threads": session.pool.current_num_threads(),
        "times_s": { "load": session.load_s, "accel_build": session.accel_s, "learn": learn_s },
    });
    write_stats(std::slice::from_ref(&args.output), &json)?;
    if args.learn_dir.is_none() {
        std::fs::remove_dir_all(&dir)
            .with_context(|| format!("cannot remove {}", dir.display()))?;
    }
    if !args.scene.quiet {
        let plan = (&header, &reference, payload.len());
        report(
            &session,
            &args.output,
            plan,
            training.as_deref(),
            (method, learn_s),
        );
    }
    Ok(())
}

/// What `learn` tells on stderr of the plan it wrote to `output` (`header`, `reference`,
/// its payload's bytes) and its training shard.
fn report(
    session: &Session,
    output: &Path,
    (header, reference, bytes): (&PlanHeader, &PlanRef, usize),
    training: Option<&Path>,
    (method, learn_s): (Method, f64),
) {
    let id = &header.identity;
    let (spp, per_half) = match id.command.as_str() {
        "reference" => (
            format!(
                "a reference of {} spp (two halves of {})",
                2 * id.spp,
                id.spp
            ),
            " per half",
        ),
        _ => (format!("{} spp", id.spp), ""),
    };
    let shard = training.map_or_else(String::new, |t| {
        format!(
            ", its {} training samples per pixel{per_half} in {}",
            reference.training_spp,
            t.display()
        )
    });
    eprintln!(
        "genpath: learned {} for {}×{} at {spp} in {learn_s:.2} s → {} ({bytes} bytes){shard}",
        method.name(),
        session.scene.camera.width,
        session.scene.camera.height,
        output.display(),
    );
}

/// One learned state that `learn` makes: a render's, or one half of a reference's.
struct Target {
    /// The render it learns for: its seed and samples per pixel.
    settings: RenderSettings,
    /// Where its learning keeps what it finished, and the identity its files carry.
    dir: PathBuf,
    identity: Identity,
    /// How messages name it: empty, or `half 1: `.
    label: String,
}

/// The identity of the plan `args` learn (a render's, or with `--for-reference` a
/// reference's), and what it learns: the render's one state in `dir`, or each half of the
/// reference as `genpath reference` learns it (its seed derived from `--seed`, half of
/// `--spp`) in `dir/half-1` and `dir/half-2`.
fn targets(
    args: &LearnArgs,
    session: &Session,
    method: Method,
    config: &genpath::integrators::Settings,
    dir: &Path,
) -> Result<(Identity, Vec<Target>)> {
    if !args.for_reference {
        let spp = args.spp.or(session.scene.render.spp).unwrap_or(64);
        let settings = session.settings(&args.scene, method, spp);
        let seeds = vec![settings.seed];
        let identity = session.identity("render", &args.scene, &settings, seeds, config)?;
        let target = Target {
            settings,
            dir: dir.to_path_buf(),
            identity: identity.clone(),
            label: String::new(),
        };
        return Ok((identity, vec![target]));
    }
    let half_spp = args.spp.unwrap_or(super::reference::DEFAULT_SPP) / 2;
    let settings = session.settings(&args.scene, method, half_spp);
    let seeds = super::reference::half_seeds(args.scene.seed);
    let identity = session.identity("reference", &args.scene, &settings, seeds.to_vec(), config)?;
    let targets = (0..2)
        .map(|i| Target {
            settings: RenderSettings {
                seed: seeds[i],
                ..settings.clone()
            },
            dir: dir.join(format!("half-{}", i + 1)),
            identity: Identity {
                half: Some(i as u32 + 1),
                ..identity.clone()
            },
            label: format!("half {}: ", i + 1),
        })
        .collect();
    Ok((identity, targets))
}

/// Learns `target` (`shard`: this job's share of a split GA; `stop`: the signals): its
/// learned state, or none where this job of a split GA did its share of a wave.
fn learn_one(
    session: &Session,
    view: &SceneView,
    config: &genpath::integrators::Settings,
    target: Target,
    (shard, stop): (Shard, &Stop),
    quiet: bool,
) -> Result<Option<Learned>> {
    let store = LearnDir::open(target.dir.clone(), target.identity, shard, stop.clone())?;
    // The target's one `RenderSettings`, with the signals that stop it and the store.
    let mut settings = target.settings;
    settings.control.stop = stop.clone();
    settings.learning = Some(Arc::new(store));
    let t_learn = Instant::now();
    let prepared = match session.pool.install(|| prepare(view, config, &settings)) {
        Ok(prepared) => prepared,
        Err(e) => {
            let ended = (shard, target.dir.as_path(), t_learn, &target.label[..]);
            return learning_ended(e, ended, quiet).map(|()| None);
        }
    };
    if let Some(signal) = stop.requested() {
        let detail = format!(
            "{}in the spatial guide's training, with its finished passes",
            target.label
        );
        return Err(super::resume::LearnInterrupted::new(signal, target.dir, detail).into());
    }
    if !shard.is_whole() {
        // The method learned nothing to split (the gate closed the GA before its waves).
        if !quiet {
            eprintln!(
                "genpath: learn --shard {shard}: {}the GA has no wave left; learn without \
                 --shard builds the plan",
                target.label
            );
        }
        return Ok(None);
    }
    let method = settings.method;
    let learned = prepared
        .learned()
        .with_context(|| format!("--method {} kept no learned state", method.name()))?;
    Ok(Some(learned))
}

/// Refuses a `method` that learns nothing, and a split (`shard`) of one without a GA.
fn check_learns(method: Method, shard: Shard) -> Result<()> {
    use clap::ValueEnum;
    let name = method.name();
    let learning: Vec<String> = (Method::value_variants().iter())
        .filter(|m| m.learns())
        .map(|m| m.name())
        .collect();
    if !method.learns() {
        bail!(
            "--method {name} learns nothing (learn is for {}): render it, with --shard K/N to \
             split it",
            learning.join(", ")
        );
    }
    if !shard.is_whole() && !method.info().splits_learning {
        bail!(
            "--shard {shard}: {name} learns no GA plan to split (its learning runs in one \
             job): learn it without --shard"
        );
    }
    Ok(())
}

/// What a learning that `prepare` ended with `e` reports: `Ok` where this job of a split GA
/// (`shard`) finished its share of a wave, [`super::resume::LearnInterrupted`] where a signal
/// stopped the GA (what it finished is kept in `dir`), else `e`.
fn learning_ended(
    e: PrepareError,
    (shard, dir, t_learn, label): (Shard, &Path, Instant, &str),
    quiet: bool,
) -> Result<()> {
    match e {
        PrepareError::Plan(done @ PlanError::ShareDone { .. }) => {
            if !quiet {
                eprintln!(
                    "genpath: learn --shard {shard}: {label}{done} ({:.2} s; kept in {})",
                    t_learn.elapsed().as_secs_f64(),
                    dir.display()
                );
            }
            Ok(())
        }
        PrepareError::Plan(PlanError::Stopped {
            signal,
            wave,
            done,
            jobs,
        }) => {
            let detail = format!(
                "{label}in wave {wave} of the GA, with {done} of its {jobs} GA pixels evolved"
            );
            Err(super::resume::LearnInterrupted::new(signal, dir.to_path_buf(), detail).into())
        }
        e => Err(e.into()),
    }
}

/// What learning finished, kept as files in a folder: `wave-W.K-of-N.bin`, the GA pixels of
/// wave `W` that job `K/N` evolved (plan_file's wave files), and `training.bin`, the spatial
/// guide's training after its last finished pass; every file is checked against the render
/// the plan is learned for.
#[derive(Debug)]
pub struct LearnDir {
    dir: PathBuf,
    identity: Identity,
    shard: Shard,
    stop: Stop,
}

impl LearnDir {
    /// The folder at `dir`, made if it does not exist.
    fn open(dir: PathBuf, identity: Identity, shard: Shard, stop: Stop) -> Result<Self> {
        std::fs::create_dir_all(&dir)
            .with_context(|| format!("--learn-dir {}: cannot make the folder", dir.display()))?;
        Ok(Self {
            dir,
            identity,
            shard,
            stop,
        })
    }

    /// This job's file of wave `wave`.
    fn file(&self, wave: usize) -> PathBuf {
        let Shard { index, count } = self.shard;
        self.dir.join(format!("wave-{wave}.{index}-of-{count}.bin"))
    }

    /// Every wave file of wave `wave`, by name.
    fn files(&self, wave: usize) -> std::io::Result<Vec<PathBuf>> {
        let prefix = format!("wave-{wave}.");
        let mut files: Vec<PathBuf> = std::fs::read_dir(&self.dir)?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| {
                p.file_name()
                    .and_then(|n| n.to_str())
                    .is_some_and(|n| n.starts_with(&prefix) && n.ends_with(".bin"))
            })
            .collect();
        files.sort();
        Ok(files)
    }

    /// Refuses the file at `path`, kept for the render of `identity`, where that is not
    /// this learning's render.
    fn check(&self, path: &Path, identity: &Identity) -> Result<(), String> {
        match identity.difference(&self.identity) {
            Some((what, theirs, ours)) => Err(format!(
                "{}: it was learned for another render: {what} is {theirs} there and {ours} \
                 here (every job of a split GA must run the same command but for --shard)",
                path.display()
            )),
            None => Ok(()),
        }
    }

    /// A wave file's results, refused where it is of another render or another wave.
    fn read(&self, path: &Path, wave: usize) -> Result<Vec<WaveEntry>, String> {
        let (header, entries) = plan_file::read_waves(path).map_err(|e| e.to_string())?;
        self.check(path, &header.identity)?;
        if header.wave != wave {
            return Err(format!(
                "{}: it holds wave {}, not {wave}",
                path.display(),
                header.wave
            ));
        }
        Ok(entries)
    }
}

impl LearnStore for LearnDir {
    fn load(&self, wave: usize) -> Result<Vec<WaveEntry>, StoreError> {
        let files = self
            .files(wave)
            .map_err(|e| format!("{}: {e}", self.dir.display()))?;
        let mut entries = Vec::new();
        for path in files {
            entries.extend(self.read(&path, wave)?);
        }
        Ok(entries)
    }

    fn save(&self, wave: usize, jobs: usize, entries: &[WaveEntry]) -> Result<(), StoreError> {
        let path = self.file(wave);
        let mut all = match path.exists() {
            true => self.read(&path, wave)?,
            false => Vec::new(),
        };
        all.extend_from_slice(entries);
        let header = WaveHeader {
            identity: self.identity.clone(),
            wave,
            jobs,
            shard: self.shard.to_string(),
        };
        plan_file::write_waves(&path, &header, &all).map_err(|e| StoreError(e.to_string()))
    }

    fn mine(&self, job: usize) -> bool {
        job % self.shard.count as usize == self.shard.index as usize
    }

    fn split(&self) -> bool {
        !self.shard.is_whole()
    }

    fn stop_requested(&self) -> Option<usize> {
        self.stop.requested()
    }

    fn load_training(&self) -> Result<Option<Vec<u8>>, StoreError> {
        let path = self.dir.join("training.bin");
        if !path.exists() {
            return Ok(None);
        }
        let (header, state) = plan_file::read_training(&path).map_err(|e| e.to_string())?;
        self.check(&path, &header.identity)?;
        Ok(Some(state))
    }

    fn save_training(&self, passes: u32, state: &[u8]) -> Result<(), StoreError> {
        let header = TrainingHeader {
            identity: self.identity.clone(),
            passes,
        };
        plan_file::write_training(&self.dir.join("training.bin"), &header, state)
            .map_err(|e| StoreError(e.to_string()))
    }
}

/// Writes the training's samples, if it took any, as the training shard beside `output`
/// (a layer per state in `learned`: a reference's two halves): its path.
fn training_shard(
    session: &Session,
    output: &Path,
    learned: &[Learned],
    identity: Identity,
    reference: &PlanRef,
) -> Result<Option<PathBuf>> {
    if reference.training_spp == 0 {
        return Ok(None);
    }
    let pixels = (session.scene.camera.width * session.scene.camera.height) as usize;
    let layers: Vec<LayerSums> = learned.iter().map(|l| training_layer(l, pixels)).collect();
    let identity = Identity {
        plan: Some(reference.clone()),
        ..identity
    };
    let path = shard_path(output);
    session.write_shard(&path, identity, (Shard::WHOLE, Part::Training), &layers)?;
    Ok(Some(path))
}
