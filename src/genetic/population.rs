//! The generation loop (paper §4): roulette-wheel parent selection on the fitness of eq. 11,
//! crossover and mutation of the offspring, and elitism (the best `E` individuals go on
//! unchanged, so the best `V` never increases). Deterministic given the random generator.

use super::fitness::{fitness, Evaluator, Steps};
use super::individual::{GenePool, Individual};
use super::operators::{crossover, mutate};
use super::test_paths::TestPaths;
use super::GaConfig;
use crate::path::SceneView;
use crate::sampling::Rng;
use rand::Rng as _;

/// Best and mean `V` (eq. 10) of one generation; the mean over the finite values.
#[derive(Clone, Copy, Debug, serde::Serialize, serde::Deserialize)]
pub struct GenerationStats {
    pub best: f64,
    pub mean: f64,
}

/// What [`evolve`] found.
#[derive(Clone, Debug)]
pub struct Evolution {
    /// The individual with the smallest `V` in the last generation.
    pub best: Individual,
    pub best_v: f64,
    pub history: Vec<GenerationStats>,
    /// Individuals and generators evaluated (the latter: cache misses).
    pub individual_evaluations: u64,
    pub generator_evaluations: u64,
}

/// Index drawn with probability proportional to `fitness` (uniformly when all are 0).
fn roulette(fitness: &[f64], rng: &mut Rng) -> usize {
    let total: f64 = fitness.iter().sum();
    if total.is_nan() || total <= 0.0 {
        return rng.random_range(0..fitness.len());
    }
    let target = rng.random::<f64>() * total;
    let mut acc = 0.0;
    for (i, f) in fitness.iter().enumerate() {
        acc += f;
        if target < acc {
            return i;
        }
    }
    fitness.len() - 1
}

/// With `GaConfig::convex_weights`: individuals per generation whose weights are optimised,
/// and the steps each gets: at most 20, ending at the first that lowers `V` by less than
/// 10⁻⁴ of it. The elite go on unchanged and are optimised again in every generation, where
/// a step's gain is far below what `M` test paths can tell apart (`V`'s relative standard
/// error is of the order of 1/√M), yet a tighter bound ran all 20 steps at a large share of
/// the GA's instructions (reports/README.md, "Measurements formerly in code comments
/// (2026-12-07)").
const CONVEX_ELITE: usize = 4;
const CONVEX_STEPS: Steps = Steps {
    iterations: 20,
    tolerance: 1e-4,
};

/// Indices of `v` sorted by increasing `V` (best first); ties by index, so deterministic.
fn ranking(v: &[f64], order: &mut Vec<usize>) {
    order.clear();
    order.extend(0..v.len());
    order.sort_by(|&a, &b| v[a].total_cmp(&v[b]).then(a.cmp(&b)));
}

/// Runs the genetic algorithm on the test paths of one pixel.
pub fn evolve(config: &GaConfig, paths: &TestPaths, view: &SceneView, rng: &mut Rng) -> Evolution {
    evolve_from(config, (paths, paths), view, rng, &[])
}

/// [`evolve`] with `seeds` (individuals evolved elsewhere, e.g. at neighbouring pixels) in
/// the first generation, the rest random: a warm start. The data-driven anchors and patches
/// are placed from `placement`'s light-carrying paths and every `V` is measured on `paths`:
/// two independent sets of test paths (see [`super::GaConfig::held_out`]), or the same set
/// twice.
pub fn evolve_from(
    config: &GaConfig,
    (placement, paths): (&TestPaths, &TestPaths),
    view: &SceneView,
    rng: &mut Rng,
    seeds: &[Individual],
) -> Evolution {
    let n = config.population.max(1);
    let mut pool = GenePool::new(view.scene, paths.max_bounces, config).with_test_paths(placement);
    let mut population: Vec<Individual> = seeds
        .iter()
        .take(n)
        .map(|s| pool.adopt(s, config))
        .collect();
    while population.len() < n {
        population.push(pool.random_individual(config, rng));
    }
    let mut next = Vec::with_capacity(n);
    let mut evaluator = Evaluator::default();
    let (mut v, mut fit, mut order) = (Vec::new(), Vec::new(), Vec::new());
    let mut history = Vec::with_capacity(config.generations);
    for generation in 0..config.generations.max(1) {
        evaluator.evaluate(view, paths, &population, &mut v);
        ranking(&v, &mut order);
        if config.convex_weights {
            // Lamarckian: the best individuals get their generators' optimal weights, which
            // their offspring inherit.
            for &i in order.iter().take(CONVEX_ELITE.min(n)) {
                if v[i].is_finite() {
                    v[i] = evaluator.optimise(
                        paths,
                        &mut population[i],
                        config.defensive_weight,
                        CONVEX_STEPS,
                    );
                }
            }
            ranking(&v, &mut order);
        }
        let (sum, count) = v
            .iter()
            .filter(|x| x.is_finite())
            .fold((0.0, 0usize), |(s, c), x| (s + x, c + 1));
        history.push(GenerationStats {
            best: v[order[0]],
            mean: sum / count.max(1) as f64,
        });
        if generation + 1 >= config.generations {
            break;
        }
        fitness(&v, &mut fit);
        next.clear();
        for &i in order.iter().take(config.elitism.min(n)) {
            next.push(population[i].clone());
        }
        while next.len() < n {
            let mut a = population[roulette(&fit, rng)].clone();
            let mut b = population[roulette(&fit, rng)].clone();
            if rng.random::<f64>() < config.p_cross {
                crossover(&mut a, &mut b, config, rng);
            }
            mutate(&mut a, &mut pool, config, rng);
            mutate(&mut b, &mut pool, config, rng);
            next.push(a);
            if next.len() < n {
                next.push(b);
            }
        }
        std::mem::swap(&mut population, &mut next);
    }
    let best = order[0];
    Evolution {
        best: population[best].clone(),
        best_v: v[best],
        history,
        individual_evaluations: evaluator.individual_evaluations,
        generator_evaluations: evaluator.generator_evaluations,
    }
}
