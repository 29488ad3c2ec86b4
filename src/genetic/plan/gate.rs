//! The gate: the pilot that decides whether the GA goes on, a GA pixel's trial of the
//! evolved estimator against `pt` ([`Trial`], from [`Moments`] of each), and its margins.

use super::super::test_paths::TestPaths;
use super::super::{fitness, ChannelWeights};
use super::baseline::Origin;
use super::pixel::{Evolved, GaRun, PixelContext};
use super::stages::PlanError;
use super::waves::{Job, Waves};
use super::PlanFor;
use crate::film::pixel_sample;
use crate::guiding::Guide;
use crate::path::generator::Nee;
use crate::path::mixture::{Mixture, MixtureScratch};
use crate::path::{camera_sample, RayCounts, SceneView};
use crate::sampling::{derived_seed, sample_variance, Stream};
use glam::DVec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};

crate::settings_table! {
    /// The gate's settings, table `[gate]`.
    #[derive(Clone, Copy, Debug, PartialEq)]
    pub struct GateConfig {
        table: "gate",
        heading: "Gate (--method ga, ga-pt)",
        settings: {
            /// A pilot of the GA predicts whether it pays, and each pixel renders with its
            /// evolved mixture only where it is predicted to beat pt (see docs/methods.md, "the
            /// gate"); `false` is the paper's method everywhere.
            #[negation = "no_gate"]
            pub gate: bool = true,
        },
    }
}

/// Samples of `pt` (and of the guided path tracer) with which the gate measures their
/// variance at a GA pixel.
pub const GATE_SAMPLES: u32 = 2048;
/// Samples of the mixture estimator with which the gate counts its cost.
pub const COST_SAMPLES: u32 = 256;
/// The gate's thresholds on a trial's predicted gain: `(lose, win)`. The GA goes on past
/// the pilot only if at least half the pilot pixels predict a gain above `win`; a GA pixel
/// prefers `pt` where it predicts one below `lose`.
///
/// The guided path tracer keeps `pt`'s next-event estimation and its BRDF sampling (at the
/// defensive weight), so it rarely loses much, while its 2048-sample trial is noisy (fig5:
/// sending every pixel below 1.25 to `pt` lost 20 % relMSE against no gate): it must win
/// by 1.25 and is dropped below 0.8. The mixture estimator's prediction is the less certain
/// (fig5, 9 GA pixels against 200 000-sample variances: within a factor 2 either way), its
/// variance grows faster away from the GA pixel and can exceed `pt`'s many times: it must
/// win by 2 everywhere.
pub fn gate_margins(plan_for: PlanFor) -> (f64, f64) {
    match plan_for {
        PlanFor::Guide => (0.8, 1.25),
        PlanFor::Mixture => (2.0, 2.0),
    }
}
/// GA pixels evolved before the gate decides whether to evolve the others.
pub const PILOT_PIXELS: usize = 8;
/// The pilot evolves for `1 / PILOT_SHARE` of the generations before its trial decides: a
/// scene where the GA cannot pay costs a quarter of a full pilot (cbox, 2 s budgets: the
/// full pilot took a third of the time). Where the pilot pays, its pixels go on from their
/// best individual for the remaining generations.
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
/// cannot (cbox, `ga`: the GA phase 0.16 -> 0.12 s; `ga-pt`, 8 spp, three runs each: fig1
/// 0.092 -> 0.070–0.073 s, 6 of 8 pilot pixels evolved, cbox 0.066 -> 0.050–0.064 s). The
/// image is the same bit for bit. Which pixels that skips depends on the
/// threads' timing, so such a pilot that fails leaves the whole image to `pt` or the spatial
/// guide (see
/// `Plan::closed`), whichever of its pixels ran. With a store (learning kept between
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

/// One estimator's samples at a pixel, per sample: mean and variance under the pixel's
/// [`ChannelWeights`] (`√(Σ_c w_c mean_c²)` and `Σ_c w_c Var_c`), and the cost
/// ([`RayCounts::cost`]).
#[derive(Clone, Copy, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct Moments {
    pub mean: f64,
    pub variance: f64,
    pub cost: f64,
    /// The standard error of `variance` over `variance` (0 where not measured): from the
    /// samples' fourth central moment, `√((μ₄ − σ⁴) / n) / σ²` per channel.
    #[serde(default)]
    pub variance_error: f64,
}

impl Moments {
    /// `1 / (variance × cost)`; infinite without variance.
    fn efficiency(&self) -> f64 {
        1.0 / (self.variance * self.cost)
    }
}

/// The gate's comparison at a GA pixel.
#[derive(Clone, Copy, Debug, serde::Serialize, serde::Deserialize)]
pub struct Trial {
    pub pt: Moments,
    pub evolved: Moments,
    /// `evolved`'s efficiency over `pt`'s; 0 where neither has variance (nothing to gain).
    pub gain: f64,
}

impl Trial {
    /// The gain one standard error below its estimate, on a log scale: `gain · e^(−ε)`, `ε`
    /// the two variances' relative standard errors added in quadrature
    /// ([`Moments::variance_error`]).
    ///
    /// A guide's pilot counts this against the winning margin. Its 2048-sample variances are
    /// heavy-tailed where rare paths carry the light: glossy's pilot pixels' gains range
    /// from 0.04 to 55 on one seed, with relative standard errors up to 0.9, and half of
    /// them passed 1.25 on five seeds of twelve (401–412), where the GA then lost to `pg`
    /// (1.08–1.18 × its relMSE at 2 s). One standard error below, glossy's pilot passes on
    /// none of the twelve and fig5's on all twelve, as before (two below: ten).
    pub fn cautious_gain(&self) -> f64 {
        let error = self.pt.variance_error.hypot(self.evolved.variance_error);
        self.gain * (-error).exp()
    }
}

/// Where a trial samples: the scene, the pixel, its [`ChannelWeights`], the bounce limit and
/// the user's seed (from which each estimator's stream is derived).
struct TrialAt<'a> {
    view: &'a SceneView<'a>,
    at: (u32, u32),
    weights: ChannelWeights,
    max_bounces: u32,
    seed: u64,
}

/// One estimator's samples at the trial's pixel: `n` samples of `pt`, guided by the guide
/// when given, or of the mixture's estimator (eq. 8) when given, from `stream`'s random
/// streams.
fn sample_moments(
    trial: &TrialAt,
    (stream, n): (Stream, u32),
    (mixture, guide): (Option<&Mixture>, Option<&Guide>),
    counts: &mut RayCounts,
) -> Moments {
    let &TrialAt {
        view,
        at: (x, y),
        weights,
        max_bounces,
        seed,
    } = trial;
    let camera = &view.scene.camera;
    let seed = derived_seed(seed, stream.tag());
    let mut scratch = MixtureScratch::default();
    let mut c = RayCounts::default();
    let (mut sum, mut sum_sq) = (DVec3::ZERO, DVec3::ZERO);
    let mut values = Vec::with_capacity(n as usize);
    for s in 0..n {
        let (ray, mut rng) = pixel_sample(camera, seed, (x, y), s as u64);
        let value = camera_sample(
            view,
            &ray,
            max_bounces,
            (mixture, guide),
            &mut rng,
            &mut c,
            &mut scratch,
        );
        sum += value;
        sum_sq += value * value;
        values.push(value);
    }
    counts.add(c);
    let n = n as f64;
    let mean = sum / n;
    let variance = sample_variance(sum, sum_sq, n).max(DVec3::ZERO);
    let weighted = weights.weigh(variance);
    Moments {
        mean: weights.weigh(mean * mean).sqrt(),
        variance: weighted,
        cost: c.cost() / n,
        variance_error: variance_error(&values, mean, weights, weighted),
    }
}

/// The standard error of the weighted sample variance `weighted` of `values` (mean `mean`)
/// over `weighted`: per channel `√((μ₄ − σ⁴) / n)`, summed with the channel weights as if
/// the channels' errors were fully correlated (they are nearly: the same paths carry all
/// three). 0 where there is no variance.
fn variance_error(values: &[DVec3], mean: DVec3, weights: ChannelWeights, weighted: f64) -> f64 {
    if weighted <= 0.0 || values.is_empty() {
        return 0.0;
    }
    let n = values.len() as f64;
    let (mut m2, mut m4) = (DVec3::ZERO, DVec3::ZERO);
    for v in values {
        let d2 = (*v - mean) * (*v - mean);
        m2 += d2;
        m4 += d2 * d2;
    }
    let (m2, m4) = (m2 / n, m4 / n);
    let per_channel = ((m4 - m2 * m2).max(DVec3::ZERO) / n)
        .to_array()
        .map(f64::sqrt);
    weights.weigh(DVec3::from_array(per_channel)) / weighted
}

/// The gate's comparison at `(x, y)`, under the pixel's channel `weights`, of `mixture`'s
/// estimator for the plan's [`PlanFor`] with `pt`.
///
/// `pt`'s and the guided path tracer's variances come from `GATE_SAMPLES` samples each.
/// The mixture estimator's cannot: its variance hides in rare paths where the mixture's
/// density is far below `srt`'s (down to the defensive weight), which a few hundred of its
/// own samples mostly miss (fig5: the median 512-sample variance is 2–7× below the true
/// one). Its second moment is therefore eq. 10 on fresh `srt` test paths, which sample
/// exactly those paths at `srt`'s rate; its cost comes from `COST_SAMPLES` samples.
pub(super) fn run_trial(
    context: &PixelContext,
    ((x, y), weights): ((u32, u32), ChannelWeights),
    mixture: &Mixture,
    counts: &mut RayCounts,
) -> Trial {
    let trial = TrialAt {
        view: context.view,
        at: (x, y),
        weights,
        max_bounces: context.max_bounces,
        seed: context.seed,
    };
    let pt = sample_moments(&trial, (Stream::GatePt, GATE_SAMPLES), (None, None), counts);
    let evolved = match context.plan_for {
        PlanFor::Guide => {
            let guide = Guide::new(mixture);
            let g = Some(&guide);
            sample_moments(&trial, (Stream::Gate, GATE_SAMPLES), (None, g), counts)
        }
        PlanFor::Mixture => mixture_moments(context, &trial, mixture, counts),
    };
    let gain = if pt.variance > 0.0 {
        evolved.efficiency() / pt.efficiency()
    } else {
        0.0
    };
    Trial { pt, evolved, gain }
}

/// The mixture estimator's moments in a trial: its cost from `COST_SAMPLES` of its samples,
/// its variance from eq. 10 on fresh `srt` test paths (see [`run_trial`]). With next-event
/// estimation at every vertex a sample sums many contributions, whose covariances eq. 10
/// (a sum over contributions) leaves out, so that `V − mean²` can fall below the variance,
/// even below 0: there the variance of the `COST_SAMPLES` samples is the floor.
fn mixture_moments(
    context: &PixelContext,
    trial: &TrialAt,
    mixture: &Mixture,
    counts: &mut RayCounts,
) -> Moments {
    let m = Some(mixture);
    let cost = sample_moments(trial, (Stream::Gate, COST_SAMPLES), (m, None), counts);
    let (view, ga) = (context.view, context.ga);
    let (mut check, c) = TestPaths::sample_until(
        view,
        context.srt,
        trial.at,
        (ga.test_paths, ga.max_light_paths),
        trial.max_bounces,
        derived_seed(trial.seed, Stream::Check.tag()),
    );
    counts.add(c);
    check.weigh(trial.weights);
    let mean = check.mean();
    let variance = (fitness::second_moment(view, &check, mixture) - mean * mean).max(0.0);
    let floor = match mixture.nee {
        Nee::Every => cost.variance,
        Nee::End => 0.0,
    };
    Moments {
        mean,
        variance: variance.max(floor),
        cost: cost.cost,
        variance_error: 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::{geometric_mean_gain, variance_error, Moments, Trial};
    use crate::genetic::ChannelWeights;
    use glam::DVec3;

    #[test]
    fn a_variance_from_heavy_tailed_samples_has_a_large_error() {
        let weights = ChannelWeights::EQUAL;
        let error = |values: &[f64]| {
            let values: Vec<DVec3> = values.iter().map(|&v| DVec3::splat(v)).collect();
            let n = values.len() as f64;
            let mean = values.iter().sum::<DVec3>() / n;
            let var = values
                .iter()
                .map(|v| (*v - mean) * (*v - mean))
                .sum::<DVec3>()
                / n;
            variance_error(&values, mean, weights, weights.weigh(var))
        };
        // ±1 alternately: the sample variance is exact (μ₄ = σ⁴).
        let even: Vec<f64> = (0..1000)
            .map(|i| if i % 2 == 0 { 1.0 } else { -1.0 })
            .collect();
        assert!(error(&even) < 1e-9, "{}", error(&even));
        // One large value among zeros: the variance rests on it alone, error ≈ 1.
        let mut rare = vec![0.0; 1000];
        rare[7] = 100.0;
        let e = error(&rare);
        assert!((0.9..1.1).contains(&e), "{e}");
        assert_eq!(error(&[3.0, 3.0]), 0.0);
    }

    #[test]
    fn a_cautious_gain_falls_with_the_variances_errors() {
        let moments = |variance_error| Moments {
            mean: 1.0,
            variance: 1.0,
            cost: 1.0,
            variance_error,
        };
        let trial = |e_pt, e_ev| Trial {
            pt: moments(e_pt),
            evolved: moments(e_ev),
            gain: 2.0,
        };
        assert_eq!(trial(0.0, 0.0).cautious_gain(), 2.0);
        let noisy = trial(0.3, 0.4).cautious_gain();
        assert!((noisy - 2.0 * (-0.5f64).exp()).abs() < 1e-12, "{noisy}");
        // The same gain with large errors no longer clears a guide's winning margin.
        assert!(noisy < 1.25);
    }

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
