//! `genpath check`: the numerical invariants on a scene at a small size.

use super::args::SceneArgs;
use super::check_dir;
use super::session::Session;
use anyhow::{bail, Result};
use clap::Args;
use genpath::path::SceneView;
use std::path::PathBuf;

#[derive(Args)]
pub struct CheckArgs {
    /// The scene is rendered 32 pixels wide (aspect kept) unless --width/--height are given.
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Samples per pixel of each method's render.
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(2..=1 << 20))]
    pub spp: u32,
    /// Also write the report as JSON to FILE.
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
}

pub fn run_check(mut args: CheckArgs) -> Result<()> {
    if let Some(json) = &args.json {
        check_dir(json)?;
    }
    if args.scene.width.is_none() && args.scene.height.is_none() {
        args.scene.width = Some(32);
    }
    let session = Session::open(&args.scene)?;
    let max_bounces = args
        .scene
        .max_bounces
        .unwrap_or(session.scene.render.max_bounces);
    let config = genpath::check::CheckConfig::new(args.spp, max_bounces, args.scene.seed);
    let view = SceneView::new(&session.scene, session.accel.as_ref());
    let report = session
        .pool
        .install(|| genpath::check::check(&view, &config))?;
    println!(
        "{}: {}×{}, {} spp, max bounces {max_bounces}",
        session.scene.path.display(),
        session.scene.camera.width,
        session.scene.camera.height,
        args.spp
    );
    println!("| method | bad pixels | mean (R, G, B) | |z| vs pt | seconds |");
    println!("|---|---|---|---|---|");
    for m in &report.methods {
        println!(
            "| {} | {} | {:.4e}, {:.4e}, {:.4e} | {:.2} | {:.2} |",
            m.method, m.bad_pixels, m.mean[0], m.mean[1], m.mean[2], m.z_vs_pt, m.seconds
        );
    }
    println!(
        "densities: {} sampled, min {:.3e}, max {:.3e}, {} not finite and positive",
        report.pdf_samples, report.pdf_min, report.pdf_max, report.pdf_bad
    );
    println!(
        "fitness: {} values, {} not finite; critical |z| {:.2}",
        report.fitness_values, report.fitness_bad, report.z_critical
    );
    if let Some(json) = &args.json {
        genpath::image::write_bytes_atomic(
            json,
            serde_json::to_string_pretty(&report)?.as_bytes(),
        )?;
    }
    if !report.passed() {
        bail!("check failed:\n  {}", report.failures.join("\n  "));
    }
    println!("check passed");
    Ok(())
}
