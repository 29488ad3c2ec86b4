//! The gate's pilot: grid GA pixels spread over the image, evolved first, whose trials
//! decide whether the GA goes on past them.

use super::context::GaRun;
use super::stages::PlanError;
use super::types::{Evolved, Origin};
use super::waves::{Job, Waves};
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};

/// GA pixels evolved before the gate decides whether to evolve the others.
pub const PILOT_PIXELS: usize = 8;
/// The pilot evolves for `1 / PILOT_SHARE` of the generations before its trial decides, so
/// a scene where the GA cannot pay spends a quarter of a full pilot on finding out: a full
/// pilot is a large share of a short budget (reports/README.md, "Measurements formerly in
/// code comments (2026-12-07)", `PILOT_SHARE`). Where the pilot pays, its pixels go on from
/// their best individual for the remaining generations.
pub const PILOT_SHARE: usize = 4;

/// The pilot: with the gate, up to `PILOT_PIXELS` grid pixels spread evenly over the image
/// (`grid`, in row-major cell order), evolved first, before the baseline: where it predicts
/// no gain, the plan costs no baseline. Without the gate, none.
pub(super) fn pilot_pixels(grid: &[(u32, u32)], gate: bool) -> Vec<(u32, u32, Origin)> {
    if !gate {
        return Vec::new();
    }
    let k = PILOT_PIXELS.min(grid.len());
    (0..k)
        .map(|j| {
            let (x, y) = grid[j * grid.len() / k];
            (x, y, Origin::Grid)
        })
        .collect()
}

/// Evolves the pilot's pixels for `scout` generations, in parallel, each with its trial.
///
/// Where a failed pilot `closes` the plan (a mixture's, or a guide's beside the spatial
/// guide), a pilot pixel is not started once so many others failed to pay that the pilot
/// cannot: where the pilot fails this shortens the GA phase, and the image is the same bit
/// for bit (reports/README.md, "Measurements formerly in code comments (2026-12-07)",
/// `scout_pilot`). Which pixels that skips depends on the threads' timing, so such a pilot
/// that fails leaves the whole image to `pt` or the spatial guide (see `Plan::closed`),
/// whichever of its pixels ran. With a store (learning kept between
/// processes, or split over jobs) every pilot pixel runs, as one wave: the store's
/// results must not depend on timing.
pub(super) fn scout_pilot(waves: &mut Waves, scout: usize, closes: bool) -> Result<(), PlanError> {
    let plan_for = waves.context.plan_for;
    let pilot = waves.pilot;
    let run = || GaRun {
        seeds: Vec::new(),
        generations: scout,
        stream: 0,
        trial: true,
    };
    if waves.context.store.is_some() {
        let jobs: Vec<Job> = (0..pilot).map(|pixel| Job { pixel, run: run() }).collect();
        return waves.evolve(&jobs);
    }
    let losing = AtomicUsize::new(0);
    let settled = || closes && 2 * (pilot - losing.load(Ordering::Relaxed)) < pilot;
    let this = &*waves;
    let scouted_pilot: Vec<(usize, Evolved)> = (0..pilot)
        .into_par_iter()
        .filter_map(|i| {
            if settled() {
                return None;
            }
            let r = this.evolve_one(i, &run());
            if !r.0.pays(plan_for) {
                losing.fetch_add(1, Ordering::Relaxed);
            }
            Some((i, r))
        })
        .collect();
    for (i, r) in scouted_pilot {
        waves.done[i] = Some(r);
    }
    Ok(())
}

/// The geometric mean of the scouted pilot pixels' predicted gains over `pt`
/// ([`geometric_mean_gain`]).
pub(super) fn pilot_gain(waves: &Waves) -> f64 {
    let trials = waves.done.iter().flatten().filter_map(|(p, _)| p.trial);
    geometric_mean_gain(trials.map(|t| t.gain))
}

/// The geometric mean of trials' gains: 0 without a finite one; a gain of 0 (nothing to
/// gain) counts as 10⁻⁹, and a NaN or infinite one is left out.
fn geometric_mean_gain(gains: impl Iterator<Item = f64>) -> f64 {
    let (sum, n) = gains
        .filter(|g| g.is_finite())
        .fold((0.0, 0usize), |(sum, n), g| (sum + g.max(1e-9).ln(), n + 1));
    match n {
        0 => 0.0,
        _ => (sum / n as f64).exp(),
    }
}

/// Whether the GA goes on past the scouted pilot: where at least half the pilot pixels
/// predict a gain above the winning margin. One pixel alone (an outlier, or a small region)
/// does not pay for evolving the whole image. (Without the gate there is no pilot, and it
/// does not pay.)
pub(super) fn pilot_pays(waves: &Waves) -> bool {
    let plan_for = waves.context.plan_for;
    let paying = (waves.done.iter().flatten())
        .filter(|(p, _)| p.pays(plan_for))
        .count();
    2 * paying >= waves.pilot.max(1)
}

#[cfg(test)]
mod tests {
    use super::geometric_mean_gain;

    #[test]
    fn pilot_gain_is_the_geometric_mean_of_finite_gains() {
        let g = geometric_mean_gain([2.0, 8.0, f64::NAN, f64::INFINITY].into_iter());
        assert!((g - 4.0).abs() < 1e-12, "{g}");
        // The arithmetic mean (5) is not it; a gain of 0 pulls it to nearly 0.
        assert!((geometric_mean_gain([2.0, 8.0, 0.0].into_iter())) < 1e-2);
        assert_eq!(geometric_mean_gain(std::iter::empty()), 0.0);
        assert_eq!(geometric_mean_gain([f64::NAN].into_iter()), 0.0);
    }
}
