//! `genpath reference`: a long render in two independent halves, with its own noise estimate.
//! A method that learns learns in each half, or takes each half's learned state from a plan
//! file (`--plan`, written by `genpath learn --for-reference`), which lets it shard.

use super::args::{load_mixture, MethodArgs, SceneArgs, ShardArgs};
use super::check_output;
use super::resume::Continuation;
use super::saved_plan::{read_plan, training_layer, SavedPlan};
use super::session::{rays_json, shard_path, write_stats, Session};
use anyhow::{bail, Result};
use clap::{ArgMatches, Args};
use genpath::film::{Control, Film, LayerSums, Shard};
use genpath::image::Image;
use genpath::integrators::{prepare, prepare_learned, Learned, RenderSettings};
use genpath::path::SceneView;
use genpath::sampling::{derive_seed, Stream};
use genpath::shard::{Identity, Part};
use std::path::PathBuf;

/// `reference`'s default `--spp` (and `learn --for-reference`'s).
pub const DEFAULT_SPP: u32 = 4096;

#[derive(Args)]
pub struct ReferenceArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// The reference image (EXR); `<FILE>.json` beside it holds its noise estimate.
    #[arg(short, long = "output", value_name = "FILE")]
    pub output: PathBuf,
    /// Samples per pixel, split into two independent halves.
    #[arg(long, default_value_t = DEFAULT_SPP, value_parser = clap::value_parser!(u32).range(2..=1 << 24))]
    pub spp: u32,
    #[command(flatten)]
    pub shard: ShardArgs,
    /// Render each half with its learned state in FILE (`genpath learn --for-reference`,
    /// with the same scene and flags) instead of learning it: the reference is the one that
    /// learns, bit for bit, and methods that learn (pg, ga, ga-pt) may then be sharded
    /// (merge the shards with the learn job's training shard, `<FILE>.shard`), resumed and
    /// checkpointed (docs/shards.md).
    #[arg(long, value_name = "FILE")]
    pub plan: Option<PathBuf>,
    /// The method (default `pt`) and its settings: each half prepares it anew, from its own
    /// seed, or takes what it learned from `--plan`.
    #[command(flatten)]
    pub method: MethodArgs,
}

/// The seeds of a reference's two halves, derived from `--seed`, so that neither shares
/// random numbers with a render made with the same `--seed` (that would correlate its
/// error with the reference's and understate it).
pub fn half_seeds(seed: u64) -> [u64; 2] {
    [Stream::ReferenceFirst, Stream::ReferenceSecond].map(|stream| derive_seed(seed, stream.tag()))
}

/// Two independent halves, averaged; their relMSE against each other is about four times
/// the average's own relMSE (each half has twice its variance, and both count).
pub fn run_reference(args: ReferenceArgs, matches: &ArgMatches) -> Result<()> {
    let method = args.method.method_or(genpath::integrators::Method::Pt);
    check_args(&args, method)?;
    // Settings first, before any loading.
    let mut config = args.method.settings(matches)?;
    let session = Session::open(&args.scene)?;
    let max_bounces = session.settings(&args.scene, method, 1).max_bounces;
    load_mixture(&mut config, &session.scene, max_bounces)?;
    let view = SceneView::new(&session.scene, session.accel.as_ref());
    let half_spp = args.spp / 2;
    let shard = args.shard.shard(half_spp, "half of --spp, per half")?;
    let seeds = half_seeds(args.scene.seed);
    let plain = || {
        let settings = session.settings(&args.scene, method, half_spp);
        session.identity("reference", &args.scene, &settings, seeds.to_vec(), &config)
    };
    let saved = match &args.plan {
        Some(path) => Some(read_plan(path, &plain()?, shard)?),
        None => None,
    };
    let plan_ref = saved.as_ref().map(SavedPlan::reference);
    let identity = || {
        Ok(Identity {
            plan: plan_ref.clone(),
            ..plain()?
        })
    };
    let pixels = (session.scene.camera.width * session.scene.camera.height) as usize;
    let halves = Halves::new(saved, shard, half_spp, pixels);
    let file = shard_path(&args.output);
    let what = ((method, halves.plan.is_some()), (shard, halves.part));
    let continuation = Continuation::new(&args.shard, what.0, what.1, file, identity)?;
    let [first, second] = halves.learned;
    // Half `i` with its learned state `learned` (if from a plan file), resumed from its
    // layer of `--resume`, its checkpoints holding `other` as the other half's layer.
    let half = |i: usize, other: LayerSums, learned: Option<Learned>| -> Result<Film> {
        let layers = move |sums: &LayerSums| {
            let mut layers = vec![sums.clone(), other.clone()];
            layers.swap(0, i);
            layers
        };
        let settings = RenderSettings {
            seed: seeds[i],
            shard,
            control: Control {
                stop: continuation.stop.clone(),
                resume: continuation.resumed(i),
                checkpoint: continuation.checkpoint(&session, layers),
            },
            ..session.settings(&args.scene, method, half_spp)
        };
        session.pool.install(|| {
            let integrator = match learned {
                Some(learned) => prepare_learned(&view, &config, &settings, learned)?,
                None => prepare(&view, &config, &settings)?,
            };
            Ok(integrator.render(&view, &settings))
        })
    };
    // The second half's layer before it renders: what it resumes from, or starts from.
    let second_start = continuation
        .resumed(1)
        .map_or_else(|| halves.start[1].clone(), |l| l.as_ref().clone());
    let a = half(0, second_start.clone(), first)?;
    let b = match continuation.stop.requested() {
        None => Some(half(1, a.sums.clone(), second)?),
        Some(_) => None,
    };
    let second_sums = b.as_ref().map_or(second_start, |b| b.sums.clone());
    let layers = [a.sums.clone(), second_sums];
    continuation.check_stopped(&session, &layers, halves.of, identity)?;
    let Some(b) = b else {
        unreachable!("the second half ran, since no signal stopped the first");
    };
    let plan_json = halves.plan.as_ref().map(SavedPlan::json);
    let done = Done {
        halves: [a, b],
        layers,
        seeds,
        plan_json,
    };
    finish(&args, &session, method, &continuation, done)
}

/// Refuses, before anything loads, an output that is not an EXR or cannot be written, a
/// plan for a method that learns nothing, and a shard, resume or checkpoint of a method that
/// learns without a plan.
fn check_args(args: &ReferenceArgs, method: genpath::integrators::Method) -> Result<()> {
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
    args.shard
        .check_method(method, args.plan.as_deref(), "reference")
}

/// What a reference's two halves start from and take: their learned states from a plan
/// file (none where they learn, or learn nothing), the layer each starts from (the
/// training's samples, which a whole reference with a plan keeps), the part of the samples
/// its shard file holds and how many samples per pixel (per half) a whole one holds.
struct Halves {
    plan: Option<SavedPlan>,
    learned: [Option<Learned>; 2],
    start: [LayerSums; 2],
    part: Part,
    of: u32,
}

impl Halves {
    fn new(plan: Option<SavedPlan>, shard: Shard, half_spp: u32, pixels: usize) -> Self {
        let mut plan = plan;
        let mut learned = [None, None];
        if let Some(saved) = plan.as_mut() {
            for (slot, state) in learned.iter_mut().zip(saved.learned.drain(..)) {
                *slot = Some(state);
            }
        }
        let training = learned
            .each_ref()
            .map(|l| l.as_ref().map_or(0, Learned::training_spp));
        let whole = shard.is_whole();
        let start = learned.each_ref().map(|l| match (l, whole) {
            (Some(l), true) => training_layer(l, pixels),
            _ => LayerSums::zero(pixels),
        });
        let part = match (whole, training.iter().any(|&t| t > 0)) {
            (true, true) => Part::WithTraining,
            _ => Part::Samples,
        };
        let of = match whole {
            true => half_spp,
            // A shard takes its share of each half's samples after its training's.
            false => (training.iter())
                .map(|&t| shard.samples_of(half_spp.saturating_sub(t)))
                .max()
                .unwrap_or(0),
        };
        Self {
            plan,
            learned,
            start,
            part,
            of,
        }
    }
}

/// A reference's two rendered halves, their layers, their seeds and its plan file's JSON.
struct Done {
    halves: [Film; 2],
    layers: [LayerSums; 2],
    seeds: [u64; 2],
    plan_json: Option<serde_json::Value>,
}

/// Writes the reference of `done`'s halves, its shard file if it keeps one, and its JSON.
fn finish(
    args: &ReferenceArgs,
    session: &Session,
    method: genpath::integrators::Method,
    continuation: &Continuation,
    done: Done,
) -> Result<()> {
    let [a, b] = &done.halves;
    let (image, reference) = average_halves(&a.image, &b.image, done.seeds, args.spp / 2);
    genpath::image::write(&args.output, &image)?;
    let resume = args.shard.resume.as_deref();
    let spp_key = "samples_per_pixel_per_half";
    let shard_json = continuation.finish(session, &done.layers, spp_key, a.spp, resume)?;
    let settings = session.settings(&args.scene, method, args.spp / 2 * 2);
    let seconds = a.elapsed.as_secs_f64() + b.elapsed.as_secs_f64();
    let mut stats = session.stats(&settings);
    let estimate = reference["relmse_estimate"].as_f64().unwrap_or(f64::NAN);
    stats.insert("reference".into(), reference);
    stats.insert("shard".into(), serde_json::json!(shard_json));
    stats.insert("plan_file".into(), serde_json::json!(done.plan_json));
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
            a.spp * 2,
            estimate,
            args.output.display()
        );
    }
    Ok(())
}

/// The reference, the pixel-wise average of its two halves, and what its JSON records of
/// them: the halves' seeds and samples, and the noise estimate from their difference.
pub fn average_halves(
    a: &Image,
    b: &Image,
    seeds: [u64; 2],
    spp_per_half: u32,
) -> (Image, serde_json::Value) {
    let Some(between) = genpath::image::metrics::compare(a, b) else {
        unreachable!("both halves have the scene's size");
    };
    let mut image = a.clone();
    for (p, q) in image.pixels.iter_mut().zip(&b.pixels) {
        *p = std::array::from_fn(|c| 0.5 * (p[c] + q[c]));
    }
    let json = serde_json::json!({
        "half_seeds": seeds,
        "spp_per_half": spp_per_half,
        "relmse_between_halves": between.relmse,
        "relmse_estimate": between.relmse / 4.0,
        "mse_estimate": between.mse / 4.0,
        "bad_fraction": between.bad_fraction,
    });
    (image, json)
}
