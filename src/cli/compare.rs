//! `genpath compare`: an image against a reference.

use anyhow::{bail, Result};
use clap::Args;
use std::path::PathBuf;

#[derive(Args)]
pub struct CompareArgs {
    /// The image to judge (EXR).
    pub image: PathBuf,
    /// The reference (EXR).
    pub reference: PathBuf,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
    /// Also compare every channel bit for bit; exits with status 1 if any differs.
    #[arg(long)]
    pub bits: bool,
}

pub fn run_compare(args: CompareArgs) -> Result<()> {
    let image = genpath::image::read_exr(&args.image)?;
    let reference = genpath::image::read_exr(&args.reference)?;
    let Some(m) = genpath::image::metrics::compare(&image, &reference) else {
        bail!(
            "{} is {}×{} but the reference {} is {}×{}",
            args.image.display(),
            image.width,
            image.height,
            args.reference.display(),
            reference.width,
            reference.height
        );
    };
    let differing = image
        .pixels
        .iter()
        .zip(&reference.pixels)
        .filter(|(a, b)| a.map(f32::to_bits) != b.map(f32::to_bits))
        .count();
    if args.json {
        println!("{}", serde_json::to_string_pretty(&m)?);
    } else {
        println!(
            "relMSE {:.6e}  MSE {:.6e}  MAPE {:.6e}  bad pixels {:.4}%",
            m.relmse,
            m.mse,
            m.mape,
            100.0 * m.bad_fraction
        );
    }
    if args.bits {
        if differing > 0 {
            bail!(
                "{differing} of {} pixels differ in their bits",
                image.pixels.len()
            );
        }
        println!("bit-identical: all {} pixels", image.pixels.len());
    }
    Ok(())
}
