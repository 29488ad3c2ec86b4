//! `pixel-constant` (feature `testing`, for the test suite): path tracing that learns one
//! number per pixel and renders with it. A training pass of `pt` (its samples stay in the
//! image) gives each pixel's mean luminance; each pixel's samples then trace their path
//! with a probability that grows with it (Russian roulette at the camera, the survivors
//! weighted by its inverse), so the image stays unbiased and depends on what was learned.
//! It exists to show that a method that learns is one file and one line, and that `learn`,
//! `render --plan`, shards and `--explain` work on it as on the GA's methods.

use super::pt::PathTracing;
use super::{
    Context, Description, ExplainError, Integrator, Learned, Method, MethodInfo, PixelIntegrator,
    PrepareError, Settings,
};
use crate::accel::Ray;
use crate::film::{self, Control, Pass, PixelEstimator, PixelSums, Shard, Splats};
use crate::image::Image;
use crate::path::{RayCounts, SceneView};
use crate::sampling::{derive_seed, uniform, Rng};
use crate::scene::Camera;
use glam::DVec3;
use std::time::Instant;

/// `pixel-constant` learns (in one job) and explains what it learned.
pub const METHOD: MethodInfo = MethodInfo {
    prepare_learned: Some(prepare_learned),
    explains: true,
    ..MethodInfo::plain(prepare)
};

/// Samples per pixel of the training pass, at most (and at most half of `--spp`).
const TRAINING_SPP: u32 = 4;
/// The training pass's family of random streams.
const TRAINING_STREAMS: u64 = 0x7069_7865_6c63;
/// The least probability that a pixel's sample traces its path.
const MIN_SURVIVAL: f32 = 0.25;

/// What it learns: each pixel's mean luminance in the training pass, and how long that took.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
struct Constants {
    values: Vec<f32>,
    seconds: f64,
}

/// The learned constants, the training's samples, and how the image's samples use them.
pub struct PixelConstant {
    pt: PathTracing,
    constants: Constants,
    /// Per pixel, the probability that a sample traces its path.
    survival: Vec<f32>,
    training: PixelSums,
    width: u32,
    /// Whether the image keeps the training's samples (not in a shard rendered with a plan
    /// file, whose training shard holds them).
    keeps_taken: bool,
}

impl PixelConstant {
    fn new(context: &Context, constants: Constants, training: PixelSums) -> Self {
        let most = constants.values.iter().copied().fold(0.0, f32::max);
        let survival = (constants.values.iter())
            .map(|&c| {
                if most > 0.0 {
                    (c / most).max(MIN_SURVIVAL)
                } else {
                    1.0
                }
            })
            .collect();
        Self {
            pt: PathTracing {
                max_bounces: context.settings.max_bounces,
            },
            constants,
            survival,
            training,
            width: context.view.scene.camera.width,
            keeps_taken: context.settings.shard.is_whole(),
        }
    }
}

fn prepare(context: &Context) -> Result<Box<dyn Integrator>, PrepareError> {
    let (view, settings) = (context.view, context.settings);
    let start = Instant::now();
    let pass = Pass {
        run_spp: (settings.spp / 2).clamp(1, TRAINING_SPP),
        seed: derive_seed(settings.seed, TRAINING_STREAMS),
        shard: Shard::WHOLE,
        control: Control {
            stop: settings.control.stop.clone(),
            ..Default::default()
        },
        progress: settings.progress,
    };
    let pt = PathTracing {
        max_bounces: settings.max_bounces,
    };
    let film = film::render(view, &pass, None, || pt);
    let training = PixelSums {
        spp: film.spp,
        sum: film.sums.sum,
        sum_sq: film.sums.sum_sq,
    };
    let values = (training.sum.iter())
        .map(|s| (s.element_sum() / 3.0 / f64::from(training.spp.max(1))) as f32)
        .collect();
    let constants = Constants {
        values,
        seconds: start.elapsed().as_secs_f64(),
    };
    Ok(Box::new(PixelConstant::new(context, constants, training)))
}

fn prepare_learned(
    context: &Context,
    learned: Learned,
) -> Result<Box<dyn Integrator>, PrepareError> {
    let constants: Constants = learned.state()?;
    let camera = &context.view.scene.camera;
    let pixels = (camera.width * camera.height) as usize;
    let training = learned.samples.unwrap_or_default();
    if constants.values.len() != pixels || training.sum.len() != pixels {
        return Err(PrepareError::Learned {
            method: learned.method,
            what: format!("{} constants for {pixels} pixels", constants.values.len()),
        });
    }
    Ok(Box::new(PixelConstant::new(context, constants, training)))
}

impl PixelIntegrator for PixelConstant {
    type Estimator<'a> = ConstantEstimator<'a>;
    fn estimator(&self) -> ConstantEstimator<'_> {
        ConstantEstimator {
            pt: self.pt,
            survival: &self.survival,
            width: self.width,
            here: 1.0,
        }
    }
    fn taken(&self) -> Option<&PixelSums> {
        self.keeps_taken.then_some(&self.training)
    }
    fn taken_spp(&self) -> u32 {
        self.training.spp
    }
    fn learned(&self) -> Option<Learned> {
        let summary = serde_json::json!({ "pixels": self.constants.values.len() });
        let training = Some(self.training.clone());
        Some(Learned::new(
            Method::PixelConstant,
            training,
            &self.constants,
            &summary,
        ))
    }
    fn describe(&self, _config: &Settings) -> Description {
        let values = &self.constants.values;
        let mean = values.iter().map(|&v| f64::from(v)).sum::<f64>() / values.len().max(1) as f64;
        let mut description = Description::default();
        let stats = serde_json::json!({ "pixels": values.len(), "mean": mean });
        description.stats.insert("pixel_constant".into(), stats);
        description
            .phases
            .push(("pixel_constant", self.constants.seconds));
        description.lines.push(format!(
            "genpath: pixel-constant: {} constants learned from {} spp in {:.2} s",
            values.len(),
            self.training.spp,
            self.constants.seconds
        ));
        description
    }
    fn explain(&self, camera: &Camera, _image: &Image) -> Option<Result<String, ExplainError>> {
        let (width, height) = (camera.width, camera.height);
        let mut svg = format!(
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{width}\" height=\"{height}\">\n"
        );
        for (i, q) in self.survival.iter().enumerate() {
            let (x, y) = (i as u32 % width, i as u32 / width);
            let grey = (q * 255.0).round() as u8;
            svg += &format!(
                "<rect x=\"{x}\" y=\"{y}\" width=\"1\" height=\"1\" fill=\"rgb({grey},{grey},{grey})\"/>\n"
            );
        }
        svg += "</svg>\n";
        Some(Ok(svg))
    }
}

/// A pixel's samples: each traces its path with the pixel's survival probability.
pub struct ConstantEstimator<'a> {
    pt: PathTracing,
    survival: &'a [f32],
    width: u32,
    /// The survival probability at the current pixel.
    here: f32,
}

impl PixelEstimator for ConstantEstimator<'_> {
    fn start(&mut self, x: u32, y: u32) {
        self.here = self.survival[(y * self.width + x) as usize];
    }
    fn sample(
        &mut self,
        view: &SceneView,
        ray: &Ray,
        rng: &mut Rng,
        counts: &mut RayCounts,
        splats: &mut Splats,
    ) -> DVec3 {
        if uniform(rng) >= self.here {
            return DVec3::ZERO;
        }
        self.pt.sample(view, ray, rng, counts, splats) / f64::from(self.here)
    }
}
