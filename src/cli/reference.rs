//! `genpath reference`: a long render in two independent halves, with its own noise estimate.

use super::args::{load_mixture, MethodArgs, SceneArgs, ShardArgs};
use super::check_output;
use super::resume::Continuation;
use super::session::{rays_json, shard_path, write_stats, Session};
use anyhow::{bail, Result};
use clap::{ArgMatches, Args};
use genpath::image::Image;
use genpath::integrators::{prepare, Control, Film, LayerSums, RenderSettings};
use genpath::path::SceneView;
use genpath::sampling::{derive_seed, Stream};
use genpath::shard::Part;
use std::path::PathBuf;

#[derive(Args)]
pub struct ReferenceArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// The reference image (EXR); `<FILE>.json` beside it holds its noise estimate.
    #[arg(short, long = "output", value_name = "FILE")]
    pub output: PathBuf,
    /// Samples per pixel, split into two independent halves.
    #[arg(long, default_value_t = 4096, value_parser = clap::value_parser!(u32).range(2..=1 << 24))]
    pub spp: u32,
    /// The method (default `pt`) and its settings: each half prepares it anew, from its own
    /// seed.
    #[command(flatten)]
    pub shard: ShardArgs,
    #[command(flatten)]
    pub method: MethodArgs,
}

/// Two independent halves, averaged; their relMSE against each other is about four times
/// the average's own relMSE (each half has twice its variance, and both count).
pub fn run_reference(args: ReferenceArgs, matches: &ArgMatches) -> Result<()> {
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
    let method = args.method.method_or(genpath::integrators::Method::Pt);
    args.shard.check_method(method, false)?;
    // Settings first, before any loading.
    let mut config = args.method.settings(matches)?;
    let session = Session::open(&args.scene)?;
    let max_bounces = session.settings(&args.scene, method, 1).max_bounces;
    load_mixture(&mut config, &session.scene, max_bounces)?;
    let view = SceneView::new(&session.scene, session.accel.as_ref());
    let shard = args.shard.shard(args.spp / 2, "half of --spp, per half")?;
    // The halves use seeds derived from the given one, so neither shares random numbers with
    // a render made with the same `--seed` (that would correlate its error with the
    // reference's and understate it).
    let seeds = [Stream::ReferenceFirst, Stream::ReferenceSecond]
        .map(|stream| derive_seed(args.scene.seed, stream.tag()));
    let identity = || {
        let settings = session.settings(&args.scene, method, args.spp / 2);
        session.identity("reference", &args.scene, &settings, seeds.to_vec(), &config)
    };
    let file = shard_path(&args.output);
    let what = ((method, false), (shard, Part::Samples));
    let continuation = Continuation::new(&args.shard, what.0, what.1, file, identity)?;
    let pixels = (session.scene.camera.width * session.scene.camera.height) as usize;
    // Half `i`, resumed from its layer of `--resume`, its checkpoints holding `other` as the
    // other half's layer.
    let half = |i: usize, other: LayerSums| -> Result<Film> {
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
                learning: None,
            },
            ..session.settings(&args.scene, method, args.spp / 2)
        };
        session.pool.install(|| {
            let integrator = prepare(&view, &config, &settings)?;
            Ok(integrator.render(&view, &settings))
        })
    };
    let second_resumed = || {
        continuation
            .resumed(1)
            .map_or_else(|| LayerSums::zero(pixels), |l| l.as_ref().clone())
    };
    let a = half(0, second_resumed())?;
    let b = match continuation.stop.requested() {
        None => Some(half(1, a.sums.clone())?),
        Some(_) => None,
    };
    let second = b.as_ref().map_or_else(second_resumed, |b| b.sums.clone());
    let layers = [a.sums.clone(), second];
    let of = shard.samples_of(args.spp / 2);
    continuation.check_stopped(&session, &layers, of, identity)?;
    let Some(b) = b else {
        unreachable!("the second half ran, since no signal stopped the first");
    };
    let (image, reference) = average_halves(&a.image, &b.image, seeds, args.spp / 2);
    genpath::image::write(&args.output, &image)?;
    let resume = args.shard.resume.as_deref();
    let spp_key = "samples_per_pixel_per_half";
    let shard_json = continuation.finish(&session, &layers, spp_key, a.spp, resume)?;
    let settings = session.settings(&args.scene, method, args.spp / 2 * 2);
    let seconds = a.elapsed.as_secs_f64() + b.elapsed.as_secs_f64();
    let mut stats = session.stats(&settings);
    let estimate = reference["relmse_estimate"].as_f64().unwrap_or(f64::NAN);
    stats.insert("reference".into(), reference);
    stats.insert("shard".into(), serde_json::json!(shard_json));
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
