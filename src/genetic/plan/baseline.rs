//! Choosing the GA pixels: the grid's cells and their scattering pixels, the baseline pass
//! of `srt` samples, and the pixels chosen from its variance. The baseline's samples are
//! unbiased samples of every pixel like any other, and the image keeps them
//! ([`super::Plan::baseline`]).

use super::super::luminance;
use super::config::PlanConfig;
use super::context::PixelContext;
use super::types::{Origin, PlanStats};
use crate::film::sample_pixel;
use crate::film::PixelSums;
use crate::path::mixture::{Mixture, MixtureScratch};
use crate::path::{mixture_sample, RayCounts, SceneView};
use crate::sampling::{derived_seed, sample_variance, Stream};
use glam::DVec3;
use rayon::prelude::*;
use std::ops::ControlFlow;

/// Per-pixel baseline estimate.
#[derive(Clone, Copy, Default)]
struct Baseline {
    /// Relative variance of one `srt` sample: `Var[L] / (E[L]² + 0.01)` (luminance).
    rel_variance: f64,
    /// Sum and sum of squares of the samples' luminance.
    sum: f64,
    sum_sq: f64,
    /// Some baseline ray hit a scattering surface.
    scatters: bool,
    /// Sum and sum of squares of the samples (RGB), which the image keeps.
    rgb_sum: DVec3,
    rgb_sum_sq: DVec3,
}

/// The cells of a `grid`-pixel grid over a `width × height` image, row by row: `[x0, y0, x1,
/// y1)` each, clipped to the image.
fn grid_cells(width: u32, height: u32, grid: u32) -> impl Iterator<Item = [u32; 4]> {
    (0..height).step_by(grid as usize).flat_map(move |y0| {
        (0..width)
            .step_by(grid as usize)
            .map(move |x0| [x0, y0, (x0 + grid).min(width), (y0 + grid).min(height)])
    })
}

/// Each grid cell's GA pixel: the pixel closest to the cell's centre whose centre ray sees a
/// scattering surface (`None`: the cell has none), in row-major cell order; and the pixels
/// whose centre ray sees none. One ray per pixel, no random numbers: the pilot can run
/// before (and without) the baseline.
fn grid_pixels(
    view: &SceneView,
    grid: u32,
    counts: &mut RayCounts,
) -> (Vec<Option<(u32, u32)>>, usize) {
    let camera = &view.scene.camera;
    let (width, height) = (camera.width, camera.height);
    let rows: Vec<(Vec<bool>, RayCounts)> = (0..height)
        .into_par_iter()
        .map(|y| {
            let mut c = RayCounts::default();
            let row = (0..width)
                .map(|x| {
                    let ray = camera.ray(x as f32 + 0.5, y as f32 + 0.5);
                    view.trace(&ray, &mut c)
                        .is_some_and(|hit| view.material(hit.prim).scatters())
                })
                .collect();
            (row, c)
        })
        .collect();
    let mut scatters = Vec::with_capacity((width * height) as usize);
    for (row, c) in rows {
        scatters.extend(row);
        counts.add(c);
    }
    let cells = grid_cells(width, height, grid)
        .map(|[x0, y0, x1, y1]| {
            let centre = ((x0 + x1 - 1) as f64 / 2.0, (y0 + y1 - 1) as f64 / 2.0);
            let mut best: Option<(f64, u32, u32)> = None;
            for y in y0..y1 {
                for x in x0..x1 {
                    if !scatters[(y * width + x) as usize] {
                        continue;
                    }
                    let d = (x as f64 - centre.0).powi(2) + (y as f64 - centre.1).powi(2);
                    if best.is_none_or(|(bd, ..)| d < bd) {
                        best = Some((d, x, y));
                    }
                }
            }
            best.map(|(_, x, y)| (x, y))
        })
        .collect();
    (cells, scatters.iter().filter(|s| !**s).count())
}

/// [`grid_pixels`], with its rays, its pixels without a scattering surface and its empty
/// cells counted in `stats`.
pub(super) fn scattering_cells(
    view: &SceneView,
    grid: u32,
    stats: &mut PlanStats,
) -> Vec<Option<(u32, u32)>> {
    let mut counts = RayCounts::default();
    let (cells, skipped) = grid_pixels(view, grid, &mut counts);
    stats.rays.add(counts);
    stats.skipped_pixels = skipped;
    stats.empty_cells = cells.iter().filter(|c| c.is_none()).count();
    cells
}

/// The baseline pass and the GA pixels [`choose_pixels`] chooses from it in `cells` (those
/// at `keep`, the pilot's, stay whatever their cells' variance), with the baseline's rays,
/// low-variance cells and variance quartiles in `stats`; and its samples' per-pixel sums.
pub(super) fn baseline_choice(
    context: &PixelContext,
    cells: &[Option<(u32, u32)>],
    keep: &[(u32, u32)],
    stats: &mut PlanStats,
) -> (Choice, PixelSums) {
    let &PixelContext {
        view,
        srt,
        config,
        max_bounces,
        seed,
        ..
    } = context;
    let camera = &view.scene.camera;
    let (base, counts) = baseline(view, srt, config, max_bounces, seed);
    stats.rays.add(counts);
    stats.baseline_ran = true;
    let size = (camera.width, camera.height);
    let grid = config.grid(context.plan_for);
    let choice = choose_pixels(&base, cells, (size, grid), config, keep);
    let samples = PixelSums {
        spp: config.baseline_spp,
        sum: base.iter().map(|b| b.rgb_sum).collect(),
        sum_sq: base.iter().map(|b| b.rgb_sum_sq).collect(),
    };
    stats.low_variance_cells = choice.low.len();
    let mut v = choice.cell_variance.clone();
    v.sort_by(f64::total_cmp);
    if !v.is_empty() {
        stats.cell_variance = [v[0], v[v.len() / 2], v[v.len() - 1]];
    }
    (choice, samples)
}

fn baseline(
    view: &SceneView,
    srt: &Mixture,
    config: &PlanConfig,
    max_bounces: u32,
    seed: u64,
) -> (Vec<Baseline>, RayCounts) {
    let camera = &view.scene.camera;
    let (width, height) = (camera.width, camera.height);
    let seed = derived_seed(seed, Stream::Baseline.tag());
    let rows: Vec<(Vec<Baseline>, RayCounts)> = (0..height)
        .into_par_iter()
        .map(|y| {
            let mut counts = RayCounts::default();
            let mut scratch = MixtureScratch::default();
            let row = (0..width)
                .map(|x| {
                    let (mut sum, mut sum_sq, mut scatters) = (0.0, 0.0, false);
                    let (mut rgb_sum, mut rgb_sum_sq) = (DVec3::ZERO, DVec3::ZERO);
                    let samples = 0..u64::from(config.baseline_spp);
                    sample_pixel(camera, seed, (x, y), samples, |ray, rng| {
                        let hit = view.trace_through(ray, rng, &mut counts);
                        scatters |= hit.is_some_and(|x1| view.material(x1.prim).scatters());
                        let value = mixture_sample(
                            view,
                            (ray, hit),
                            max_bounces,
                            srt,
                            rng,
                            &mut counts,
                            &mut scratch,
                        );
                        rgb_sum += value;
                        rgb_sum_sq += value * value;
                        let l = luminance(value);
                        sum += l;
                        sum_sq += l * l;
                        ControlFlow::Continue(())
                    });
                    let n = config.baseline_spp as f64;
                    let mean = sum / n;
                    let var = if n > 1.0 {
                        sample_variance(sum, sum_sq, n).max(0.0)
                    } else {
                        0.0
                    };
                    Baseline {
                        rel_variance: var / (mean * mean + 0.01),
                        sum,
                        sum_sq,
                        scatters,
                        rgb_sum,
                        rgb_sum_sq,
                    }
                })
                .collect();
            (row, counts)
        })
        .collect();
    let mut counts = RayCounts::default();
    let mut out = Vec::with_capacity((width * height) as usize);
    for (row, c) in rows {
        out.extend(row);
        counts.add(c);
    }
    (out, counts)
}

/// What [`choose_pixels`] chose and left out.
pub(super) struct Choice {
    pub(super) pixels: Vec<(u32, u32, Origin)>,
    /// The GA pixel of each low-variance cell (pruning).
    pub(super) low: Vec<(u32, u32)>,
    /// Pooled baseline relative variance of every cell with a GA pixel.
    cell_variance: Vec<f64>,
}

/// The GA pixels, in cells `grid` pixels wide: each cell's grid pixel ([`grid_pixels`]),
/// then extras in the noisiest cells; with pruning, none in cells whose pooled baseline relative variance is below
/// `config.prune_variance`, except at `keep` (the pilot, already evolved).
fn choose_pixels(
    base: &[Baseline],
    cells: &[Option<(u32, u32)>],
    ((width, height), grid): ((u32, u32), u32),
    config: &PlanConfig,
    keep: &[(u32, u32)],
) -> Choice {
    let mut chosen = Vec::new();
    let mut low_cells = Vec::new();
    let mut noisy = Vec::new();
    let mut cell_variance = Vec::new();
    for ([x0, y0, x1, y1], cell) in grid_cells(width, height, grid).zip(cells) {
        let Some((x, y)) = *cell else {
            continue;
        };
        let (mut sum, mut sum_sq, mut n) = (0.0, 0.0, 0usize);
        let mut noisiest = None::<(f64, u32, u32)>;
        for py in y0..y1 {
            for px in x0..x1 {
                let b = base[(py * width + px) as usize];
                if !b.scatters {
                    continue;
                }
                sum += b.sum;
                sum_sq += b.sum_sq;
                n += config.baseline_spp as usize;
                if noisiest.is_none_or(|(v, ..)| b.rel_variance > v) {
                    noisiest = Some((b.rel_variance, px, py));
                }
            }
        }
        // The cell's samples pooled: rare bright paths, which a few samples per pixel
        // mostly miss, still show up in the cell's variance.
        let mean_noise = if n > 1 {
            let mean = sum / n as f64;
            let var = sample_variance(sum, sum_sq, n as f64).max(0.0);
            var / (mean * mean + 0.01)
        } else {
            0.0
        };
        cell_variance.push(mean_noise);
        if config.prune && mean_noise < config.prune_variance && !keep.contains(&(x, y)) {
            low_cells.push((x, y));
            continue;
        }
        chosen.push((x, y, Origin::Grid));
        if let Some((_, nx, ny)) = noisiest.filter(|&(_, nx, ny)| (nx, ny) != (x, y)) {
            noisy.push((mean_noise, nx, ny));
        }
    }
    let extra = (config.extra * chosen.len() as f64).round() as usize;
    noisy.sort_by(|a, b| b.0.total_cmp(&a.0).then((a.2, a.1).cmp(&(b.2, b.1))));
    chosen.extend(
        noisy
            .iter()
            .take(extra)
            .map(|&(_, x, y)| (x, y, Origin::Extra)),
    );
    Choice {
        pixels: chosen,
        low: low_cells,
        cell_variance,
    }
}
