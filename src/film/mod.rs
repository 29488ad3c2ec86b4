//! The film: what every method's samples land on (pbrt-v4's `Film`, Mitsuba 3's
//! `ImageBlock`), and the one loop that takes them ([`render`]).
//!
//! A pixel's own samples are summed per pixel ([`LayerSums`]: a count, a sum and a sum of
//! squares), so that the image is their mean and its variance is estimated. A sample may
//! also *splat*: add light to another pixel (a light-started path reaching the camera).
//! Splats go into a layer of their own ([`SplatLayer`]) that counts the light paths that fed
//! it and is divided by that count, not by a pixel's samples; the image is the sum of both.
//! Splats are gathered per tile and added in tile order, so that the image does not depend
//! on the thread count.
//!
//! The loop ([`render`]) walks the image in tiles, draws sample `s` of pixel `p` from the
//! random stream `(seed, p, s)` with its camera ray first ([`sample_pixel`]), and asks a
//! [`PixelEstimator`] for its value. It can stop, checkpoint and resume ([`Control`]), and
//! take only one shard's samples ([`Shard`]). Everything else that samples pixels of the
//! image (a GA plan's baseline, its gate, `check`, the GA's test paths) draws its samples
//! through [`sample_pixel`] too.

mod control;
mod render;
mod shard;

pub use control::{Checkpoint, Control, Stop};
pub use render::{
    render, render_tile, sample_pixel, sample_stream, tiles, Pass, PixelResult, Tile, TileResult,
    TILE,
};
pub use shard::{Shard, ShardParseError, MAX_SHARDS};

use crate::accel::Ray;
use crate::image::Image;
use crate::path::{RayCounts, SceneView};
use crate::sampling::{sample_variance, Rng};
use glam::DVec3;
use std::time::Duration;

/// The estimator of one pixel's samples, reused from pixel to pixel of a tile.
pub trait PixelEstimator {
    /// Whether its samples splat onto other pixels. The loop then takes the samples in
    /// passes of one sample per pixel and stops, checkpoints and resumes only between
    /// passes, so that every pixel's splats come from whole passes.
    const SPLATS: bool = false;
    /// Makes this the estimator of pixel `(x, y)` (its neighbours' mixture, its guide).
    fn start(&mut self, x: u32, y: u32);
    /// One sample of the radiance along camera ray `ray`, drawn from `rng` (the sample's
    /// own stream, after the camera ray's two numbers); light it sends to other pixels goes
    /// to `splats`.
    fn sample(
        &mut self,
        view: &SceneView,
        ray: &Ray,
        rng: &mut Rng,
        counts: &mut RayCounts,
        splats: &mut Splats,
    ) -> DVec3;
}

/// A rendered image with the per-pixel statistics of its estimator.
#[derive(Clone, Debug)]
pub struct Film {
    /// Per-pixel mean of the samples, plus the splat layer's light where there is one.
    pub image: Image,
    /// Per-pixel, per-channel estimated variance of the pixel's value: of the mean of its own
    /// samples (sample variance / spp), plus the splat layer's (from its passes'
    /// spread, [`SplatLayer::variance`]).
    pub variance_of_mean: Vec<[f64; 3]>,
    /// Samples per pixel in the image, those its integrator took while preparing included.
    pub spp: u32,
    pub rays: RayCounts,
    pub elapsed: Duration,
    /// Per pixel, the sums the image is the mean of and their sample counts (what a shard
    /// file keeps).
    pub sums: LayerSums,
    /// Whether the render stopped before it took every sample ([`Stop`]): then
    /// [`LayerSums::counts`] says how many each pixel has.
    pub interrupted: bool,
}

/// One layer of a render's per-pixel sums with the number of samples in each: a film's,
/// a shard file's (a reference has two layers, one per half), a merge's.
#[derive(Clone, Debug, PartialEq)]
pub struct LayerSums {
    /// Samples in each pixel's sums.
    pub counts: Vec<u32>,
    pub sum: Vec<DVec3>,
    pub sum_sq: Vec<DVec3>,
    /// What samples splatted onto the pixels, for a method that splats.
    pub splats: Option<SplatLayer>,
}

impl LayerSums {
    /// No samples at `pixels` pixels.
    pub fn zero(pixels: usize) -> Self {
        Self {
            counts: vec![0; pixels],
            sum: vec![DVec3::ZERO; pixels],
            sum_sq: vec![DVec3::ZERO; pixels],
            splats: None,
        }
    }

    /// The image (the mean of each pixel's samples, plus the splat layer's light), as a
    /// render computes it.
    pub fn image(&self, width: u32, height: u32) -> Image {
        let mut image = Image::new(width, height);
        for (i, pixel) in image.pixels.iter_mut().enumerate() {
            (*pixel, _) = self.estimate(i);
        }
        image
    }

    /// Pixel `i`'s value and the estimated variance of the mean of its own samples.
    pub fn estimate(&self, i: usize) -> ([f32; 3], [f64; 3]) {
        let (sum, sum_sq, count) = (self.sum[i], self.sum_sq[i], self.counts[i]);
        match &self.splats {
            Some(splats) if splats.light_paths > 0 => {
                let (_, variance) = pixel_estimate(sum, sum_sq, count);
                let mean = sum / f64::from(count.max(1)) + splats.light(i);
                let variance = DVec3::from_array(variance) + splats.variance(i);
                (mean.as_vec3().to_array(), variance.to_array())
            }
            _ => pixel_estimate(sum, sum_sq, count),
        }
    }

    /// Samples in the pixel that has the fewest.
    pub fn fewest(&self) -> u32 {
        self.counts.iter().copied().min().unwrap_or(0)
    }

    pub(crate) fn set(&mut self, p: &PixelResult) {
        self.counts[p.index] = p.count;
        self.sum[p.index] = p.sum;
        self.sum_sq[p.index] = p.sum_sq;
    }
}

/// The light that samples splatted onto each pixel, and the number of light paths that
/// carried it: pixel `i`'s share of the image is `sum[i] / light_paths`. The light comes
/// in passes of equally many light paths (one per pixel sample of the pass); the sums of
/// squares of each pass's light per pixel give its variance.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SplatLayer {
    pub light_paths: u64,
    /// Passes summed, each of `light_paths / passes` light paths.
    pub passes: u64,
    pub sum: Vec<DVec3>,
    /// Per pixel, the sum over passes of the square of the pass's light there.
    pub sum_sq: Vec<DVec3>,
}

impl SplatLayer {
    /// No light yet at `pixels` pixels.
    pub fn zero(pixels: usize) -> Self {
        Self {
            light_paths: 0,
            passes: 0,
            sum: vec![DVec3::ZERO; pixels],
            sum_sq: vec![DVec3::ZERO; pixels],
        }
    }

    /// Pixel `i`'s share of the image.
    pub fn light(&self, i: usize) -> DVec3 {
        self.sum[i] / self.light_paths as f64
    }

    /// The estimated variance of [`Self::light`] at pixel `i`: the passes' light there,
    /// each the mean of its light paths', is a sample of independent values whose mean
    /// the pixel's share is; zero with fewer than two passes.
    pub fn variance(&self, i: usize) -> DVec3 {
        if self.passes < 2 || self.light_paths == 0 {
            return DVec3::ZERO;
        }
        // One pass's light paths: each pass's light is its sum over them.
        let per_pass = self.light_paths as f64 / self.passes as f64;
        let n = self.passes as f64;
        let (sum, sum_sq) = (
            self.sum[i] / per_pass,
            self.sum_sq[i] / (per_pass * per_pass),
        );
        (sample_variance(sum, sum_sq, n) / n).max(DVec3::ZERO)
    }

    /// Adds one pass: its tiles' splats, in tile order.
    pub fn add_pass(&mut self, tiles: &[&Splats], scratch: &mut Vec<DVec3>) {
        scratch.clear();
        scratch.resize(self.sum.len(), DVec3::ZERO);
        for splats in tiles {
            self.light_paths += splats.light_paths;
            for &(i, value) in &splats.list {
                scratch[i as usize] += value;
            }
        }
        self.passes += 1;
        for ((sum, sum_sq), pass) in self.sum.iter_mut().zip(&mut self.sum_sq).zip(&*scratch) {
            *sum += *pass;
            *sum_sq += *pass * *pass;
        }
    }

    /// Adds another layer of the same image (a shard's).
    pub fn add_layer(&mut self, other: &SplatLayer) {
        self.light_paths += other.light_paths;
        self.passes += other.passes;
        for (a, b) in self.sum.iter_mut().zip(&other.sum) {
            *a += *b;
        }
        for (a, b) in self.sum_sq.iter_mut().zip(&other.sum_sq) {
            *a += *b;
        }
    }
}

/// Where one tile's samples put their splats, in order, and count the light paths they
/// traced; the film adds each tile's list in tile order ([`SplatLayer::add`]).
#[derive(Clone, Debug, Default)]
pub struct Splats {
    list: Vec<(u32, DVec3)>,
    light_paths: u64,
}

impl Splats {
    /// Adds `value` to pixel `index` (row by row).
    pub fn add(&mut self, index: u32, value: DVec3) {
        self.list.push((index, value));
    }

    /// Counts `n` light paths traced, whether or not they splatted.
    pub fn count_light_paths(&mut self, n: u64) {
        self.light_paths += n;
    }
}

/// Per pixel, the sums of the samples taken so far, which a render adds its own to.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct PixelSums {
    /// Samples per pixel so far.
    pub spp: u32,
    pub sum: Vec<DVec3>,
    pub sum_sq: Vec<DVec3>,
}

impl PixelSums {
    /// No samples yet at each of `pixels` pixels.
    pub fn zero(pixels: usize) -> Self {
        Self {
            spp: 0,
            sum: vec![DVec3::ZERO; pixels],
            sum_sq: vec![DVec3::ZERO; pixels],
        }
    }

    /// Pixel `i`'s sum and sum of squares.
    pub fn at(&self, i: usize) -> (DVec3, DVec3) {
        (self.sum[i], self.sum_sq[i])
    }
}

impl From<&PixelSums> for LayerSums {
    /// The layer of the samples `sums` holds, `sums.spp` in every pixel.
    fn from(sums: &PixelSums) -> Self {
        Self {
            counts: vec![sums.spp; sums.sum.len()],
            sum: sums.sum.clone(),
            sum_sq: sums.sum_sq.clone(),
            splats: None,
        }
    }
}

/// A pixel's value, the mean of its `spp` samples, and the estimated variance of that mean,
/// from their sum and sum of squares: what a render and a merge of shards both write.
pub fn pixel_estimate(sum: DVec3, sum_sq: DVec3, spp: u32) -> ([f32; 3], [f64; 3]) {
    let n = spp.max(1) as f64;
    let m = sum / n;
    // Unbiased sample variance, divided by spp for the variance of the mean.
    let var = if spp > 1 {
        sample_variance(sum, sum_sq, n) / n
    } else {
        DVec3::ZERO
    };
    (m.as_vec3().to_array(), var.max(DVec3::ZERO).to_array())
}
