//! `genpath sweep`: error against samples or time for several methods.

use super::args::{load_mixture, SceneArgs, SettingsArgs};
use super::check_dir;
use super::session::Session;
use anyhow::{anyhow, bail, Context, Result};
use clap::{ArgMatches, Args};
use genpath::film::Shard;
use genpath::integrators::Method;
use genpath::path::SceneView;
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct SweepArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// The reference (EXR), e.g. from `genpath reference`, of the size rendered.
    #[arg(long = "ref", value_name = "REF.exr")]
    pub reference: PathBuf,
    /// Methods, comma-separated: pt, srt, mixture (with --generators), ga, ga-pt, pg, lt, or
    /// ga:key=value:… (ga-pt:…, pg:sp=N) with keys m, l, pop, gen, s, e, grid, extra,
    /// neighbours, cw, gate, warm, da, pa, gs, spatial, sp (e.g. ga:m=10000:grid=32,
    /// ga-pt:gate=0, ga-pt:spatial=1; an unknown key lists them).
    #[arg(long, value_delimiter = ',', default_value = "pt,srt,ga")]
    pub methods: Vec<String>,
    /// Budgets, comma-separated: samples per pixel, or seconds per image with --time.
    #[arg(long, value_delimiter = ',', default_value = "4,16,64,256")]
    pub budgets: Vec<f64>,
    /// Budgets are wall-clock seconds per image, every phase included.
    #[arg(long)]
    pub time: bool,
    /// Repetitions of every render, with seeds seed, seed + 1, …
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=10_000))]
    pub reps: u32,
    /// Writes PREFIX.csv and PREFIX.svg.
    #[arg(short, long = "output", value_name = "PREFIX")]
    pub output: PathBuf,
    /// Run part K of N of the sweep: of its runs (every method at one budget of one
    /// repetition), run j = repetition × budgets + budget index when j mod N = K; writes
    /// PREFIX.csv with those rows and PREFIX.csv.json with what the sweep is, for
    /// `genpath merge PARTS.csv -o PREFIX` (docs/shards.md).
    #[arg(long, value_name = "K/N")]
    pub shard: Option<Shard>,
    /// Also writes a comparison picture (SVG) of the last budget's renders of the first
    /// repetition: each method's render and its per-pixel error against the reference, with
    /// its seconds, samples and relMSE and its ratio to the first method's, and the
    /// reference; and prints each method's relMSE over the first's at that budget.
    #[arg(long, value_name = "FILE.svg")]
    pub picture: Option<PathBuf>,
    #[command(flatten)]
    pub settings: SettingsArgs,
}

pub fn run_sweep(args: SweepArgs, matches: &ArgMatches) -> Result<()> {
    use genpath::report::{MethodSpec, Sweep};
    let with_ext = |ext: &str| {
        let mut p = args.output.clone().into_os_string();
        p.push(ext);
        PathBuf::from(p)
    };
    let (csv_path, svg_path) = (with_ext(".csv"), with_ext(".svg"));
    for p in [&csv_path, &svg_path].into_iter().chain(&args.picture) {
        check_dir(p)?;
    }
    check_picture(&args, &csv_path, &svg_path)?;
    let budgets = parse_budgets(&args)?;
    let mut base = args.settings.settings(matches)?;
    let reference = genpath::image::read_exr(&args.reference)?;
    let session = Session::open(&args.scene)?;
    let settings = session.settings(&args.scene, Method::Pt, 1);
    load_mixture(&mut base, &session.scene, settings.max_bounces)?;
    let methods = args
        .methods
        .iter()
        .map(|m| MethodSpec::parse(m.trim(), &base).map_err(|e| anyhow::anyhow!("--methods: {e}")))
        .collect::<Result<Vec<_>>>()?;
    if methods.iter().any(|m| m.method == Method::Mixture) && base.loaded_mixture.is_none() {
        bail!("--methods mixture needs --generators FILE");
    }
    let scene_name = args
        .scene
        .scene
        .parent()
        .and_then(|d| d.file_name())
        .map_or_else(|| "scene".to_string(), |n| n.to_string_lossy().into_owned());
    let runs = args.reps as usize * args.budgets.len();
    let part = args.shard.unwrap_or(Shard::WHOLE);
    if part.count as usize > runs {
        bail!(
            "--shard {part}: the sweep has {runs} runs (repetitions × budgets), fewer than {} parts",
            part.count
        );
    }
    let sweep = Sweep {
        scene_name: scene_name.clone(),
        reference: &reference,
        methods,
        budgets,
        reps: args.reps,
        settings,
        progress: !args.scene.quiet,
        part,
    };
    let title = format!(
        "{scene_name}: relMSE against time ({}×{}, max bounces {})",
        session.scene.camera.width, session.scene.camera.height, sweep.settings.max_bounces
    );
    if let Some(part) = args.shard {
        let id = identity(&args, &session, &sweep, &base)?;
        let json = serde_json::json!({ "part": part.to_string(), "title": title, "sweep": id });
        let text = serde_json::to_string_pretty(&json)?;
        genpath::image::write_bytes_atomic(&with_ext(".csv.json"), text.as_bytes())?;
    }
    let view = SceneView::new(&session.scene, session.accel.as_ref());
    let quiet = args.scene.quiet;
    // The renders the picture shows: the last budget's, of the first repetition.
    let shown = |r: &genpath::report::Row| {
        r.seed == sweep.settings.seed && Some(&r.budget) == args.budgets.last()
    };
    let mut pictured = Vec::new();
    let rows = session.pool.install(|| {
        sweep.run(&view, |r, image| {
            report_row(r, quiet);
            if args.picture.is_some() && shown(r) {
                pictured.push((r.clone(), image.clone()));
            }
        })
    })?;
    if let (Some(path), Some(budget)) = (&args.picture, args.budgets.last()) {
        let at = if args.time {
            format!("equal time, {budget} s each, every phase counted")
        } else {
            format!("{budget} samples per pixel")
        };
        let camera = &session.scene.camera;
        let title = format!(
            "{scene_name} at {at} ({}×{}, max bounces {})",
            camera.width, camera.height, sweep.settings.max_bounces
        );
        write_picture(path, &title, &pictured, &reference)?;
    }
    write_sweep(&args.output, &title, &rows, args.time)
}

/// Refuses a `--picture` where the sweep writes its table or plot, or with `--shard`.
fn check_picture(args: &SweepArgs, csv_path: &Path, svg_path: &Path) -> Result<()> {
    if args
        .picture
        .as_ref()
        .is_some_and(|p| p == svg_path || p == csv_path)
    {
        bail!(
            "--picture {}: that is where the sweep writes its plot or table (-o {})",
            svg_path.display(),
            args.output.display()
        );
    }
    if let (Some(_), Some(part)) = (&args.picture, args.shard) {
        bail!("--picture with --shard {part}: a part of a sweep may not hold the renders it shows");
    }
    Ok(())
}

/// The sweep's budgets: seconds with --time, else samples per pixel.
fn parse_budgets(args: &SweepArgs) -> Result<genpath::report::Budgets> {
    use genpath::report::Budgets;
    Ok(if args.time {
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
    })
}

/// Writes the comparison picture of `pictured` (rows and their images) against
/// `reference`, and prints each method's relMSE over the first's at equal time.
fn write_picture(
    path: &Path,
    title: &str,
    pictured: &[(genpath::report::Row, genpath::image::Image)],
    reference: &genpath::image::Image,
) -> Result<()> {
    use genpath::report::picture::{svg, Panel};
    let panels: Vec<Panel> = pictured
        .iter()
        .map(|(row, image)| Panel { row, image })
        .collect();
    let svg = svg(title, &panels, reference).map_err(|e| anyhow!("{}: {e}", path.display()))?;
    genpath::image::write_bytes_atomic(path, svg.as_bytes())?;
    if let Some(((first, _), rest)) = pictured.split_first() {
        for (r, _) in rest {
            println!(
                "{}: relMSE {:.3e} in {:.2} s against {}'s {:.3e} in {:.2} s: {:.2} × {}'s at equal time",
                r.method,
                r.relmse,
                r.seconds,
                first.method,
                first.relmse,
                first.seconds,
                (r.relmse * r.seconds) / (first.relmse * first.seconds),
                first.method
            );
        }
    }
    Ok(())
}

/// Writes PREFIX.csv and PREFIX.svg of `rows` (and PREFIX-ablations.svg where some are
/// ablations), and prints their summary.
fn write_sweep(
    prefix: &Path,
    title: &str,
    rows: &[genpath::report::Row],
    time: bool,
) -> Result<()> {
    use genpath::report;
    let with_ext = |ext: &str| {
        let mut p = prefix.as_os_str().to_owned();
        p.push(ext);
        PathBuf::from(p)
    };
    genpath::image::write_bytes_atomic(&with_ext(".csv"), report::csv(rows).as_bytes())?;
    let svg = report::plot::svg(title, rows, false, time).map_err(|e| anyhow::anyhow!(e))?;
    genpath::image::write_bytes_atomic(&with_ext(".svg"), svg.as_bytes())?;
    if rows.iter().any(|r| report::plot::is_ablation(&r.method)) {
        let title = format!("{title}: ablations");
        let svg = report::plot::svg(&title, rows, true, time).map_err(|e| anyhow::anyhow!(e))?;
        genpath::image::write_bytes_atomic(&with_ext("-ablations.svg"), svg.as_bytes())?;
    }
    println!("{}", report::summary(rows));
    Ok(())
}

/// What makes parts of one sweep: the build, the scene and reference files, the size, the
/// back-end, and every setting of the sweep but its part.
fn identity(
    args: &SweepArgs,
    session: &Session,
    sweep: &genpath::report::Sweep,
    base: &genpath::integrators::Settings,
) -> Result<serde_json::Value> {
    use genpath::shard::{build_hash, hash_files};
    let hex = |h: u64| format!("{h:016x}");
    Ok(serde_json::json!({
        "genpath_version": env!("CARGO_PKG_VERSION"),
        "build": hex(build_hash()?),
        "scene": hex(hash_files(&session.scene.files, &args.scene.define)?),
        "reference": hex(hash_files(std::slice::from_ref(&args.reference), &[])?),
        "width": session.scene.camera.width,
        "height": session.scene.camera.height,
        "accel": session.accel.kernels(),
        "max_bounces": sweep.settings.max_bounces,
        "seed": sweep.settings.seed,
        "methods": sweep.methods.iter().map(|m| m.label.clone()).collect::<Vec<_>>(),
        "budgets": args.budgets,
        "time": args.time,
        "reps": args.reps,
        "settings": base,
    }))
}

/// A finished render of the sweep on stderr, unless `quiet`; a warning, even when quiet,
/// where some of its pixels are bad (its relMSE then does not compare with the others').
fn report_row(r: &genpath::report::Row, quiet: bool) {
    if !quiet {
        eprintln!(
            "genpath: {:<24} {:>6} spp {:>8.2} s (GA {:>6.2} s)  relMSE {:.4e}",
            r.method, r.spp, r.seconds, r.ga_seconds, r.relmse
        );
    }
    if r.bad_fraction > 0.0 {
        eprintln!(
            "genpath: warning: {} (seed {}, budget {}): {:.3} % of the pixels are NaN, \
             infinite or negative; relMSE leaves them out (the CSV's bad_fraction)",
            r.method,
            r.seed,
            r.budget,
            100.0 * r.bad_fraction
        );
    }
}

/// One part of a sweep as its files hold it.
struct Part {
    csv: PathBuf,
    part: Shard,
    title: String,
    sweep: serde_json::Value,
    rows: Vec<genpath::report::Row>,
}

fn read_part(csv: &Path) -> Result<Part> {
    let text = std::fs::read_to_string(csv).with_context(|| csv.display().to_string())?;
    let rows = genpath::report::parse_csv(&text).map_err(|e| anyhow!("{}: {e}", csv.display()))?;
    let json_path = super::session::beside(csv, ".json");
    let json: serde_json::Value = std::fs::read_to_string(&json_path)
        .map_err(|e| {
            anyhow!(
                "{}: {e}: a part of a sweep has its description there (sweep --shard writes it)",
                json_path.display()
            )
        })
        .and_then(|t| {
            serde_json::from_str(&t).map_err(|e| anyhow!("{}: {e}", json_path.display()))
        })?;
    let field = |k: &str| {
        json.get(k)
            .cloned()
            .ok_or_else(|| anyhow!("{}: no `{k}`", json_path.display()))
    };
    let part: Shard = field("part")?
        .as_str()
        .unwrap_or_default()
        .parse()
        .map_err(|e| anyhow!("{}: part: {e}", json_path.display()))?;
    let title = field("title")?.as_str().unwrap_or_default().to_string();
    Ok(Part {
        csv: csv.to_path_buf(),
        part,
        title,
        sweep: field("sweep")?,
        rows,
    })
}

/// `genpath merge PARTS.csv -o PREFIX`: the parts of one sweep (`sweep --shard K/N`) as the
/// sweep's CSV, plot and summary, their rows in the order one sweep writes them.
pub fn merge_parts(parts: &[PathBuf], prefix: &Path, complete: bool, quiet: bool) -> Result<()> {
    let parts = parts
        .iter()
        .map(|p| read_part(p))
        .collect::<Result<Vec<_>>>()?;
    let first = &parts[0];
    for p in &parts[1..] {
        if let Some((what, a, b)) =
            genpath::shard::first_difference(&first.sweep, &p.sweep, String::new())
        {
            bail!("{} and {} are not parts of one sweep: {what} differs ({a} in the first, {b} in the second)", first.csv.display(), p.csv.display());
        }
        if p.part.count != first.part.count {
            bail!(
                "{} is part {} and {} part {}: parts of one split have the same N",
                first.csv.display(),
                first.part,
                p.csv.display(),
                p.part
            );
        }
    }
    let n = first.part.count;
    let mut seen = vec![None::<&Path>; n as usize];
    for p in &parts {
        if let Some(other) = seen[p.part.index as usize].replace(&p.csv) {
            bail!(
                "{} and {} are both part {}",
                other.display(),
                p.csv.display(),
                p.part
            );
        }
    }
    let missing: Vec<String> = (0..n)
        .filter(|&k| seen[k as usize].is_none())
        .map(|k| format!("{k}/{n}"))
        .collect();
    if !missing.is_empty() {
        let text = format!(
            "{} of {n} parts missing ({})",
            missing.len(),
            missing.join(", ")
        );
        if complete {
            bail!("--complete: {text}");
        }
        if !quiet {
            eprintln!("genpath: warning: {text}");
        }
    }
    let list = |k: &str| first.sweep[k].as_array().cloned().unwrap_or_default();
    let (methods, budgets) = (list("methods"), list("budgets"));
    let seed0 = first.sweep["seed"].as_u64().unwrap_or(0);
    let mut rows: Vec<_> = parts.iter().flat_map(|p| p.rows.iter().cloned()).collect();
    let key = |r: &genpath::report::Row| {
        let b = budgets.iter().position(|v| v.as_f64() == Some(r.budget));
        let m = methods
            .iter()
            .position(|v| v.as_str() == Some(r.method.as_str()));
        (r.seed.wrapping_sub(seed0), b, m)
    };
    rows.sort_by_key(key);
    let time = first.sweep["time"].as_bool().unwrap_or(false);
    write_sweep(prefix, &first.title, &rows, time)
}
