//! Genetic operators (paper §5.5): crossover of the first `R ≥ 1` generators, sampler
//! mutation, switching two generators, weight mutation and absorption mutation. Every
//! operator keeps the invariants of an individual (weights sum to 1, defensive weight
//! ≥ `defensive_weight`, absorptions in `[ABSORPTION_MIN, ABSORPTION_MAX]`, α ∈ (0, 1),
//! β ∈ [0, 1), θc ∈ (0, π), anchors on the triangle they were drawn on); the defensive
//! component 0 is never touched. A changed generator gets a fresh id.

use super::individual::{clamp_theta_c, Gene, GenePool, Individual, BETA_MAX, PATCH_HALF_RANGE};
use super::GaConfig;
use crate::path::generator::{DirectionSampler, ABSORPTION_MAX, ABSORPTION_MIN};
use crate::sampling::light_point::barycentric;
use crate::sampling::Rng;
use glam::DVec3;
use rand::Rng as _;
use std::f64::consts::PI;

/// Relative size of the multiplicative weight mutation (log-normal standard deviation).
const WEIGHT_SIGMA: f64 = 0.5;
/// Standard deviation, in logit space, of α, β and absorption mutations.
const LOGIT_SIGMA: f64 = 0.7;
/// Standard deviation of the log of θc in a cone-angle mutation, and of a patch edge's
/// length in a patch-scale mutation.
const THETA_SIGMA: f64 = 0.3;
/// Standard deviation of a patch shift along each edge, relative to the half-edge.
const PATCH_SHIFT: f64 = 0.3;

/// A standard normal number (Box–Muller).
fn normal(rng: &mut Rng) -> f64 {
    let u1 = 1.0 - rng.random::<f64>(); // (0, 1]: the log stays finite
    let u2 = rng.random::<f64>();
    (-2.0 * u1.ln()).sqrt() * (2.0 * PI * u2).cos()
}

fn logit(p: f64) -> f64 {
    (p / (1.0 - p)).ln()
}

fn sigmoid(x: f64) -> f64 {
    1.0 / (1.0 + (-x).exp())
}

/// `p ∈ (0, 1)` moved in logit space, then clamped to `[lo, hi]`.
fn perturb_probability(p: f64, rng: &mut Rng, lo: f64, hi: f64) -> f64 {
    sigmoid(logit(p.clamp(lo, hi)) + LOGIT_SIGMA * normal(rng)).clamp(lo, hi)
}

/// `anchor` on triangle `prim` moved by a Gaussian step in the triangle's plane and clamped
/// back into the triangle (barycentrics clamped to ≥ 0 and renormalised); on an analytic
/// shape, projected back onto it.
fn shift_anchor(pool: &GenePool, prim: u32, anchor: DVec3, sigma: f64, rng: &mut Rng) -> DVec3 {
    if let Some(shape) = pool.scene.mesh.analytic(prim) {
        // On a sphere or disk: a step in the tangent plane, projected back onto the shape.
        let (e1, e2) = shape.tangents(anchor);
        let step = sigma * f64::from(pool.scene.extent);
        let moved = anchor + e1 * (step * normal(rng)) + e2 * (step * normal(rng));
        let moved = shape.project(moved);
        return if moved.is_finite() { moved } else { anchor };
    }
    let tri = pool.scene.mesh.vertices(prim).map(|v| v.as_dvec3());
    let [a, b, c] = tri;
    let e1 = (b - a).normalize_or_zero();
    let e2 = (b - a).cross(c - a).cross(b - a).normalize_or_zero();
    let step = sigma * f64::from(pool.scene.extent);
    let moved = anchor + e1 * (step * normal(rng)) + e2 * (step * normal(rng));
    let w = barycentric(tri, moved).max(DVec3::ZERO);
    let sum = w.x + w.y + w.z;
    if !(sum > 0.0 && sum.is_finite()) {
        return anchor;
    }
    let w = w / sum;
    a * w.x + b * w.y + c * w.z
}

/// A patch's half-edge scaled by a log-normal factor, its length kept in
/// `PATCH_HALF_RANGE` of the scene's size.
fn scale_half(pool: &GenePool, half: DVec3, rng: &mut Rng) -> DVec3 {
    let extent = f64::from(pool.scene.extent);
    let (lo, hi) = PATCH_HALF_RANGE;
    let length = half.length();
    let scaled = (length * (THETA_SIGMA * normal(rng)).exp()).clamp(lo * extent, hi * extent);
    half * (scaled / length)
}

/// Mutates step `k`'s directional sampler of `gene`: for a cone, shift, re-draw or re-aim
/// its anchor, change θc or α; for a patch, shift it in its plane, scale an edge, change α
/// or fit a new one to the test paths; or replace it by a random sampler of any type.
fn mutate_sampler(pool: &GenePool, config: &GaConfig, gene: &mut Gene, k: usize, rng: &mut Rng) {
    let choice = rng.random_range(0..6u32);
    let prim = gene.anchor_prims[k];
    match (&mut gene.generator.steps[k].sampler, prim) {
        (DirectionSampler::Patch(p), _) if choice < 5 => match choice {
            0 => {
                let (u, v) = (PATCH_SHIFT * normal(rng), PATCH_SHIFT * normal(rng));
                p.center += p.half_u * u + p.half_v * v;
            }
            1 => p.half_u = scale_half(pool, p.half_u, rng),
            2 => p.half_v = scale_half(pool, p.half_v, rng),
            3 => p.alpha = perturb_probability(p.alpha, rng, 1e-3, 1.0 - 1e-3),
            _ => {
                let at = (p.center, p.half_u.cross(p.half_v).normalize());
                if let Some(fitted) = pool.data_patch(k, at, rng) {
                    *p = fitted;
                }
            }
        },
        (DirectionSampler::Anchor(s), Some(prim)) if choice < 5 => match choice {
            0 | 1 => s.anchor = shift_anchor(pool, prim, s.anchor, config.anchor_shift, rng),
            2 => {
                let (anchor, prim) = pool.random_anchor(k, rng);
                s.anchor = anchor;
                gene.anchor_prims[k] = Some(prim);
            }
            3 => s.theta_c = clamp_theta_c(s.theta_c * (THETA_SIGMA * normal(rng)).exp()),
            _ => s.alpha = perturb_probability(s.alpha, rng, 1e-3, 1.0 - 1e-3),
        },
        _ => {
            let (sampler, prim) = pool.random_sampler(k, rng);
            gene.generator.steps[k].sampler = sampler;
            gene.anchor_prims[k] = prim;
        }
    }
}

/// Mutates the light-point sampler: change β, or draw a new region and β.
fn mutate_light(pool: &GenePool, gene: &mut Gene, rng: &mut Rng) {
    let light = &mut gene.generator.light;
    if rng.random::<f64>() < 0.5 {
        light.beta = perturb_probability(light.beta.max(1e-3), rng, 0.0, BETA_MAX);
    } else {
        *light = pool.random_light(rng);
    }
}

/// Crossover: the first `R ≥ 1` evolved generators (and their weights) change places.
pub fn crossover(a: &mut Individual, b: &mut Individual, config: &GaConfig, rng: &mut Rng) {
    let s = a.genes.len().min(b.genes.len()) - 1;
    if s == 0 {
        return;
    }
    // R = S would only swap the individuals: at most S − 1 where possible.
    let r = rng.random_range(1..=(s - 1).max(1));
    for i in 1..=r {
        std::mem::swap(&mut a.genes[i], &mut b.genes[i]);
        std::mem::swap(&mut a.weights[i], &mut b.weights[i]);
    }
    a.normalise_weights(config.defensive_weight);
    b.normalise_weights(config.defensive_weight);
}

/// Applies every mutation of §5.5, each with its probability.
pub fn mutate(ind: &mut Individual, pool: &mut GenePool, config: &GaConfig, rng: &mut Rng) {
    let s = ind.genes.len() - 1;
    for gene in &mut ind.genes[1..] {
        let mut changed = false;
        for k in 0..gene.generator.steps.len() {
            if rng.random::<f64>() < config.p_sampler_mutate {
                mutate_sampler(pool, config, gene, k, rng);
                changed = true;
            }
        }
        if config.directions_only {
            // Light sampler and absorptions stay `srt`'s.
        } else if rng.random::<f64>() < config.p_sampler_mutate {
            mutate_light(pool, gene, rng);
            changed = true;
        }
        if !config.directions_only
            && !gene.generator.steps.is_empty()
            && rng.random::<f64>() < config.p_absorb
        {
            let k = rng.random_range(0..gene.generator.steps.len());
            let a = &mut gene.generator.steps[k].absorption;
            *a = perturb_probability(*a, rng, ABSORPTION_MIN, ABSORPTION_MAX);
            changed = true;
        }
        if changed {
            gene.id = pool.fresh_id();
        }
    }
    if s >= 2 && rng.random::<f64>() < config.p_switch {
        let i = rng.random_range(1..=s);
        let j = 1 + (i - 1 + rng.random_range(1..s)) % s; // j ≠ i
        ind.genes.swap(i, j);
        ind.weights.swap(i, j);
    }
    if rng.random::<f64>() < config.p_weight {
        let max = ind.weights.iter().copied().fold(0.0, f64::max);
        for w in &mut ind.weights {
            // The floor lets a weight that fell to nothing grow back.
            *w = w.max(1e-3 * max) * (WEIGHT_SIGMA * normal(rng)).exp();
        }
        ind.normalise_weights(config.defensive_weight);
    }
}
