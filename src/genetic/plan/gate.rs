//! The gate: a GA pixel's trial of the evolved estimator against `pt` ([`Trial`], from
//! [`Moments`] of each). The pilot that decides whether the GA goes on is `pilot.rs`'s; the
//! trial's data and the gate's margins are `types.rs`'s.

use super::super::test_paths::TestPaths;
use super::super::{fitness, ChannelWeights};
use super::context::PixelContext;
use super::types::{Moments, PlanFor, Trial};
use crate::film::sample_pixel;
use crate::guiding::Guide;
use crate::path::generator::Nee;
use crate::path::mixture::{Mixture, MixtureScratch};
use crate::path::{camera_sample, RayCounts, SceneView};
use crate::sampling::{derived_seed, sample_variance, Stream};
use glam::DVec3;
use std::ops::ControlFlow;

/// Samples of `pt` (and of the guided path tracer) with which the gate measures their
/// variance at a GA pixel.
pub const GATE_SAMPLES: u32 = 2048;
/// Samples of the mixture estimator with which the gate counts its cost.
pub const COST_SAMPLES: u32 = 256;
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
    sample_pixel(camera, seed, (x, y), 0..u64::from(n), |ray, rng| {
        let value = camera_sample(
            view,
            ray,
            max_bounces,
            (mixture, guide),
            rng,
            &mut c,
            &mut scratch,
        );
        sum += value;
        sum_sq += value * value;
        values.push(value);
        ControlFlow::Continue(())
    });
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
/// own samples mostly miss, so they underestimate it (reports/README.md, "Measurements
/// formerly in code comments (2026-12-07)", `run_trial`). Its second moment is therefore
/// eq. 10 on fresh `srt` test paths, which sample
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
    use super::super::types::{Moments, Trial};
    use super::variance_error;
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
}
