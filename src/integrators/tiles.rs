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
    let mut rays = RayCounts::default();
    let mut spp = settings.spp;
    for result in &results {
        spp = result.spp;
        let n = result.spp.max(1) as f64;
        for &(i, sum, sum_sq) in &result.sums {
            let m = sum / n;
            // Unbiased sample variance, divided by spp for the variance of the mean.
            let var = if result.spp > 1 {
                sample_variance(sum, sum_sq, n) / n
            } else {
                DVec3::ZERO
            };
            image.pixels[i] = m.as_vec3().to_array();
            variance_of_mean[i] = var.max(DVec3::ZERO).to_array();
        }
        rays.add(result.rays);
    }
    Film {
        image,
        variance_of_mean,
        spp,
        rays,
        elapsed: start.elapsed(),
    }
}

/// Renders `settings.spp` samples of each pixel of `tile` with `estimator`, started at each
/// pixel in turn, onto the sums in `taken` (none: from zero). Sample `s` of pixel `p` draws
/// from the stream `(settings.seed, p, s)`, its camera ray first.
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
            for s in 0..settings.spp {
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
        spp: taken.map_or(0, |t| t.spp) + settings.spp,
        rays,
    }
}
