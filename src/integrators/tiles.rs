//! The image loop every method shares (pbrt-v4's `ImageTileIntegrator::Render`): square
//! tiles in parallel (rayon), one deterministic random stream per pixel sample, each
//! pixel's samples summed by the estimator its integrator gives it.

use super::{PixelEstimator, PixelIntegrator, RenderSettings};
use crate::genetic::plan::LearnStore;
use crate::image::Image;
use crate::path::{RayCounts, SceneView};
use crate::progress::progress_bar;
use crate::sampling::{camera_ray, sample_rng, sample_variance};
use glam::DVec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
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
}

impl LayerSums {
    /// No samples at `pixels` pixels.
    pub fn zero(pixels: usize) -> Self {
        Self {
            counts: vec![0; pixels],
            sum: vec![DVec3::ZERO; pixels],
            sum_sq: vec![DVec3::ZERO; pixels],
        }
    }

    /// The image (the mean of each pixel's samples), as a render computes it.
    pub fn image(&self, width: u32, height: u32) -> Image {
        let mut image = Image::new(width, height);
        for (i, pixel) in image.pixels.iter_mut().enumerate() {
            (*pixel, _) = pixel_estimate(self.sum[i], self.sum_sq[i], self.counts[i]);
        }
        image
    }

    /// Samples in the pixel that has the fewest.
    pub fn fewest(&self) -> u32 {
        self.counts.iter().copied().min().unwrap_or(0)
    }

    fn set(&mut self, p: &PixelResult) {
        self.counts[p.index] = p.count;
        self.sum[p.index] = p.sum;
        self.sum_sq[p.index] = p.sum_sq;
    }
}

/// A request to stop a render early, shared with whoever makes it (a signal handler): `0`
/// while the render should go on, else the number of the signal that stopped it. Each
/// pixel checks it before each sample, so a render stops within one sample per thread and
/// keeps every sample it took.
#[derive(Clone, Debug, Default)]
pub struct Stop(Option<Arc<AtomicUsize>>);

impl Stop {
    /// A stop requested by storing a non-zero value (a signal number) in `flag`.
    pub fn on(flag: Arc<AtomicUsize>) -> Self {
        Self(Some(flag))
    }

    /// The signal number that requested the stop, if one did.
    pub fn requested(&self) -> Option<usize> {
        self.0
            .as_ref()
            .map(|f| f.load(Ordering::Relaxed))
            .filter(|&s| s != 0)
    }
}

/// Periodic snapshots of a render's sums while it runs (`render --checkpoint SECONDS`):
/// after each tile, when `every` has passed since the last, `write` is given every pixel's
/// sums so far (the finished tiles', and for the others what the render started from).
#[derive(Clone)]
pub struct Checkpoint {
    pub every: Duration,
    pub write: Arc<dyn Fn(&LayerSums) + Send + Sync>,
}

impl std::fmt::Debug for Checkpoint {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Checkpoint(every {:?})", self.every)
    }
}

/// How a render may be stopped, continued and saved while it runs; by default it starts
/// from nothing and runs to the end.
#[derive(Clone, Debug, Default)]
pub struct Control {
    pub stop: Stop,
    /// Sums of this render (this shard of it) taken before, in a shard file it wrote when
    /// it was stopped or at a checkpoint: pixel `p` holds the first `counts[p]` of its
    /// samples, and the render takes the rest onto those sums (`render --resume FILE`).
    pub resume: Option<Arc<LayerSums>>,
    pub checkpoint: Option<Checkpoint>,
    /// Where learning keeps what it finished between processes (`genpath learn`): a GA
    /// plan's waves of GA pixels and the spatial guide's passes, so that learning goes on
    /// after a signal, and the GA splits over jobs.
    pub learning: Option<Arc<dyn LearnStore>>,
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
    /// Per pixel, the sums of its samples (with those taken before).
    pub sums: Vec<PixelResult>,
    /// Samples per pixel in those sums, unless the render was stopped.
    pub spp: u32,
    pub rays: RayCounts,
}

/// One pixel's sums after a tile's render.
pub struct PixelResult {
    pub index: usize,
    pub sum: DVec3,
    pub sum_sq: DVec3,
    /// Samples in the sums.
    pub count: u32,
    /// The work of this call's samples of the pixel, in rays ([`RayCounts::cost`]).
    pub cost: f64,
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
/// added to the samples it took while preparing (and to those of `settings.control`'s
/// resumed render), until `settings.control`'s stop is requested.
pub fn render<I: PixelIntegrator + ?Sized>(
    view: &SceneView,
    settings: &RenderSettings,
    integrator: &I,
) -> Film {
    let start = Instant::now();
    let camera = &view.scene.camera;
    let (width, height) = (camera.width, camera.height);
    let pixels = (width * height) as usize;
    let tiles = tiles(width, height);
    let bar = progress_bar(tiles.len() as u64, "render", settings.progress);
    let snapshots = settings.control.checkpoint.as_ref().map(|checkpoint| {
        let sums = match (&settings.control.resume, integrator.taken()) {
            (Some(resume), _) => resume.as_ref().clone(),
            (None, Some(taken)) => LayerSums {
                counts: vec![taken.spp; pixels],
                sum: taken.sum.clone(),
                sum_sq: taken.sum_sq.clone(),
            },
            (None, None) => LayerSums::zero(pixels),
        };
        (checkpoint, Mutex::new((sums, Instant::now())))
    });
    let results: Vec<TileResult> = tiles
        .par_iter()
        .map(|tile| {
            let mut estimator = integrator.estimator();
            let result = render_tile(view, settings, &mut estimator, integrator.taken(), tile);
            if let Some((checkpoint, live)) = &snapshots {
                snapshot(checkpoint, live, &result);
            }
            bar.inc(1);
            result
        })
        .collect();
    bar.finish_and_clear();

    let mut image = Image::new(width, height);
    let mut variance_of_mean = vec![[0.0; 3]; pixels];
    let mut sums = LayerSums::zero(pixels);
    let mut rays = RayCounts::default();
    for result in &results {
        for p in &result.sums {
            (image.pixels[p.index], variance_of_mean[p.index]) =
                pixel_estimate(p.sum, p.sum_sq, p.count);
            sums.set(p);
        }
        rays.add(result.rays);
    }
    let interrupted = settings.control.stop.requested().is_some();
    let spp = if interrupted {
        sums.fewest()
    } else {
        results.last().map_or_else(
            || settings.shard.samples_of(settings.spp),
            |result| result.spp,
        )
    };
    Film {
        image,
        variance_of_mean,
        spp,
        rays,
        elapsed: start.elapsed(),
        sums,
        interrupted,
    }
}

/// Adds a finished tile's sums to the checkpoint's `live` copy, and hands the copy to the
/// checkpoint's writer when it is due (one writer at a time; the others go on).
fn snapshot(checkpoint: &Checkpoint, live: &Mutex<(LayerSums, Instant)>, tile: &TileResult) {
    let due = {
        let Ok(mut guard) = live.lock() else { return };
        let (sums, last) = &mut *guard;
        for p in &tile.sums {
            sums.set(p);
        }
        if last.elapsed() < checkpoint.every {
            None
        } else {
            *last = Instant::now();
            Some(sums.clone())
        }
    };
    if let Some(sums) = due {
        (checkpoint.write)(&sums);
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
/// its camera ray first, in increasing `s`. A resumed render (`settings.control.resume`)
/// skips each pixel's samples that the resumed sums hold and adds the rest to them; a
/// requested stop ends every pixel before its next sample.
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
    let (resume, stop) = (settings.control.resume.as_deref(), &settings.control.stop);
    let taken_spp = taken.map_or(0, |t| t.spp);
    for y in tile.y0..tile.y1 {
        for x in tile.x0..tile.x1 {
            let pixel = y as u64 * camera.width as u64 + x as u64;
            let index = pixel as usize;
            estimator.start(x, y);
            let (mut sum, mut sum_sq) = match taken {
                Some(t) => t.at(index),
                None => (DVec3::ZERO, DVec3::ZERO),
            };
            let mut count = 0;
            let cost_before = rays.cost();
            if let Some(r) = resume {
                // The resumed sums hold the samples preparing took too.
                let done = r.counts[index].saturating_sub(taken_spp);
                (count, sum, sum_sq) = (done, r.sum[index], r.sum_sq[index]);
            }
            for s in settings.shard.samples(settings.spp).skip(count as usize) {
                if stop.requested().is_some() {
                    break;
                }
                let mut rng = sample_rng(settings.seed, pixel, s as u64);
                let ray = camera_ray(camera, (x, y), &mut rng);
                let value = estimator.sample(view, &ray, &mut rng, &mut rays);
                sum += value;
                sum_sq += value * value;
                count += 1;
            }
            sums.push(PixelResult {
                index,
                sum,
                sum_sq,
                count: taken_spp + count,
                cost: rays.cost() - cost_before,
            });
        }
    }
    TileResult {
        sums,
        spp: taken_spp + settings.shard.samples_of(settings.spp),
        rays,
    }
}
