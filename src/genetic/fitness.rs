//! Fitness (paper eq. 10–11). For an individual with mixture density `pdf`, eq. 10
//!
//! ```text
//! V(ind) = (1/M) Σ_i F(X_i)² / (pdf(X_i) · q(X_i))
//! ```
//!
//! estimates `σ² + Φ²`, the second moment of the estimator of eq. 8, on the test paths
//! `X_i ~ q`; eq. 11 turns it into `fitness = 1 − V/V_max` over a generation.
//!
//! Evaluation is cheap because each generator's densities on the test paths are cached, keyed
//! by gene id (copies share the id): an individual then costs `(S + 1)·M` multiply-adds, and
//! only generators that are new in a generation are evaluated against the paths.

use super::individual::Individual;
use super::test_paths::TestPaths;
use crate::path::mixture::Mixture;
use crate::path::SceneView;
use std::collections::HashMap;

/// Eq. 10 for any mixture, without the cache.
pub fn second_moment(view: &SceneView, paths: &TestPaths, mixture: &Mixture) -> f64 {
    let mut pdf = vec![0.0; paths.len()];
    let mut one = vec![0.0; paths.len()];
    for (g, &w) in mixture.generators.iter().zip(&mixture.weights) {
        paths.generator_pdfs(view, g, &mut one);
        for (p, o) in pdf.iter_mut().zip(&one) {
            *p += w * o;
        }
    }
    moment(paths, &pdf)
}

/// `(1/M) Σ F²/(q·pdf)`; infinite where a light-carrying test path has `pdf = 0`.
fn moment(paths: &TestPaths, pdf: &[f64]) -> f64 {
    if paths.sampled == 0 {
        return 0.0;
    }
    let mut sum = 0.0;
    for (f2q, p) in paths.f2_over_q.iter().zip(pdf) {
        if *p <= 0.0 {
            return f64::INFINITY;
        }
        sum += f2q / p;
    }
    sum / paths.sampled as f64
}

/// Eq. 11 over one generation: `1 − V/V_max`, `V_max` over the finite values; an individual
/// with infinite `V` gets 0, and so does everyone when `V_max` is 0 (no information).
pub fn fitness(v: &[f64], out: &mut Vec<f64>) {
    let v_max = v
        .iter()
        .copied()
        .filter(|x| x.is_finite())
        .fold(0.0, f64::max);
    out.clear();
    out.extend(v.iter().map(|&x| {
        if v_max > 0.0 && x.is_finite() {
            1.0 - x / v_max
        } else {
            0.0
        }
    }));
}

/// Evaluates eq. 10 for whole generations, caching every generator's densities.
#[derive(Default)]
pub struct Evaluator {
    /// Gene id → slot of `densities`.
    slot_of: HashMap<u64, usize>,
    densities: Vec<Vec<f64>>,
    /// Slots whose gene left the population, ready for reuse.
    free: Vec<usize>,
    /// Per slot: referenced by the generation being evaluated.
    used: Vec<bool>,
    mixture_pdf: Vec<f64>,
    /// Generators evaluated against the test paths (cache misses), for statistics.
    pub generator_evaluations: u64,
    /// Individuals evaluated.
    pub individual_evaluations: u64,
}

impl Evaluator {
    /// `V` (eq. 10) of every individual of `population`, into `v`.
    pub fn evaluate(
        &mut self,
        view: &SceneView,
        paths: &TestPaths,
        population: &[Individual],
        v: &mut Vec<f64>,
    ) {
        // Forget generators no longer in the population, keeping their buffers.
        self.used.iter_mut().for_each(|u| *u = false);
        for ind in population {
            for gene in &ind.genes {
                if let Some(&slot) = self.slot_of.get(&gene.id) {
                    self.used[slot] = true;
                }
            }
        }
        let used = &self.used;
        let free = &mut self.free;
        self.slot_of.retain(|_, slot| {
            if !used[*slot] {
                free.push(*slot);
            }
            used[*slot]
        });
        // Evaluate the new ones.
        for ind in population {
            for gene in &ind.genes {
                if self.slot_of.contains_key(&gene.id) {
                    continue;
                }
                let slot = match self.free.pop() {
                    Some(slot) => slot,
                    None => {
                        self.densities.push(vec![0.0; paths.len()]);
                        self.used.push(true);
                        self.densities.len() - 1
                    }
                };
                self.used[slot] = true;
                paths.generator_pdfs(view, &gene.generator, &mut self.densities[slot]);
                self.slot_of.insert(gene.id, slot);
                self.generator_evaluations += 1;
            }
        }
        // S + 1 multiply-adds per path and individual.
        self.mixture_pdf.resize(paths.len(), 0.0);
        v.clear();
        for ind in population {
            self.mixture_pdf.iter_mut().for_each(|p| *p = 0.0);
            for (gene, &w) in ind.genes.iter().zip(&ind.weights) {
                let densities = &self.densities[self.slot_of[&gene.id]];
                for (p, d) in self.mixture_pdf.iter_mut().zip(densities) {
                    *p += w * d;
                }
            }
            v.push(moment(paths, &self.mixture_pdf));
        }
        self.individual_evaluations += population.len() as u64;
    }
}
