//! `genpath render`: one image with any method, and its statistics as JSON.

use super::args::{load_mixture, MethodArgs, SceneArgs, ShardArgs};
use super::check_output;
use super::resume::Continuation;
use super::saved_plan::{read_plan, SavedPlan};
use super::session::{rays_json, shard_path, write_stats, Session};
use anyhow::{anyhow, bail, Result};
use clap::{ArgMatches, Args};
use genpath::film::{Control, Film};
use genpath::integrators::{
    prepare, prepare_learned, Integrator, Method, RenderSettings, Settings,
};
use genpath::path::SceneView;
use genpath::shard::{Identity, Part};
use std::path::PathBuf;
use std::time::Instant;

#[derive(Args)]
pub struct RenderArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Output image; repeat for several formats. A `<FILE>.json` with statistics is written beside each.
    #[arg(short, long = "output", value_name = "FILE", required = true)]
    pub outputs: Vec<PathBuf>,
    /// Samples (paths) per pixel [default: a Mitsuba scene's `sample_count`, else 64].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1 << 24))]
    pub spp: Option<u32>,
    /// With `--method ga` or `ga-pt`: also write an SVG picture of what the GA learned over
    /// the render: its GA pixels, a stroke from each towards where its heaviest evolved
    /// generator sends paths, its anchor points and patches, with a legend.
    #[arg(long, value_name = "FILE.svg")]
    pub explain: Option<PathBuf>,
    #[command(flatten)]
    pub shard: ShardArgs,
    /// Render with the learned state in FILE (`genpath learn`, with the same scene and
    /// flags) instead of learning it: the image is the one the render that learns makes,
    /// bit for bit, and methods that learn (pg, ga, ga-pt) may then be sharded (merge the
    /// shards with the learn job's training shard, `<FILE>.shard`), resumed and
    /// checkpointed (docs/shards.md).
    #[arg(long, value_name = "FILE")]
    pub plan: Option<PathBuf>,
    #[command(flatten)]
    pub method: MethodArgs,
}

/// Refuses `--explain FILE` for a method that explains nothing, or a FILE that is not an
/// SVG in a directory that exists.
fn check_explain(explain: &std::path::Path, method: Method) -> Result<()> {
    if !method.info().explains {
        use clap::ValueEnum;
        let explaining: Vec<String> = (Method::value_variants().iter())
            .filter(|m| m.info().explains)
            .map(|m| m.name())
            .collect();
        bail!(
            "--explain is only used with --method {}",
            explaining.join(" or ")
        );
    }
    if explain.extension().and_then(|e| e.to_str()) != Some("svg") {
        bail!(
            "--explain {}: the explanation is an SVG picture (FILE.svg)",
            explain.display()
        );
    }
    super::check_dir(explain)
}

pub fn run_render(args: RenderArgs, matches: &ArgMatches) -> Result<()> {
    let method = args.method.method_or(Method::GaPt);
    for output in &args.outputs {
        check_output(output)?;
    }
    if let Some(explain) = &args.explain {
        check_explain(explain, method)?;
    }
    args.shard
        .check_method(method, args.plan.as_deref(), "render")?;
    // Settings first, before any loading.
    let mut config = args.method.settings(matches)?;
    let session = Session::open(&args.scene)?;
    let spp = args.spp.or(session.scene.render.spp).unwrap_or(64);
    // The render's one `RenderSettings`: its shard now, its control once the continuation
    // (which the settings identify) is known.
    let mut settings = session.settings(&args.scene, method, spp);
    settings.shard = args.shard.shard(spp, "--spp")?;
    load_mixture(&mut config, &session.scene, settings.max_bounces)?;
    let plain = settings.clone();
    let identity = || session.identity("render", &args.scene, &plain, vec![plain.seed], &config);
    let mut saved = match &args.plan {
        Some(path) => Some(read_plan(path, &identity()?, settings.shard)?),
        None => None,
    };
    let (part, of) = part_and_share(saved.as_ref(), &settings);
    let plan_ref = saved.as_ref().map(SavedPlan::reference);
    let identity = || {
        Ok(Identity {
            plan: plan_ref.clone(),
            ..identity()?
        })
    };
    let file = shard_path(&args.outputs[0]);
    let continuation = Continuation::new(
        &args.shard,
        (settings.method, saved.is_some()),
        (settings.shard, part),
        file,
        identity,
    )?;
    settings.control = Control {
        stop: continuation.stop.clone(),
        resume: continuation.resumed(0),
        checkpoint: continuation.checkpoint(&session, |sums| vec![sums.clone()]),
    };
    let view = SceneView::new(&session.scene, session.accel.as_ref());
    let learned = saved.as_mut().and_then(|s| s.learned.pop());
    let prepared = session.pool.install(|| match learned {
        Some(learned) => prepare_learned(&view, &config, &settings, learned),
        None => prepare(&view, &config, &settings),
    })?;
    let film = session.pool.install(|| prepared.render(&view, &settings));
    let layers = std::slice::from_ref(&film.sums);
    continuation.check_stopped(&session, layers, of, identity)?;

    let t_write = Instant::now();
    for output in &args.outputs {
        genpath::image::write(output, &film.image)?;
    }
    let explained = (args.explain.as_ref())
        .and_then(|file| Some((file, prepared.explain(&view.scene.camera, &film.image)?)));
    if let Some((file, svg)) = explained {
        let svg = svg.map_err(|e| anyhow!("{}: {e}", file.display()))?;
        genpath::image::write_bytes_atomic(file, svg.as_bytes())?;
    }
    let resume = args.shard.resume.as_deref();
    let shard = continuation.finish(&session, layers, "samples_per_pixel", film.spp, resume)?;
    let write_s = t_write.elapsed().as_secs_f64();

    let mut stats = render_stats(
        &session,
        (&settings, &config),
        prepared.as_ref(),
        &film,
        write_s,
        saved.as_ref(),
    );
    stats.insert("shard".into(), serde_json::json!(shard));
    write_stats(&args.outputs, &serde_json::Value::Object(stats))?;
    if !args.scene.quiet {
        report(
            &session,
            (&settings, &config),
            prepared.as_ref(),
            &film,
            &args.outputs,
        );
    }
    Ok(())
}

/// What of the render's samples a render with `saved` keeps in its shard file, and how
/// many samples per pixel that file holds when the render is whole: a shard with a plan
/// takes its share of the samples after the training's (the training shard has those).
fn part_and_share(saved: Option<&SavedPlan>, settings: &RenderSettings) -> (Part, u32) {
    let training = saved.map_or(0, |s| s.training_spp);
    if settings.shard.is_whole() {
        let part = match training {
            0 => Part::Samples,
            _ => Part::WithTraining,
        };
        (part, settings.spp)
    } else {
        let after = settings.spp.saturating_sub(training);
        (Part::Samples, settings.shard.samples_of(after))
    }
}

/// The JSON statistics of a render (`saved`: the plan file it rendered with).
fn render_stats(
    session: &Session,
    (settings, config): (&RenderSettings, &Settings),
    prepared: &dyn Integrator,
    film: &Film,
    write_s: f64,
    saved: Option<&SavedPlan>,
) -> serde_json::Map<String, serde_json::Value> {
    let render_s = film.elapsed.as_secs_f64();
    let description = prepared.describe(config);
    let prepare_s: f64 = description.phases.iter().map(|(_, s)| s).sum();
    let mut stats = session.stats(settings);
    stats.insert("method_settings".into(), serde_json::json!(config));
    stats.extend(description.stats);
    stats.insert(
        "plan_file".into(),
        serde_json::json!(saved.map(|s| s.json())),
    );
    let mut times = serde_json::json!({
        "load": session.load_s,
        "accel_build": session.accel_s,
        "render": render_s,
        "write": write_s,
        "total_render": prepare_s + render_s,
    });
    for (phase, seconds) in description.phases {
        times[phase] = serde_json::json!(seconds);
    }
    stats.insert("times_s".into(), times);
    stats.insert("rays".into(), rays_json(film.rays));
    stats.insert(
        "rays_per_s".into(),
        serde_json::json!(film.rays.total() as f64 / render_s.max(1e-9)),
    );
    stats
}

/// What a render tells on stderr.
fn report(
    session: &Session,
    (settings, config): (&RenderSettings, &Settings),
    prepared: &dyn Integrator,
    film: &Film,
    outputs: &[PathBuf],
) {
    let render_s = film.elapsed.as_secs_f64();
    for line in prepared.describe(config).lines {
        eprintln!("{line}");
    }
    let shard = if settings.shard.is_whole() {
        String::new()
    } else {
        format!(" (shard {}: {} of them)", settings.shard, film.spp)
    };
    eprintln!(
        "genpath: {}×{} {} spp{shard} in {render_s:.2} s ({:.2} Mrays/s) → {}",
        session.scene.camera.width,
        session.scene.camera.height,
        settings.spp,
        film.rays.total() as f64 / render_s.max(1e-9) / 1e6,
        outputs
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(", ")
    );
}
