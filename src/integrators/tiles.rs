//! The image loop every method shares (pbrt-v4's `ImageTileIntegrator::Render`): square
//! tiles in parallel (rayon), one deterministic random stream per pixel sample, each
//! pixel's samples summed by the estimator its integrator gives it.

use super::{PixelEstimator, PixelIntegrator, RenderSettings};
use crate::image::Image;
use crate::path::{RayCounts, SceneView};
use crate::progress::progress_bar;
use crate::sampling::{camera_ray, sample_rng, sample_variance};
use glam::DVec3;
use rayon::prelude::*;
use std::time::{Duration, Instant};

/// Side of the square tiles the image is split into for parallel rendering.
pub const TILE: u32 = 16;

/// A rendered image with the per-pixel statistics of its estimator.
#[derive(Clone, Debug)]
pub struct Film {
    /// Per-pixel mean of the samples.
    pub image: Image,
    /// Per-pixel, per-channel estimated variance of that mean (sample variance / spp).
    pub variance_of_mean: Vec<[f64; 3]>,
    /// Samples per pixel in the image, those its integrator took while preparing included.
    pub spp: u32,
    pub rays: RayCounts,
    pub elapsed: Duration,
    /// Per pixel, the sums the image is the mean of (what a shard file keeps).
    pub sums: PixelSums,
}

/// Per pixel, the sums of the samples taken so far, which a render adds its own to.
#[derive(Clone, Debug, Default)]
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

/// Which of every pixel's samples a render takes: sample `s` belongs to shard `s mod count`
/// (design §13), so the shards of one render share no random stream, together are that
/// render, and any subset of them is an unbiased render with fewer samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Shard {
    /// `K` of `K/N`: `0 ≤ index < count`.
    pub index: u32,
    /// `N` of `K/N`.
    pub count: u32,
}

impl Shard {
    /// Every sample: the render on one machine.
    pub const WHOLE: Shard = Shard { index: 0, count: 1 };

    pub fn is_whole(&self) -> bool {
        self.count == 1
    }

    /// The indices of this shard's samples among a pixel's `spp`.
    pub fn samples(&self, spp: u32) -> std::iter::StepBy<std::ops::Range<u32>> {
        (self.index.min(spp)..spp).step_by(self.count as usize)
    }

    /// How many of a pixel's `spp` samples are this shard's.
    pub fn samples_of(&self, spp: u32) -> u32 {
        spp.saturating_sub(self.index).div_ceil(self.count)
    }
}

impl Default for Shard {
    fn default() -> Self {
        Self::WHOLE
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl std::str::FromStr for Shard {
    type Err = String;

    /// `K/N` with `0 ≤ K < N`.
    fn from_str(text: &str) -> Result<Self, String> {
        let not = || format!("`{text}` is not K/N (shard K of N, 0 ≤ K < N, e.g. 0/4)");
        let (k, n) = text.split_once('/').ok_or_else(not)?;
        let index: u32 = k.trim().parse().map_err(|_| not())?;
        let count: u32 = n.trim().parse().map_err(|_| not())?;
        if count == 0 {
            return Err(format!(
                "`{text}`: the number of shards N must be at least 1"
            ));
        }
        if count > MAX_SHARDS {
            return Err(format!("`{text}`: at most {MAX_SHARDS} shards"));
        }
        if index >= count {
            return Err(format!(
                "`{text}`: shard K must be below N (shards are numbered 0 to N − 1)"
            ));
        }
        Ok(Self { index, count })
    }
}

/// The most shards a render can be split into (the most samples per pixel).
pub const MAX_SHARDS: u32 = 1 << 24;

/// A rectangle of pixels, `[x0, x1) × [y0, y1)`.
pub struct Tile {
    x0: u32,
    y0: u32,
    x1: u32,
    y1: u32,
}

/// What one tile's render gives.
pub struct TileResult {
    /// Per pixel: its index, and the sum and sum of squares of its samples (with those
    /// taken before).
    pub sums: Vec<(usize, DVec3, DVec3)>,
    /// Samples per pixel in those sums.
    pub spp: u32,
    pub rays: RayCounts,
}

/// The tiles of a `width × height` image, row by row.
pub fn tiles(width: u32, height: u32) -> Vec<Tile> {
    let mut tiles = Vec::new();
    for y0 in (0..height).step_by(TILE as usize) {
        for x0 in (0..width).step_by(TILE as usize) {
            tiles.push(Tile {
                x0,
                y0,
                x1: (x0 + TILE).min(width),
                y1: (y0 + TILE).min(height),
            });
        }
    }
    tiles
}

/// Renders `settings.spp` samples of every pixel of the scene's camera with `integrator`,
/// added to the samples it took while preparing.
pub fn render<I: PixelIntegrator + ?Sized>(
    view: &SceneView,
    settings: &RenderSettings,
    integrator: &I,
) -> Film {
    let start = Instant::now();
    let camera = &view.scene.camera;
    let (width, height) = (camera.width, camera.height);
    let tiles = tiles(width, height);
    let bar = progress_bar(tiles.len() as u64, "render", settings.progress);
    let results: Vec<TileResult> = tiles
        .par_iter()
        .map(|tile| {
            let mut estimator = integrator.estimator();
            let result = render_tile(view, settings, &mut estimator, integrator.taken(), tile);
            bar.inc(1);
            result
        })
        .collect();
    bar.finish_and_clear();

    let mut image = Image::new(width, height);
    let mut variance_of_mean = vec![[0.0; 3]; (width * height) as usize];
    let mut sums = PixelSums::zero((width * height) as usize);
    let mut rays = RayCounts::default();
    let mut spp = settings.shard.samples_of(settings.spp);
    for result in &results {
        spp = result.spp;
        for &(i, sum, sum_sq) in &result.sums {
            (image.pixels[i], variance_of_mean[i]) = pixel_estimate(sum, sum_sq, result.spp);
            sums.sum[i] = sum;
            sums.sum_sq[i] = sum_sq;
        }
        rays.add(result.rays);
    }
    sums.spp = spp;
    Film {
        image,
        variance_of_mean,
        spp,
        rays,
        elapsed: start.elapsed(),
        sums,
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

/// Renders `settings.spp` samples of each pixel of `tile` with `estimator` (those of them
/// that are `settings.shard`'s), started at each pixel in turn, onto the sums in `taken`
/// (none: from zero). Sample `s` of pixel `p` draws from the stream `(settings.seed, p, s)`,
/// its camera ray first, in increasing `s`.
pub fn render_tile<E: PixelEstimator>(
    view: &SceneView,
    settings: &RenderSettings,
    estimator: &mut E,
    taken: Option<&PixelSums>,
    tile: &Tile,
) -> TileResult {
    let camera = &view.scene.camera;
    let n = ((tile.x1 - tile.x0) * (tile.y1 - tile.y0)) as usize;
    let mut sums = Vec::with_capacity(n);
    let mut rays = RayCounts::default();
    for y in tile.y0..tile.y1 {
        for x in tile.x0..tile.x1 {
            let pixel = y as u64 * camera.width as u64 + x as u64;
            estimator.start(x, y);
            let (mut sum, mut sum_sq) = match taken {
                Some(t) => t.at(pixel as usize),
                None => (DVec3::ZERO, DVec3::ZERO),
            };
            for s in settings.shard.samples(settings.spp) {
                let mut rng = sample_rng(settings.seed, pixel, s as u64);
                let ray = camera_ray(camera, (x, y), &mut rng);
                let value = estimator.sample(view, &ray, &mut rng, &mut rays);
                sum += value;
                sum_sq += value * value;
            }
            sums.push((pixel as usize, sum, sum_sq));
        }
    }
    TileResult {
        sums,
        spp: taken.map_or(0, |t| t.spp) + settings.shard.samples_of(settings.spp),
        rays,
    }
}
