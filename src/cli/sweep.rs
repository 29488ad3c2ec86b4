//! `genpath sweep`: error against samples or time for several methods.

use super::args::{load_mixture, SceneArgs, SettingsArgs};
use super::check_dir;
use super::session::Session;
use anyhow::{bail, Result};
use clap::{ArgMatches, Args};
use genpath::integrators::Method;
use genpath::path::SceneView;
use std::path::PathBuf;

#[derive(Args)]
pub struct SweepArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// The reference (EXR), e.g. from `genpath reference`, of the size rendered.
    #[arg(long = "ref", value_name = "REF.exr")]
    pub reference: PathBuf,
    /// Methods, comma-separated: pt, srt, mixture (with --generators), ga, ga-pt, pg, or
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
    #[command(flatten)]
    pub settings: SettingsArgs,
}

pub fn run_sweep(args: SweepArgs, matches: &ArgMatches) -> Result<()> {
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
