//! How every pixel renders from the GA pixels: the interpolation weights of its nearest GA
//! pixels and `pt` points, and the gate's choice between their mixtures and `pt`.

use super::super::nearest::PointGrid;
use super::Plan;
use crate::path::mixture::Mixture;

impl Plan {
    /// The GA pixels nearest to `(x, y)` (up to `neighbours`) and their weights, into `out`:
    /// inverse squared distance, normalised to sum 1; a GA pixel itself takes weight 1.
    /// Indices from `pixels.len()` on are `fallback_points`.
    pub fn interpolation(&self, x: u32, y: u32, out: &mut Vec<(f64, usize)>) {
        let index = self.index.get_or_init(|| {
            let points = self.pixels.iter().map(|p| (p.x, p.y));
            PointGrid::new(
                points.chain(self.fallback_points.iter().copied()).collect(),
                self.width,
                self.height,
            )
        });
        // The `neighbours` smallest distances, sorted, ties by index.
        index.nearest(x, y, self.neighbours, out);
        if let Some(&(_, i)) = out.first().filter(|(d2, _)| *d2 == 0.0) {
            out.clear();
            out.push((1.0, i));
            return;
        }
        let mut total = 0.0;
        for (w, _) in out.iter_mut() {
            *w = 1.0 / *w;
            total += *w;
        }
        if !self.unnormalised {
            out.iter_mut().for_each(|(w, _)| *w /= total);
        }
    }

    /// Whether interpolation point `i` (see [`Self::interpolation`]) prefers `pt`: a
    /// `fallback_points` entry, or a GA pixel that kept `srt` or whose gate trial predicts
    /// no gain.
    fn prefers_pt(&self, i: usize) -> bool {
        self.pixels
            .get(i)
            .is_none_or(|p| p.prefers_pt(self.plan_for))
    }

    /// How pixel `(x, y)` renders: `None` with `pt`, else with this mixture (`ga`) or guided
    /// by it (`ga-pt`). Without the gate: the union of the nearest points' mixtures, each
    /// with its interpolation weight, `srt` at a fallback point. With it: `pt` where the points preferring `pt` hold at
    /// least half the interpolation weight, else the union of the other points' mixtures,
    /// their weights renormalised. The choice depends on the plan alone, never on the
    /// render's samples, so every pixel's estimator stays unbiased.
    pub fn local(&self, x: u32, y: u32) -> Option<Mixture> {
        let mut weights = Vec::with_capacity(self.neighbours);
        let mut parts = Vec::with_capacity(self.neighbours);
        self.neighbour_mixtures(x, y, &mut weights, &mut parts)
            .then(|| Mixture::union(&parts))
    }

    /// [`Self::local`] without building the union: `false` for `pt`, else `true` with the
    /// weighted mixtures of the union in `parts` (`srt` alone where there is no point to
    /// interpolate). `weights` is scratch. The renderer passes the same buffers for every
    /// pixel, so that this allocates nothing.
    pub fn neighbour_mixtures<'a>(
        &'a self,
        x: u32,
        y: u32,
        weights: &mut Vec<(f64, usize)>,
        parts: &mut Vec<(f64, &'a Mixture)>,
    ) -> bool {
        parts.clear();
        if self.closed {
            return false;
        }
        self.interpolation(x, y, weights);
        if self.gate {
            let total: f64 = weights.iter().map(|w| w.0).sum();
            let pt: f64 = weights
                .iter()
                .filter(|w| self.prefers_pt(w.1))
                .map(|w| w.0)
                .sum();
            if weights.is_empty() || pt >= 0.5 * total {
                return false;
            }
            weights.retain(|w| !self.prefers_pt(w.1));
            if !self.unnormalised {
                weights.iter_mut().for_each(|w| w.0 /= total - pt);
            }
        }
        if weights.is_empty() {
            parts.push((1.0, &self.srt));
        }
        // Without the gate a fallback point lends `srt`; with it none is left here.
        parts.extend(
            (weights.iter())
                .map(|&(w, i)| (w, self.pixels.get(i).map_or(&self.srt, |p| &p.mixture))),
        );
        true
    }
}

#[cfg(test)]
mod tests {
    use super::super::{GaPixel, Moments, Origin, PlanFor, PlanStats, Trial};
    use super::*;
    use crate::film::PixelSums;
    use crate::path::generator::PathGenerator;
    use crate::sampling::light_point::LightPointSampler;
    use crate::scene::SceneAnalysis;
    use glam::DVec3;
    use std::sync::OnceLock;

    fn mixture(absorption: f64) -> Mixture {
        let light = LightPointSampler::uniform(0);
        Mixture::new(vec![PathGenerator::srt(3, absorption, light)], vec![1.0])
    }

    fn pixel(x: u32, gain: Option<f64>) -> GaPixel {
        let moments = Moments::default();
        GaPixel {
            x,
            y: 0,
            origin: Origin::Grid,
            mixture: mixture(0.25),
            v_srt: 1.0,
            v_best: 0.5,
            v_evolved: 0.5,
            kept_srt: gain.is_none(),
            trial: gain.map(|gain| Trial {
                pt: moments,
                evolved: moments,
                gain,
            }),
            best: None,
            warm: false,
            test_paths: 0,
            light_paths: 0,
            steps: 1,
            history: Vec::new(),
            individual_evaluations: 0,
            generator_evaluations: 0,
            test_path_seconds: 0.0,
            ga_seconds: 0.0,
        }
    }

    /// GA pixels at x = 0 (predicted gain 3), 10 (gain 0.5) and 20 (kept srt), a `pt`
    /// point at x = 30, two neighbours per pixel.
    fn plan(gate: bool) -> Plan {
        Plan {
            width: 40,
            height: 1,
            pixels: vec![pixel(0, Some(3.0)), pixel(10, Some(0.5)), pixel(20, None)],
            fallback_points: if gate { vec![(30, 0)] } else { Vec::new() },
            gate,
            closed: false,
            plan_for: PlanFor::Guide,
            srt: mixture(0.5),
            neighbours: 2,
            analysis: SceneAnalysis {
                triangles: 0,
                diffuse_triangles: 0,
                glossy_triangles: 0,
                mirror_triangles: 0,
                emitter_triangles: 0,
                emitter_area: 0.0,
                smallest_emitter_area: 0.0,
                extent: 1.0,
            },
            unnormalised: false,
            stats: PlanStats::default(),
            baseline: PixelSums::default(),
            index: OnceLock::new(),
        }
    }

    #[test]
    fn the_gate_renders_with_pt_where_the_neighbours_predict_a_loss() {
        let gated = plan(true);
        // At and next to the paying GA pixel: its mixture alone (the other neighbour, which
        // prefers pt, holds less than half the weight and is left out).
        for x in [0, 1, 4] {
            let m = gated.local(x, 0).expect("evolved mixture near x = 0");
            assert_eq!(m.generators.len(), 1, "x = {x}");
            assert!(
                (m.weights[0] - 1.0).abs() < 1e-12,
                "renormalised at x = {x}"
            );
            assert_eq!(m.generators[0].steps[0].absorption, 0.25);
        }
        // Nearer the losing pixel, the srt-only one and the pt point: pt.
        for x in [6, 10, 15, 20, 25, 30, 39] {
            assert!(gated.local(x, 0).is_none(), "x = {x}");
        }
        // A pixel the trial says loses is a loss whatever the estimator's margin.
        assert!(!gated.pixels[1].pays(PlanFor::Guide) && !gated.pixels[1].pays(PlanFor::Mixture));
        assert!(gated.pixels[0].pays(PlanFor::Mixture));
        // Without the gate every pixel renders with the interpolated union (the paper).
        let paper = plan(false);
        for x in 0..40 {
            let m = paper.local(x, 0).expect("a mixture everywhere");
            let total: f64 = m.weights.iter().sum();
            assert!(
                (total - 1.0).abs() < 1e-12,
                "x = {x}: weights sum to {total}"
            );
        }
        // Without the gate a fallback point (a low-variance cell's pixel) lends `srt`
        // (absorption 0.5 here; the GA pixels' mixtures absorb 0.25): alone at the point,
        // with its interpolation weight between it and the GA pixel at x = 20.
        let mut fallback = plan(false);
        fallback.fallback_points.push((30, 0));
        let weights = |plan: &Plan, x: u32| {
            let m = plan.local(x, 0).expect("a mixture everywhere");
            let at = |a: f64| m.generators.iter().position(|g| g.steps[0].absorption == a);
            (
                at(0.5).map(|i| m.weights[i]),
                at(0.25).map(|i| m.weights[i]),
            )
        };
        assert_eq!(weights(&fallback, 30), (Some(1.0), None));
        let (srt, evolved) = weights(&fallback, 27);
        let expected = (1.0 / 9.0) / (1.0 / 9.0 + 1.0 / 49.0);
        assert!((srt.expect("srt near x = 30") - expected).abs() < 1e-12);
        assert!((evolved.expect("the GA pixel's") - (1.0 - expected)).abs() < 1e-12);
        // The same plan without the fallback point: the GA pixels' mixtures alone there.
        for x in [27, 30] {
            let (srt, evolved) = weights(&paper, x);
            assert!(srt.is_none() && (evolved.expect("evolved") - 1.0).abs() < 1e-12);
        }
        // The fault injection still reaches the gated path: unnormalised weights show.
        let mut wrong = plan(true);
        wrong.unnormalised = true;
        let m = wrong.local(4, 0).expect("evolved mixture");
        assert!((m.weights.iter().sum::<f64>() - 1.0).abs() > 1e-3);
    }

    /// `ga`'s image keeps the baseline's samples where the median `V_srt / V_best` is at
    /// most the keep ratio and `--spp` holds them; `ga-pt`'s never.
    #[test]
    fn the_baseline_stays_where_srt_is_near_the_evolved_mixtures() {
        // V_srt / V_best of 1.5, 3 and 1: median 1.5.
        let with = |plan_for, spp, ratio| {
            let mut p = plan(false);
            p.plan_for = plan_for;
            for (px, v_best) in p.pixels.iter_mut().zip([2.0 / 3.0, 1.0 / 3.0, 1.0]) {
                px.v_best = v_best;
            }
            p.baseline = PixelSums {
                spp: 4,
                sum: vec![DVec3::ONE; 40],
                sum_sq: vec![DVec3::ONE; 40],
            };
            p.settle_baseline(spp, ratio);
            (p.baseline().map(|b| b.spp), p.stats.baseline_kept_spp)
        };
        assert_eq!(with(PlanFor::Mixture, 8, 2.0), (Some(4), 4));
        assert_eq!(with(PlanFor::Mixture, 4, 1.5), (Some(4), 4));
        // The median above the ratio, fewer samples than the baseline's, a guide's plan.
        assert_eq!(with(PlanFor::Mixture, 8, 1.4), (None, 0));
        assert_eq!(with(PlanFor::Mixture, 3, 2.0), (None, 0));
        assert_eq!(with(PlanFor::Guide, 8, f64::INFINITY), (None, 0));
    }
}
