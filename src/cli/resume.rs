//! Renders that outlive their process: SIGINT and SIGTERM (what Slurm sends at a time limit
//! or a preemption) stop a render within one sample per thread, and it writes what it has
//! as a shard file with its true per-pixel sample counts; `--checkpoint SECONDS` writes that
//! file while it runs; `--resume FILE` continues from such a file to the image an
//! uninterrupted render makes (docs/shards.md).

use super::args::ShardArgs;
use super::session::{header, Session};
use anyhow::{bail, Context, Result};
use genpath::film::{Checkpoint, LayerSums, Shard, Stop};
use genpath::integrators::Method;
use genpath::shard::{Identity, Part};
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicUsize;
use std::sync::Arc;
use std::time::Duration;

/// A render stopped by a signal, after it wrote what it had to `shard`: `main` exits with
/// `128 + signal`, as a shell reports a process the signal ended.
#[derive(Debug, thiserror::Error)]
#[error(
    "stopped by {name} with {fewest} to {most} of the {of} samples per pixel{layers}; they are \
     in {}: run the same command with --resume {} to continue",
    shard.display(), shard.display()
)]
pub struct Interrupted {
    pub signal: usize,
    pub name: &'static str,
    pub shard: PathBuf,
    pub fewest: u32,
    pub most: u32,
    pub of: u32,
    pub layers: &'static str,
}

impl Interrupted {
    /// The interruption of a render whose `layers` hold `of` samples per pixel when whole.
    pub fn new(signal: usize, shard: PathBuf, layers: &[LayerSums], of: u32) -> Self {
        let counts = || layers.iter().flat_map(|l| l.counts.iter().copied());
        Self {
            signal,
            name: signal_name(signal),
            shard,
            fewest: counts().min().unwrap_or(0),
            most: counts().max().unwrap_or(0),
            of,
            layers: if layers.len() > 1 { " per half" } else { "" },
        }
    }

    /// The process's exit status.
    pub fn exit_code(&self) -> i32 {
        128 + self.signal as i32
    }
}

/// Learning stopped by a signal, after it kept what it finished (the GA's waves, the spatial
/// guide's passes) in its folder: `main` exits with `128 + signal`.
#[derive(Debug, thiserror::Error)]
#[error(
    "stopped by {name} {detail}, kept in {}: run the same command to go on",
    dir.display()
)]
pub struct LearnInterrupted {
    pub signal: usize,
    pub name: &'static str,
    pub dir: PathBuf,
    pub detail: String,
}

impl LearnInterrupted {
    pub fn new(signal: usize, dir: PathBuf, detail: String) -> Self {
        Self {
            signal,
            name: signal_name(signal),
            dir,
            detail,
        }
    }

    /// The process's exit status.
    pub fn exit_code(&self) -> i32 {
        128 + self.signal as i32
    }
}

fn signal_name(signal: usize) -> &'static str {
    match signal as i32 {
        signal_hook::consts::SIGINT => "SIGINT",
        signal_hook::consts::SIGTERM => "SIGTERM",
        _ => "a signal",
    }
}

/// From now on, SIGINT and SIGTERM ask the render to stop. A second signal does no more
/// than the first: the render stops within one sample per thread anyway, and under Slurm
/// the job script and genpath may both be sent the same SIGTERM (SIGKILL still ends it).
pub fn stop_on_signals() -> Result<Stop> {
    let stop = Arc::new(AtomicUsize::new(0));
    for signal in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        signal_hook::flag::register_usize(signal, stop.clone(), signal as usize)
            .context("cannot install the signal handlers")?;
    }
    Ok(Stop::on(stop))
}

/// What a render's shard file flags and the signals give it: the shard file it keeps (with
/// `--shard`, `--resume` or `--checkpoint`), the layers it resumes from, and its stop.
pub struct Continuation {
    /// The render's identity, when it keeps a shard file (computed before the render, so
    /// that a render that cannot say what it is fails early).
    pub identity: Option<Identity>,
    /// `<output>.shard`.
    pub file: PathBuf,
    pub shard: Shard,
    /// What of the render's samples the file holds besides `shard`'s.
    pub part: Part,
    /// The layers of `--resume FILE`.
    pub resumed: Option<Vec<LayerSums>>,
    pub stop: Stop,
    every: Option<f64>,
}

impl Continuation {
    /// The continuation of `session`'s render of `method`, shard `shard` (and `part`), with
    /// `args`, writing `file`; `identity` computes the render's identity. `learned`: the
    /// method's learned state comes from a plan file (`--plan`).
    pub fn new(
        args: &ShardArgs,
        (method, learned): (Method, bool),
        (shard, part): (Shard, Part),
        file: PathBuf,
        identity: impl Fn() -> Result<Identity>,
    ) -> Result<Self> {
        let keeps = args.shard.is_some() || args.resume.is_some() || args.checkpoint.is_some();
        let identity = if keeps { Some(identity()?) } else { None };
        let resumed = match (&args.resume, &identity) {
            (Some(path), Some(identity)) => Some(read_resume(path, identity, shard, part)?),
            _ => None,
        };
        // A method that learns (a GA plan, a spatial guide) would learn anew when resumed,
        // unless its learned state is read from a plan file: a signal ends it as it ends
        // any process.
        let stop = if method.learns() && !learned {
            Stop::default()
        } else {
            stop_on_signals()?
        };
        Ok(Self {
            identity,
            file,
            shard,
            part,
            resumed,
            stop,
            every: args.checkpoint,
        })
    }

    /// Layer `i` of the resumed file, if resuming.
    pub fn resumed(&self, i: usize) -> Option<Arc<LayerSums>> {
        self.resumed
            .as_ref()
            .and_then(|layers| layers.get(i))
            .map(|layer| Arc::new(layer.clone()))
    }

    /// The checkpoints of `session`'s render (`--checkpoint SECONDS`): `layers(sums)` is
    /// what the file holds when the layer being rendered has `sums`.
    pub fn checkpoint(
        &self,
        session: &Session,
        layers: impl Fn(&LayerSums) -> Vec<LayerSums> + Send + Sync + 'static,
    ) -> Option<Checkpoint> {
        let every = Duration::from_secs_f64(self.every?);
        let header = header(session, self.identity.clone()?, (self.shard, self.part));
        let path = self.file.clone();
        let write = move |sums: &LayerSums| {
            if let Err(e) = genpath::shard::file::write(&path, &header, &layers(sums)) {
                eprintln!("genpath: warning: checkpoint not written: {e}");
            }
        };
        Some(Checkpoint {
            every,
            write: Arc::new(write),
        })
    }

    /// After the render: if a signal stopped it, writes `layers` (of `of` samples per pixel
    /// each when whole) to the shard file and fails with [`Interrupted`].
    pub fn check_stopped(
        &self,
        session: &Session,
        layers: &[LayerSums],
        of: u32,
        identity: impl Fn() -> Result<Identity>,
    ) -> Result<()> {
        let Some(signal) = self.stop.requested() else {
            return Ok(());
        };
        let identity = match &self.identity {
            Some(identity) => identity.clone(),
            None => identity()?,
        };
        session.write_shard(&self.file, identity, (self.shard, self.part), layers)?;
        Err(Interrupted::new(signal, self.file.clone(), layers, of).into())
    }

    /// Writes the shard file of a finished render, if it keeps one: what its JSON records
    /// of it.
    pub fn finish(
        &self,
        session: &Session,
        layers: &[LayerSums],
        spp_key: &str,
        spp: u32,
        resume: Option<&Path>,
    ) -> Result<serde_json::Value> {
        let Some(identity) = &self.identity else {
            return Ok(serde_json::Value::Null);
        };
        session.write_shard(
            &self.file,
            identity.clone(),
            (self.shard, self.part),
            layers,
        )?;
        Ok(serde_json::json!({
            "shard": self.shard.to_string(),
            spp_key: spp,
            "file": self.file,
            "resumed_from": resume,
            "identity": identity,
        }))
    }
}

/// `--resume FILE`: its layers, after checking that it is a shard of this very render.
fn read_resume(
    path: &Path,
    identity: &Identity,
    shard: Shard,
    part: Part,
) -> Result<Vec<LayerSums>> {
    let (header, layers) =
        genpath::shard::file::read(path).with_context(|| format!("--resume {}", path.display()))?;
    if let Some((what, theirs, ours)) = header.identity.difference(identity) {
        bail!(
            "--resume {}: it holds another render's samples: {what} is {theirs} there and \
             {ours} here (run the command that wrote it, with the same build, scene and \
             settings)",
            path.display()
        );
    }
    if header.shard != shard {
        bail!(
            "--resume {}: it holds shard {} of the render, and this is shard {shard}",
            path.display(),
            header.shard
        );
    }
    if header.part != part {
        bail!(
            "--resume {}: it holds the {:?} part of the render, and this renders the {part:?} part",
            path.display(),
            header.part
        );
    }
    Ok(layers)
}
