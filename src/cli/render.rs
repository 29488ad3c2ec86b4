//! `genpath render`: one image with any method, and its statistics as JSON.

use super::args::{load_mixture, MethodArgs, SceneArgs, ShardArgs};
use super::check_output;
use super::learn::{read_plan, SavedPlan};
use super::resume::Continuation;
use super::session::{rays_json, shard_path, write_stats, Session};
use anyhow::{anyhow, bail, Result};
use clap::{ArgMatches, Args};
use genpath::film::{Control, Film};
use genpath::genetic::plan::{Plan, PlanConfig};
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

/// Refuses `--explain FILE` for a method without a GA plan, or a FILE that is not an SVG
/// in a directory that exists.
fn check_explain(explain: &std::path::Path, method: Method) -> Result<()> {
    if !matches!(method, Method::Ga | Method::GaPt) {
        bail!("--explain is only used with --method ga or ga-pt");
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
    let settings = RenderSettings {
        shard: args.shard.shard(spp, "--spp")?,
        ..session.settings(&args.scene, method, spp)
    };
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
    let control = Control {
        stop: continuation.stop.clone(),
        resume: continuation.resumed(0),
        checkpoint: continuation.checkpoint(&session, |sums| vec![sums.clone()]),
    };
    let settings = RenderSettings {
        control,
        ..settings
    };
    let view = SceneView::new(&session.scene, session.accel.as_ref());
    let learned = saved.as_mut().and_then(|s| s.learned.pop());
    let prepared = session.pool.install(|| match learned {
        Some(learned) => prepare_learned(&view, &config, &settings, learned),
        None => prepare(&view, &config, &settings),
    })?;
    let plan = prepared.plan();
    let film = session.pool.install(|| prepared.render(&view, &settings));
    let layers = std::slice::from_ref(&film.sums);
    continuation.check_stopped(&session, layers, of, identity)?;

    let t_write = Instant::now();
    for output in &args.outputs {
        genpath::image::write(output, &film.image)?;
    }
    if let (Some(file), Some(plan)) = (&args.explain, plan) {
        let camera = &view.scene.camera;
        let svg = genpath::genetic::explain::svg(camera, &film.image, plan)
            .map_err(|e| anyhow!("{}: {e}", file.display()))?;
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
        report(&session, &settings, prepared.as_ref(), &film, &args.outputs);
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
    let plan = prepared.plan();
    let render_s = film.elapsed.as_secs_f64();
    let plan_s = plan.map_or(0.0, |p| p.elapsed().as_secs_f64());
    let spatial_s = prepared.spatial().map_or(0.0, |s| s.stats.seconds);
    let mut stats = session.stats(settings);
    stats.insert("method_settings".into(), serde_json::json!(config));
    stats.insert("mixture".into(), serde_json::json!(prepared.mixture()));
    let plan_file = saved.map(|s| s.json());
    stats.insert(
        "ga".into(),
        serde_json::json!(plan.map(|p| ga_stats(p, config, plan_file.is_some()))),
    );
    stats.insert("plan_file".into(), serde_json::json!(plan_file));
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
    stats
}

/// What a render tells on stderr.
fn report(
    session: &Session,
    settings: &RenderSettings,
    prepared: &dyn Integrator,
    film: &Film,
    outputs: &[PathBuf],
) {
    let render_s = film.elapsed.as_secs_f64();
    if let Some(plan) = prepared.plan() {
        let improved = plan.pixels.iter().filter(|p| !p.kept_srt).count();
        eprintln!(
            "genpath: GA on {} pixels ({improved} improved on srt) in {:.2} s",
            plan.pixels.len(),
            plan.elapsed().as_secs_f64()
        );
    }
    if let Some(s) = prepared.spatial() {
        eprintln!(
            "genpath: spatial guide: {} of {} regions trained on {} records from {} passes ({} spp of the image) in {:.2} s",
            s.stats.trained_cells, s.stats.cells, s.stats.records, s.stats.passes, s.stats.spp, s.stats.seconds
        );
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

/// What the GA plan and the renderer left out for this scene, and why (design §8).
fn left_out(
    plan: &Plan,
    config: &PlanConfig,
    analysis: &genpath::scene::SceneAnalysis,
) -> Vec<String> {
    let mut out = Vec::new();
    if analysis.glossy_triangles == 0 {
        out.push("glossy-lobe (Phong, microfacet) evaluation and sampling: no glossy material (the BRDF code runs only the lobes a material has)".to_string());
    }
    if analysis.mirror_triangles == 0 {
        out.push("delta vertices: no mirror, conductor or dielectric material".to_string());
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
            "the baseline and the GA at {} grid pixels: the gate's pilot predicted no gain (its gains over pt: geometric mean {:.2})",
            s.gated_pixels, s.pilot_gain
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
/// pixel's evolved mixture, and the fitness curves of a few pixels spread over the list;
/// of a plan read from a plan file (`from_file`), a summary without the pixels and curves
/// (the file has them).
fn ga_stats(plan: &Plan, settings: &Settings, from_file: bool) -> serde_json::Value {
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
    let (curves, pixels) = if from_file {
        let there = serde_json::json!("in the plan file (see plan_file)");
        (there.clone(), there)
    } else {
        (serde_json::json!(curves), serde_json::json!(pixels))
    };
    serde_json::json!({
        "config": settings.ga,
        "plan": settings.plan,
        "gate": settings.gate,
        "left_out": left_out(plan, &settings.plan, &analysis),
        "scene_analysis": analysis,
        "stats": plan.stats,
        "ga_pixels": n,
        "improved_pixels": plan.pixels.iter().filter(|p| !p.kept_srt).count(),
        "individual_evaluations_per_cpu_s": plan.stats.individual_evaluations as f64 / evolve_s,
        "fitness_curves": curves,
        "pixels": pixels,
    })
}
