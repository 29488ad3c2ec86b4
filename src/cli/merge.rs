//! `genpath merge`: the image of shards of one render, from their summed per-pixel sums.

use super::check_output;
use super::reference::average_halves;
use super::session::write_stats;
use anyhow::{bail, Result};
use clap::Args;
use genpath::shard::merge::{merge, Coverage, Merged};
use std::path::PathBuf;

#[derive(Args)]
pub struct MergeArgs {
    /// Shard files (`<image>.shard`, written by `render --shard` or `reference --shard`) of
    /// one render: all of its shards, or any of them for an image with fewer samples. A
    /// render with `--plan` whose training took samples (pg, ga-pt) also needs the learn
    /// job's training shard, `<plan>.shard`. Or the parts of one sweep (`PREFIX.csv`,
    /// written by `sweep --shard`), merged into one `-o PREFIX`.
    #[arg(required = true, value_name = "SHARD")]
    pub shards: Vec<PathBuf>,
    /// Output image; repeat for several formats (a reference's must be EXR). A
    /// `<FILE>.json` with what was merged is written beside each.
    #[arg(short, long = "output", value_name = "FILE", required = true)]
    pub outputs: Vec<PathBuf>,
    /// Fail, writing nothing, when shards (or the training shard) are missing.
    #[arg(long)]
    pub complete: bool,
    /// No report on stderr.
    #[arg(short, long)]
    pub quiet: bool,
}

pub fn run_merge(args: MergeArgs) -> Result<()> {
    let is_csv = |p: &PathBuf| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("csv"));
    if args.shards.iter().any(is_csv) {
        if !args.shards.iter().all(is_csv) {
            bail!("shards of a render (.shard) and parts of a sweep (.csv) do not merge together");
        }
        let [prefix] = &args.outputs[..] else {
            bail!("parts of a sweep merge into one -o PREFIX (PREFIX.csv and PREFIX.svg)");
        };
        return super::sweep::merge_parts(&args.shards, prefix, args.complete, args.quiet);
    }
    for output in &args.outputs {
        check_output(output)?;
    }
    let merged = merge(&args.shards)?;
    let id = merged.identity();
    let reference = id.command == "reference";
    if let Some(png) = args
        .outputs
        .iter()
        .find(|o| reference && !o.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr")))
    {
        bail!(
            "{}: these are shards of a reference, which must be an EXR (float) image",
            png.display()
        );
    }
    let missing = missing_text(&merged);
    if let (true, Some(missing)) = (args.complete, &missing) {
        bail!("--complete: {missing}");
    }
    let spp = held(&merged);
    let (width, height) = (id.width, id.height);
    let (image, reference_json) = if reference {
        let [a, b] = [0, 1].map(|i| merged.layers[i].image(width, height));
        let seeds = [id.layer_seeds[0], id.layer_seeds[1]];
        let (image, json) = average_halves(&a, &b, seeds, spp);
        (image, Some(json))
    } else {
        (merged.layers[0].image(width, height), None)
    };
    for output in &args.outputs {
        genpath::image::write(output, &image)?;
    }
    let stats = serde_json::json!({
        "genpath_version": env!("CARGO_PKG_VERSION"),
        "command_line": std::env::args().collect::<Vec<_>>(),
        "scene": merged.header.scene_path,
        "width": width,
        "height": height,
        "identity": id,
        "merged": {
            "shards": merged.shards.iter().map(|(file, shard)| {
                serde_json::json!({ "file": file, "shard": shard.to_string() })
            }).collect::<Vec<_>>(),
            "training": merged.training,
            "coverage": merged.coverage,
            "samples_per_pixel": spp,
            "of": id.spp,
            "summation": "per pixel, each shard's sum in increasing sample index, then the training shard's sums (if any), then the shards' sums in increasing (N, K)",
        },
        "reference": reference_json,
    });
    write_stats(&args.outputs, &stats)?;
    if !args.quiet {
        if let Some(missing) = &missing {
            eprintln!("genpath: warning: {missing}");
        }
        let halves = if reference { " per half" } else { "" };
        let training = if merged.training.is_some() {
            " and the training shard"
        } else {
            ""
        };
        eprintln!(
            "genpath: merged {} shards{training}: {spp} of {} spp{halves} → {}",
            merged.shards.len(),
            id.spp,
            args.outputs
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    Ok(())
}

/// Samples per pixel (of each layer) the merged shards hold: the fewest of any pixel.
fn held(merged: &Merged) -> u32 {
    merged
        .layers
        .iter()
        .flat_map(|l| l.counts.iter().copied())
        .min()
        .unwrap_or(0)
}

/// What is missing, if anything, in words.
fn missing_text(merged: &Merged) -> Option<String> {
    match &merged.coverage {
        Coverage::Complete => None,
        Coverage::Missing { n, missing, first } => {
            let listed = first
                .iter()
                .map(|k| format!("{k}/{n}"))
                .collect::<Vec<_>>()
                .join(", ");
            let more = if (*missing as usize) > first.len() {
                ", …"
            } else {
                ""
            };
            Some(format!(
                "{missing} of {n} shards missing ({listed}{more}): the image has {} of {} samples per pixel",
                held(merged),
                merged.identity().spp
            ))
        }
        Coverage::Partial { spp, of } => Some(format!(
            "the shards hold {spp} of the render's {of} samples per pixel"
        )),
        Coverage::NoTraining { training, spp, of } => Some(format!(
            "the learn job's training shard (`<plan>.shard`, with {training} training samples \
             per pixel) is missing: the image has {spp} of {of} samples per pixel"
        )),
    }
}
