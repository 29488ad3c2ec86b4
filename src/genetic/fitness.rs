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
//! only generators that are new in a generation are evaluated against the paths; even these
//! read the densities of the steps and light samplers they share with generators before
//! them from a cache ([`Evaluator`]), and multiply them along the paths
//! ([`TestPaths::generator_pdfs_with`]).

use super::individual::{normalise_weights, Gene, Individual};
use super::test_paths::TestPaths;
use crate::path::generator::DirectionSampler;
use crate::path::mixture::Mixture;
use crate::path::SceneView;
use crate::sampling::light_point::LightPointSampler;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hash, Hasher};

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
    moment_of(&paths.f2_over_q, paths.sampled, pdf)
}

/// [`moment`] from the stored paths' `F²/q` and the number of paths sampled.
fn moment_of(f2_over_q: &[f64], sampled: usize, pdf: &[f64]) -> f64 {
    if sampled == 0 {
        return 0.0;
    }
    let mut sum = 0.0;
    for (f2q, p) in f2_over_q.iter().zip(pdf) {
        if *p <= 0.0 {
            return f64::INFINITY;
        }
        sum += f2q / p;
    }
    sum / sampled as f64
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

/// A multiply-rotate hash of 64-bit words (rustc's FxHash, with its final rotation), for the
/// [`Cache`]'s keys: a step key is twelve words, and the standard library's SipHash on them
/// showed in a GA plan's instruction count (reports/README.md, "Measurements formerly in
/// code comments (2026-12-07)"). The keys are the GA's own genes and parameters, never an
/// adversary's, so a keyed hash buys nothing here.
#[derive(Clone, Copy, Default)]
struct WordHasher(u64);

impl WordHasher {
    const K: u64 = 0xf135_7aea_2e62_a9c5;

    fn add(&mut self, word: u64) {
        self.0 = self.0.wrapping_add(word).wrapping_mul(Self::K);
    }
}

impl Hasher for WordHasher {
    fn write(&mut self, bytes: &[u8]) {
        let mut words = bytes.chunks_exact(8);
        for w in &mut words {
            self.add(u64::from_le_bytes(w.try_into().unwrap_or_default()));
        }
        let mut last = [0u8; 8];
        let rest = words.remainder();
        last[..rest.len()].copy_from_slice(rest);
        self.add(u64::from_le_bytes(last) ^ ((rest.len() as u64) << 59));
    }
    fn write_u64(&mut self, word: u64) {
        self.add(word);
    }
    fn write_usize(&mut self, word: usize) {
        self.add(word as u64);
    }
    fn finish(&self) -> u64 {
        // The multiply leaves the high bits mixed best; the table indexes with the low.
        self.0.rotate_left(26)
    }
}

/// Density vectors on the test paths, each under the key of what it is the densities of,
/// kept while the generation being evaluated uses that; a forgotten key's buffer is reused.
struct Cache<K> {
    slot_of: HashMap<K, usize, BuildHasherDefault<WordHasher>>,
    buffers: Vec<Vec<f64>>,
    /// Slots whose key left the population, ready for reuse.
    free: Vec<usize>,
    /// Per slot: used by the generation being evaluated.
    used: Vec<bool>,
}

impl<K> Default for Cache<K> {
    fn default() -> Self {
        Self {
            slot_of: HashMap::default(),
            buffers: Vec::new(),
            free: Vec::new(),
            used: Vec::new(),
        }
    }
}

impl<K: Hash + Eq> Cache<K> {
    /// Forgets every key not in `keys` (the generation's), keeping the buffers.
    fn keep_only<'a>(&mut self, keys: impl Iterator<Item = &'a K>)
    where
        K: 'a,
    {
        self.used.iter_mut().for_each(|u| *u = false);
        for key in keys {
            if let Some(&slot) = self.slot_of.get(key) {
                self.used[slot] = true;
            }
        }
        let (used, free) = (&self.used, &mut self.free);
        self.slot_of.retain(|_, slot| {
            if !used[*slot] {
                free.push(*slot);
            }
            used[*slot]
        });
    }

    /// The slot of `key`, its buffer filled by `fill` if it is new.
    fn slot(&mut self, key: K, fill: impl FnOnce(&mut Vec<f64>)) -> usize {
        if let Some(&slot) = self.slot_of.get(&key) {
            return slot;
        }
        let slot = self.free.pop().unwrap_or_else(|| {
            self.buffers.push(Vec::new());
            self.used.push(true);
            self.buffers.len() - 1
        });
        self.used[slot] = true;
        fill(&mut self.buffers[slot]);
        self.slot_of.insert(key, slot);
        slot
    }

    /// The buffer of a key of the generation.
    fn get(&self, key: &K) -> &[f64] {
        &self.buffers[self.slot_of[key]]
    }
}

/// A direction sampler at step `k` of a generator, by the bits of its parameters: every
/// generator with it there reads the same densities ([`TestPaths::step_pdfs`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
struct StepKey {
    k: usize,
    /// The variant, then its parameters' bits.
    sampler: [u64; 11],
}

impl StepKey {
    fn new(k: usize, sampler: &DirectionSampler) -> Self {
        let mut bits = [0u64; 11];
        let mut put = |variant: u64, values: &[f64]| {
            bits[0] = variant;
            for (b, v) in bits[1..].iter_mut().zip(values) {
                *b = v.to_bits();
            }
        };
        match sampler {
            DirectionSampler::Brdf => put(0, &[]),
            DirectionSampler::Anchor(a) => {
                let p = a.anchor;
                put(1, &[p.x, p.y, p.z, a.theta_c, a.alpha]);
            }
            DirectionSampler::Patch(p) => {
                let (c, u, v) = (p.center, p.half_u, p.half_v);
                put(2, &[c.x, c.y, c.z, u.x, u.y, u.z, v.x, v.y, v.z, p.alpha]);
            }
        }
        Self { k, sampler: bits }
    }

    /// The keys of `gene`'s first `steps` steps.
    fn of(gene: &Gene, steps: usize) -> impl Iterator<Item = Self> + '_ {
        let steps = gene.generator.steps.iter().take(steps).enumerate();
        steps.map(|(k, s)| Self::new(k, &s.sampler))
    }
}

/// A light-point sampler by the bits of its parameters: every generator with it reads the
/// same light densities ([`TestPaths::light_pdfs`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
struct LightKey([u64; 4]);

impl LightKey {
    fn new(gene: &Gene) -> Self {
        let LightPointSampler { region, beta } = gene.generator.light;
        let (prim, level, cell) = (region.prim, region.level, region.cell);
        Self([prim.into(), level.into(), cell.into(), beta.to_bits()])
    }
}

/// Evaluates eq. 10 for whole generations, caching every generator's densities (by gene id:
/// copies share the id), every step's direction densities and every light sampler's light
/// densities (by their parameters: a generator changed in its absorption, its light sampler
/// or one step reads the others' densities from the cache, which holds most of the new
/// generators' samplers: reports/README.md, "Measurements formerly in code comments
/// (2026-12-07)").
#[derive(Default)]
pub struct Evaluator {
    genes: Cache<u64>,
    steps: Cache<StepKey>,
    lights: Cache<LightKey>,
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
        let genes = || population.iter().flat_map(|ind| &ind.genes);
        let step_keys = |gene| StepKey::of(gene, paths.step_count());
        // Forget generators and steps no longer in the population, keeping their buffers.
        self.genes.keep_only(genes().map(|gene| &gene.id));
        let keys: Vec<StepKey> = genes().flat_map(step_keys).collect();
        self.steps.keep_only(keys.iter());
        let keys: Vec<LightKey> = genes().map(LightKey::new).collect();
        self.lights.keep_only(keys.iter());
        // Evaluate the new ones.
        for gene in genes() {
            if self.genes.slot_of.contains_key(&gene.id) {
                continue;
            }
            let g = &gene.generator;
            let mut slots = Vec::with_capacity(g.steps.len());
            for (k, key) in step_keys(gene).enumerate() {
                let fill = |out: &mut Vec<f64>| paths.step_pdfs(k, &g.steps[k].sampler, out);
                slots.push(self.steps.slot(key, fill));
            }
            let steps: Vec<&[f64]> = slots.iter().map(|&s| &self.steps.buffers[s][..]).collect();
            let fill = |out: &mut Vec<f64>| paths.light_pdfs(view, g, out);
            let lights = self.lights.slot(LightKey::new(gene), fill);
            let lights = &self.lights.buffers[lights];
            let fill = |out: &mut Vec<f64>| {
                out.resize(paths.len(), 0.0);
                paths.generator_pdfs_with(g, (&steps, lights), out);
            };
            self.genes.slot(gene.id, fill);
            self.generator_evaluations += 1;
        }
        // S + 1 multiply-adds per path and individual.
        self.mixture_pdf.resize(paths.len(), 0.0);
        v.clear();
        for ind in population {
            let densities: Vec<&[f64]> = ind.genes.iter().map(|g| self.genes.get(&g.id)).collect();
            mixture_pdf(&densities, &ind.weights, &mut self.mixture_pdf);
            v.push(moment(paths, &self.mixture_pdf));
        }
        self.individual_evaluations += population.len() as u64;
    }

    /// [`optimise_weights`] for `ind`, whose generators were evaluated by the last
    /// [`Self::evaluate`]; returns its new `V`.
    pub fn optimise(
        &self,
        paths: &TestPaths,
        ind: &mut Individual,
        defensive: f64,
        steps: Steps,
    ) -> f64 {
        let densities: Vec<&[f64]> = ind.genes.iter().map(|g| self.genes.get(&g.id)).collect();
        optimise_weights(
            (&paths.f2_over_q, paths.sampled),
            &densities,
            &mut ind.weights,
            defensive,
            steps,
        )
    }
}

/// When [`optimise_weights`] stops: after `iterations` steps, or after the first step that
/// lowers `V` by less than the share `tolerance` of it (that step is kept).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Steps {
    pub iterations: usize,
    pub tolerance: f64,
}

/// The mixture weights of fixed generators that minimise eq. 10 (beyond the paper).
///
/// `V(w) = (1/M) Σ_j c_j / Σ_i w_i d_ij`, with `c_j = F²/q` of light-carrying test path `j`
/// and `d_ij` the density of generator `i` there, is convex in `w` (a sum of `1/x` of
/// linear functions). Its gradient is `∂V/∂w_i = −g_i`, `g_i = (1/M) Σ_j c_j d_ij / p_j²`,
/// and `Σ_i w_i g_i = V`: at the optimum every component in use has `g_i = V`. Each
/// iteration is the multiplicative step `w_i ← w_i (g_i/V)^η` (mirror descent on the
/// simplex), renormalised with `w_0 ≥ defensive`, kept only where it lowers `V`; `η`
/// starts at 1 and halves on a failed step. `V` never increases, and components with
/// `g_i < V` (less useful than the mixture) lose weight geometrically.
///
/// `f2_over_q` and `sampled` are the test paths' ([`TestPaths`]), `densities[i]` generator
/// `i`'s densities on the stored paths (component 0 is the defensive one), `weights` a
/// feasible start, overwritten, `steps` when to stop. Returns the final `V`.
pub fn optimise_weights(
    (f2_over_q, sampled): (&[f64], usize),
    densities: &[&[f64]],
    weights: &mut [f64],
    defensive: f64,
    steps: Steps,
) -> f64 {
    let n = weights.len();
    assert_eq!(densities.len(), n, "one density vector per weight");
    let mut pdf = vec![0.0; f2_over_q.len()];
    mixture_pdf(densities, weights, &mut pdf);
    let mut v = moment_of(f2_over_q, sampled, &pdf);
    if !(v.is_finite() && v > 0.0) {
        return v;
    }
    let mut gradient = vec![0.0; n];
    let mut candidate = vec![0.0; n];
    let mut eta = 1.0;
    for _ in 0..steps.iterations {
        // g_i with the current pdf, each summed in path order.
        for (g, d) in gradient.iter_mut().zip(densities) {
            let mut sum = 0.0;
            for ((c, p), d) in f2_over_q.iter().zip(&pdf).zip(d.iter()) {
                sum += c * d / (p * p);
            }
            *g = sum / sampled as f64;
        }
        let mut accepted = false;
        while eta > 1e-3 {
            for ((c, w), g) in candidate.iter_mut().zip(&*weights).zip(&gradient) {
                *c = w * (g / v).powf(eta);
            }
            normalise_weights(&mut candidate, defensive);
            mixture_pdf(densities, &candidate, &mut pdf);
            let v_new = moment_of(f2_over_q, sampled, &pdf);
            if v_new < v {
                accepted = v_new < v * (1.0 - steps.tolerance);
                weights.copy_from_slice(&candidate);
                v = v_new;
                break;
            }
            eta *= 0.5;
        }
        if !accepted {
            break;
        }
        eta = (eta * 2.0).min(1.0);
    }
    // `v` is the kept weights' V: a step overwrites it only when it keeps the candidate.
    v
}

/// `pdf = Σ_i weights[i] · densities[i]`, each path's sum in component order.
fn mixture_pdf(densities: &[&[f64]], weights: &[f64], pdf: &mut [f64]) {
    let mut components = densities.iter().zip(weights);
    match components.next() {
        // `0 + w·d` is `w·d` for the non-negative densities and weights: no pass to zero.
        Some((d, &wi)) => {
            for (p, di) in pdf.iter_mut().zip(d.iter()) {
                *p = wi * di;
            }
        }
        None => pdf.iter_mut().for_each(|p| *p = 0.0),
    }
    for (d, &wi) in components {
        for (p, di) in pdf.iter_mut().zip(d.iter()) {
            *p += wi * di;
        }
    }
}

/// The components worth their densities: from the weights `optimise_weights` left
/// (component 0 the defensive one, always kept), drops one component at a time, the one
/// whose removal raises `V` least (the others' weights renormalised, `w_0 ≥ defensive`),
/// while `V` stays within `1 + tolerance` of `v`, the full mixture's. The multiplicative
/// steps never set a weight to 0, and every component costs the render its densities on
/// every path of every pixel whose mixture holds it, however small its weight (many evolved
/// components end far below 10⁻³: docs/methods/ga.md, "Convex mixture weights"). Returns the
/// kept components' indices, in order, and their weights.
pub fn prune_components(
    (f2_over_q, sampled): (&[f64], usize),
    densities: &[&[f64]],
    weights: &[f64],
    (defensive, v, tolerance): (f64, f64, f64),
) -> (Vec<usize>, Vec<f64>) {
    let mut kept: Vec<usize> = (0..weights.len()).collect();
    let mut kept_weights = weights.to_vec();
    let mut pdf = vec![0.0; f2_over_q.len()];
    let limit = v * (1.0 + tolerance);
    while kept.len() > 1 {
        let mut best: Option<(f64, usize, Vec<f64>)> = None;
        for drop in 1..kept.len() {
            let mut w: Vec<f64> = kept_weights.clone();
            w.remove(drop);
            normalise_weights(&mut w, defensive);
            let others = kept.iter().filter(|&&i| i != kept[drop]);
            let others: Vec<&[f64]> = others.map(|&i| densities[i]).collect();
            mixture_pdf(&others, &w, &mut pdf);
            let v_without = moment_of(f2_over_q, sampled, &pdf);
            if v_without <= limit && best.as_ref().is_none_or(|b| v_without < b.0) {
                best = Some((v_without, drop, w));
            }
        }
        let Some((_, drop, w)) = best else { break };
        kept.remove(drop);
        kept_weights = w;
    }
    (kept, kept_weights)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{sample_rng, uniform};

    /// Three generators on 400 synthetic paths: the defensive one flat, the others each
    /// concentrated where a share of the contribution lies.
    const TIGHT: Steps = Steps {
        iterations: 200,
        tolerance: 1e-9,
    };

    fn problem() -> (Vec<f64>, Vec<Vec<f64>>) {
        let mut rng = sample_rng(3, 0, 0);
        let n = 400;
        let mut c = Vec::new();
        let mut d = vec![Vec::new(), Vec::new(), Vec::new()];
        for j in 0..n {
            let u = uniform(&mut rng) as f64;
            c.push(if j % 3 == 0 { 5.0 * u } else { 0.2 * u });
            d[0].push(1.0);
            d[1].push(if j % 3 == 0 { 2.5 } else { 0.25 });
            d[2].push(0.2 + 1.5 * u);
        }
        (c, d)
    }

    fn v_at(c: &[f64], d: &[Vec<f64>], w: &[f64]) -> f64 {
        let pdf: Vec<f64> = (0..c.len())
            .map(|j| d.iter().zip(w).map(|(d, w)| w * d[j]).sum())
            .collect();
        moment_of(c, 2 * c.len(), &pdf)
    }

    /// The smallest `V` over a grid of feasible weights with `w_0 ≥ defensive`.
    fn grid_minimum(c: &[f64], d: &[Vec<f64>], defensive: f64) -> f64 {
        let steps = 200;
        let mut best = f64::INFINITY;
        for a in 0..=steps {
            for b in 0..=steps - a {
                let (w1, w2) = (a as f64 / steps as f64, b as f64 / steps as f64);
                let w0 = 1.0 - w1 - w2;
                if w0 >= defensive - 1e-12 {
                    best = best.min(v_at(c, d, &[w0, w1, w2]));
                }
            }
        }
        best
    }

    #[test]
    fn convex_weights_reach_the_minimum_of_eq_10() {
        let (c, d) = problem();
        let defensive = 0.05;
        let start = [0.4, 0.3, 0.3];
        let mut w = start;
        let refs: Vec<&[f64]> = d.iter().map(|v| v.as_slice()).collect();
        let v = optimise_weights((&c, 2 * c.len()), &refs, &mut w, defensive, TIGHT);
        let sum: f64 = w.iter().sum();
        assert!(
            (sum - 1.0).abs() < 1e-12 && w[0] >= defensive - 1e-12,
            "{w:?}"
        );
        assert!(
            (v - v_at(&c, &d, &w)).abs() <= 1e-12 * v,
            "returned V is the weights' V"
        );
        // No grid point (spacing 0.005) does better than the optimiser, within 1e-4.
        let grid = grid_minimum(&c, &d, defensive);
        assert!(
            v <= grid * (1.0 + 1e-4),
            "optimised {v} vs grid {grid}, {w:?}"
        );
        // The same check rejects the starting weights: they are measurably off the minimum.
        let v_start = v_at(&c, &d, &start);
        assert!(v_start > grid * 1.01, "start {v_start} vs grid {grid}");
        // Optimality (KKT): the free components in use share one ∂V/∂w_i; with the
        // defensive weight at its bound that value is (V − w_0 g_0)/(1 − w_0), else V.
        let pdf: Vec<f64> = (0..c.len())
            .map(|j| d.iter().zip(&w).map(|(d, w)| w * d[j]).sum())
            .collect();
        let g: Vec<f64> = d
            .iter()
            .map(|di| {
                (0..c.len())
                    .map(|j| c[j] * di[j] / pdf[j].powi(2))
                    .sum::<f64>()
                    / (2 * c.len()) as f64
            })
            .collect();
        let lambda = (v - w[0] * g[0]) / (1.0 - w[0]);
        for i in 1..3 {
            if w[i] > 1e-3 {
                assert!(
                    (g[i] - lambda).abs() < 1e-3 * lambda,
                    "component {i}: {g:?}, λ {lambda}, {w:?}"
                );
            }
        }
    }

    #[test]
    fn pruning_drops_the_components_that_do_not_pay_and_keeps_those_that_do() {
        let (c, mut d) = problem();
        // A fourth component whose density follows nothing the contributions do.
        let mut rng = sample_rng(4, 0, 0);
        d.push(
            (0..c.len())
                .map(|_| 0.5 + uniform(&mut rng) as f64)
                .collect(),
        );
        let defensive = 0.05;
        let mut w = [0.25; 4];
        let refs: Vec<&[f64]> = d.iter().map(|v| v.as_slice()).collect();
        let tests = (&c[..], 2 * c.len());
        let v = optimise_weights(tests, &refs, &mut w, defensive, TIGHT);
        let tolerance = 1e-3;
        let (kept, kept_w) = prune_components(tests, &refs, &w, (defensive, v, tolerance));
        assert_eq!(kept, [0, 1, 2], "weights {w:?}");
        let sum: f64 = kept_w.iter().sum();
        assert!((sum - 1.0).abs() < 1e-12 && kept_w[0] >= defensive - 1e-12);
        let kept_d: Vec<Vec<f64>> = kept.iter().map(|&i| d[i].clone()).collect();
        assert!(v_at(&c, &kept_d, &kept_w) <= v * (1.0 + tolerance));
        // Each of the two kept concentrated components pays: without it `V` rises past
        // the tolerance, so a pruning that dropped it would fail the check above.
        for drop in [1, 2] {
            let mut w3 = w;
            w3[drop] = 0.0;
            crate::genetic::individual::normalise_weights(&mut w3, defensive);
            assert!(
                v_at(&c, &d, &w3) > v * (1.0 + tolerance),
                "component {drop}"
            );
        }
        // Without tolerance only what does not raise `V` at all goes: here the fourth
        // component, whose weight the optimiser has driven to nothing.
        assert!(w[3] < 1e-6, "{w:?}");
        let (strict, _) = prune_components(tests, &refs, &w, (defensive, v, 0.0));
        assert_eq!(strict, [0, 1, 2]);
    }
}
