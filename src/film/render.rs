//! The image loop every method shares (pbrt-v4's `ImageTileIntegrator::Render`): square
//! tiles in parallel (rayon), one deterministic random stream per pixel sample, each
//! pixel's samples summed by the estimator its method gives it.

use super::{Control, Film, LayerSums, PixelEstimator, PixelSums, Shard, SplatLayer, Splats};
use crate::accel::Ray;
use crate::image::Image;
use crate::path::{RayCounts, SceneView};
use crate::progress::progress_bar;
use crate::sampling::{camera_ray, sample_rng, Rng};
use crate::scene::Camera;
use glam::DVec3;
use rayon::prelude::*;
use std::ops::ControlFlow;
use std::sync::Mutex;
use std::time::Instant;

/// Side of the square tiles the image is split into for parallel rendering.
pub const TILE: u32 = 16;

/// One run of the loop: `run_spp` samples of each pixel (sample indices `0..run_spp`, of
/// which it takes `shard`'s), drawn from the random streams of `seed`, after the samples a
/// method took while preparing.
#[derive(Clone, Debug)]
pub struct Pass {
    /// Samples per pixel of this run, before sharding: a render's samples after those its
    /// method took while preparing, or one training pass's (never the render's total,
    /// `RenderSettings::spp`).
    pub run_spp: u32,
    pub seed: u64,
    pub shard: Shard,
    pub control: Control,
    /// Show a progress bar on stderr.
    pub progress: bool,
}

/// Sample `s` of pixel `(x, y)` of `camera`'s image: its random stream `(seed, pixel, s)`
/// and the camera ray drawn first from it. Every pass over the image's pixels (a render, a
/// GA plan's baseline and gate, `check`, the GA's test paths) draws its samples so.
fn pixel_sample(camera: &Camera, seed: u64, (x, y): (u32, u32), s: u64) -> (Ray, Rng) {
    let mut rng = sample_stream(camera, seed, (x, y), s);
    let ray = camera_ray(camera, (x, y), &mut rng);
    (ray, rng)
}

/// Takes samples `samples` of pixel `(x, y)` of `camera`'s image under `seed`: each draws
/// its stream and camera ray ([`pixel_sample`]) and is handed to `sample`, which may end the
/// pixel's samples early (`ControlFlow::Break`). Every loop over a pixel's samples is this
/// one: the film's tiles, a GA plan's baseline and gate, `check`, the GA's test paths.
pub fn sample_pixel(
    camera: &Camera,
    seed: u64,
    (x, y): (u32, u32),
    samples: impl IntoIterator<Item = u64>,
    mut sample: impl FnMut(&Ray, &mut Rng) -> ControlFlow<()>,
) {
    for s in samples {
        let (ray, mut rng) = pixel_sample(camera, seed, (x, y), s);
        if sample(&ray, &mut rng).is_break() {
            break;
        }
    }
}

/// The random stream of sample `s` of pixel `(x, y)` of `camera`'s image under `seed`
/// (before its camera ray's numbers): for a pass that draws its camera ray otherwise (the
/// GA's test paths over a footprint wider than the pixel).
pub fn sample_stream(camera: &Camera, seed: u64, (x, y): (u32, u32), s: u64) -> Rng {
    sample_rng(seed, y as u64 * camera.width as u64 + x as u64, s)
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
    /// Per pixel, the sums of its samples (with those taken before).
    pub sums: Vec<PixelResult>,
    /// Samples per pixel in those sums, unless the render was stopped.
    pub spp: u32,
    pub rays: RayCounts,
    /// What its samples splatted, in the order they did.
    pub splats: Splats,
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

/// Renders `pass.run_spp` samples of every pixel of the scene's camera with the estimators that
/// `estimator` makes (one per tile), added to the samples a method took while preparing
/// (`taken`) and to those of `pass.control`'s resumed render, until `pass.control`'s stop is
/// requested.
pub fn render<E: PixelEstimator>(
    view: &SceneView,
    pass: &Pass,
    taken: Option<&PixelSums>,
    estimator: impl Fn() -> E + Sync,
) -> Film {
    if E::SPLATS {
        return render_splatting(view, pass, taken, estimator);
    }
    let start = Instant::now();
    let camera = &view.scene.camera;
    let (width, height) = (camera.width, camera.height);
    let pixels = (width * height) as usize;
    let tiles = tiles(width, height);
    let bar = progress_bar(tiles.len() as u64, "render", pass.progress);
    let snapshots = pass.control.checkpoint.as_ref().map(|checkpoint| {
        let sums = starting_sums(pass, taken, pixels);
        (checkpoint, Mutex::new((sums, Instant::now())))
    });
    let results: Vec<TileResult> = tiles
        .par_iter()
        .map(|tile| {
            let mut estimator = estimator();
            let result = render_tile(view, pass, &mut estimator, taken, tile);
            if let Some((checkpoint, live)) = &snapshots {
                snapshot(checkpoint, live, &result);
            }
            bar.inc(1);
            result
        })
        .collect();
    bar.finish_and_clear();

    let mut sums = LayerSums::zero(pixels);
    let mut rays = RayCounts::default();
    for result in &results {
        for p in &result.sums {
            sums.set(p);
        }
        rays.add(result.rays);
    }
    let interrupted = pass.control.stop.requested().is_some();
    let spp = if interrupted {
        sums.fewest()
    } else {
        results
            .last()
            .map_or_else(|| pass.shard.samples_of(pass.run_spp), |result| result.spp)
    };
    develop(sums, (width, height), spp, rays, (start, interrupted))
}

/// The film of a finished (or stopped) render: its image and variances from `sums`.
fn develop(
    sums: LayerSums,
    (width, height): (u32, u32),
    spp: u32,
    rays: RayCounts,
    (start, interrupted): (Instant, bool),
) -> Film {
    let pixels = (width * height) as usize;
    let mut image = Image::new(width, height);
    let mut variance_of_mean = vec![[0.0; 3]; pixels];
    for (i, (pixel, variance)) in image
        .pixels
        .iter_mut()
        .zip(&mut variance_of_mean)
        .enumerate()
    {
        (*pixel, *variance) = sums.estimate(i);
    }
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

/// The sums a render starts from: its resumed render's, else the samples preparing took,
/// else none.
fn starting_sums(pass: &Pass, taken: Option<&PixelSums>, pixels: usize) -> LayerSums {
    match (&pass.control.resume, taken) {
        (Some(resume), _) => resume.as_ref().clone(),
        (None, Some(taken)) => LayerSums::from(taken),
        (None, None) => LayerSums::zero(pixels),
    }
}

/// [`render`] for an estimator that splats: the samples in passes of one sample per pixel,
/// each pass's tiles' splats added in tile order; a stop, a checkpoint and a resume fall
/// between passes, so that every pixel holds as many samples as the splat layer's passes.
fn render_splatting<E: PixelEstimator>(
    view: &SceneView,
    pass: &Pass,
    taken: Option<&PixelSums>,
    estimator: impl Fn() -> E + Sync,
) -> Film {
    let start = Instant::now();
    let camera = &view.scene.camera;
    let (width, height) = (camera.width, camera.height);
    let pixels = (width * height) as usize;
    let tiles = tiles(width, height);
    let taken_spp = taken.map_or(0, |t| t.spp);
    let mut sums = starting_sums(pass, taken, pixels);
    let mut splat_layer = (sums.splats.take()).unwrap_or_else(|| SplatLayer::zero(pixels));
    let passes = pass.shard.samples_of(pass.run_spp);
    let done = sums.fewest().saturating_sub(taken_spp).min(passes);
    let bar = progress_bar(u64::from(passes - done), "render", pass.progress);
    let mut rays = RayCounts::default();
    let mut last_checkpoint = Instant::now();
    let mut scratch = Vec::new();
    for k in done..passes {
        if pass.control.stop.requested().is_some() {
            break;
        }
        let results: Vec<TileResult> = tiles
            .par_iter()
            .map(|tile| {
                let from = |i: usize| (k, sums.sum[i], sums.sum_sq[i]);
                tile_samples(
                    view,
                    pass,
                    &mut estimator(),
                    tile,
                    (from, 1),
                    (taken_spp, false),
                )
            })
            .collect();
        for result in &results {
            for p in &result.sums {
                sums.set(p);
            }
            rays.add(result.rays);
        }
        let pass_splats: Vec<&Splats> = results.iter().map(|r| &r.splats).collect();
        splat_layer.add_pass(&pass_splats, &mut scratch);
        bar.inc(1);
        if let Some(checkpoint) = &pass.control.checkpoint {
            if last_checkpoint.elapsed() >= checkpoint.every {
                last_checkpoint = Instant::now();
                let mut sums = sums.clone();
                sums.splats = Some(splat_layer.clone());
                (checkpoint.write)(&sums);
            }
        }
    }
    bar.finish_and_clear();
    sums.splats = Some(splat_layer);
    let interrupted = pass.control.stop.requested().is_some();
    let spp = sums.fewest();
    develop(sums, (width, height), spp, rays, (start, interrupted))
}

/// Adds a finished tile's sums to the checkpoint's `live` copy, and hands the copy to the
/// checkpoint's writer when it is due (one writer at a time; the others go on).
fn snapshot(checkpoint: &super::Checkpoint, live: &Mutex<(LayerSums, Instant)>, tile: &TileResult) {
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

/// Renders `pass.run_spp` samples of each pixel of `tile` with `estimator` (those of them
/// that are `pass.shard`'s), started at each pixel in turn, onto the sums in `taken`
/// (none: from zero). Sample `s` of pixel `p` draws from the stream `(pass.seed, p, s)`,
/// its camera ray first, in increasing `s`. A resumed render (`pass.control.resume`)
/// skips each pixel's samples that the resumed sums hold and adds the rest to them; a
/// requested stop ends every pixel before its next sample.
pub fn render_tile<E: PixelEstimator>(
    view: &SceneView,
    pass: &Pass,
    estimator: &mut E,
    taken: Option<&PixelSums>,
    tile: &Tile,
) -> TileResult {
    let resume = pass.control.resume.as_deref();
    let taken_spp = taken.map_or(0, |t| t.spp);
    let from = |index: usize| match resume {
        // The resumed sums hold the samples preparing took too.
        Some(r) => (
            r.counts[index].saturating_sub(taken_spp),
            r.sum[index],
            r.sum_sq[index],
        ),
        None => match taken {
            Some(t) => (0, t.sum[index], t.sum_sq[index]),
            None => (0, DVec3::ZERO, DVec3::ZERO),
        },
    };
    tile_samples(
        view,
        pass,
        estimator,
        tile,
        (from, usize::MAX),
        (taken_spp, true),
    )
}

/// Takes at most `take` of each pixel's samples of `pass` in `tile`, after the `done` that
/// `from(index)` says it has (`(done, sum, sum_sq)`), stopping at a requested stop when
/// `stoppable`; `taken_spp` samples taken while preparing are in every pixel's sums.
fn tile_samples<E: PixelEstimator>(
    view: &SceneView,
    pass: &Pass,
    estimator: &mut E,
    tile: &Tile,
    (from, take): (impl Fn(usize) -> (u32, DVec3, DVec3), usize),
    (taken_spp, stoppable): (u32, bool),
) -> TileResult {
    let camera = &view.scene.camera;
    let n = ((tile.x1 - tile.x0) * (tile.y1 - tile.y0)) as usize;
    let mut sums = Vec::with_capacity(n);
    let mut rays = RayCounts::default();
    let mut splats = Splats::default();
    let stop = &pass.control.stop;
    for y in tile.y0..tile.y1 {
        for x in tile.x0..tile.x1 {
            let index = y as usize * camera.width as usize + x as usize;
            estimator.start(x, y);
            let (mut count, mut sum, mut sum_sq) = from(index);
            let cost_before = rays.cost();
            let samples = pass.shard.samples(pass.run_spp).skip(count as usize);
            let samples = samples.take(take).map(u64::from);
            sample_pixel(camera, pass.seed, (x, y), samples, |ray, rng| {
                if stoppable && stop.requested().is_some() {
                    return ControlFlow::Break(());
                }
                let value = estimator.sample(view, ray, rng, &mut rays, &mut splats);
                sum += value;
                sum_sq += value * value;
                count += 1;
                ControlFlow::Continue(())
            });
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
        spp: taken_spp + pass.shard.samples_of(pass.run_spp),
        rays,
        splats,
    }
}
