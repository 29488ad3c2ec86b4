//! The test paths of one pixel (paper §5.4): `M` paths sampled once from a defensive density
//! `q` and reused for every fitness evaluation. Only paths with `F > 0` are stored (`M` still
//! counts the others), each with what any generator needs to evaluate its density without
//! tracing a ray, and `F²/q`.
//!
//! Storage is structure-of-arrays: the scattering vertices of all paths are flattened into
//! per-vertex arrays indexed through `offsets`. The BRDF density of each scattering vertex is
//! the same for every generator that uses a BRDF sampler there, so it is computed once here.
//!
//! Paths are traced one at a time (not yet in 16-wide packets).

use super::luminance;
use crate::path::generator::{Contribution, DirectionSampler, PathGenerator, PathVertices};
use crate::path::mixture::Mixture;
use crate::path::{RayCounts, SceneView};
use crate::sampling::{brdf, sample_rng, uniform, Rng};
use glam::DVec3;

/// Test paths of one pixel.
#[derive(Clone, Debug)]
pub struct TestPaths {
    /// Number of sampled paths, zero-contribution ones included (`M` of eq. 10).
    pub sampled: usize,
    pub max_bounces: u32,
    /// Per stored path: `F²/q`, `F` the luminance of the contribution.
    pub f2_over_q: Vec<f64>,
    /// Per stored path: number of vertices `x1 … x_len`.
    len: Vec<u32>,
    /// Per stored path: ends with a light point (next-event estimation).
    nee: Vec<bool>,
    /// Per stored path: the light point and its triangle (unused where `nee` is false).
    light_point: Vec<DVec3>,
    light_prim: Vec<u32>,
    /// Scattering vertices of path `i` are `offsets[i]..offsets[i + 1]`.
    offsets: Vec<u32>,
    /// Per scattering vertex: position, sampled direction, BRDF density of that direction,
    /// and whether it is a mirror (delta) vertex.
    point: Vec<DVec3>,
    wi: Vec<DVec3>,
    brdf_pdf: Vec<f64>,
    delta: Vec<bool>,
}

/// Absorption of `g` at its `k`-th non-delta vertex, scattering event `bounce` (the rule of
/// `PathGenerator::pdf_path`): 1 after the last sampler and at `max_bounces`.
fn absorption(g: &PathGenerator, k: usize, bounce: usize, max_bounces: u32) -> f64 {
    if bounce >= max_bounces as usize || k >= g.steps.len() {
        1.0
    } else {
        g.steps[k].absorption
    }
}

/// Picks a component of `q` by its weight.
fn choose(q: &Mixture, u: f64) -> usize {
    let mut acc = 0.0;
    for (i, w) in q.weights.iter().enumerate() {
        acc += w;
        if u < acc {
            return i;
        }
    }
    q.weights.len() - 1
}

impl TestPaths {
    /// An empty store (no path sampled yet).
    pub fn new(max_bounces: u32) -> Self {
        Self {
            sampled: 0,
            max_bounces,
            f2_over_q: Vec::new(),
            len: Vec::new(),
            nee: Vec::new(),
            light_point: Vec::new(),
            light_prim: Vec::new(),
            offsets: vec![0],
            point: Vec::new(),
            wi: Vec::new(),
            brdf_pdf: Vec::new(),
            delta: Vec::new(),
        }
    }

    /// Samples `m` paths from `q` through pixel `(x, y)` (box filter: a uniformly jittered
    /// camera ray), path `j` with the random stream `sample_rng(seed, pixel, j)`.
    pub fn sample(
        view: &SceneView,
        q: &Mixture,
        (x, y): (u32, u32),
        m: usize,
        max_bounces: u32,
        seed: u64,
    ) -> (Self, RayCounts) {
        let camera = &view.scene.camera;
        let pixel = y as u64 * camera.width as u64 + x as u64;
        let mut paths = Self::new(max_bounces);
        let mut counts = RayCounts::default();
        let mut path = PathVertices::default();
        let mut contributions = Vec::new();
        for j in 0..m {
            paths.sampled += 1;
            let mut rng: Rng = sample_rng(seed, pixel, j as u64);
            let ray = camera.ray(x as f32 + uniform(&mut rng), y as f32 + uniform(&mut rng));
            let Some(x1) = view.trace(&ray, &mut counts) else {
                continue;
            };
            let g = choose(q, uniform(&mut rng) as f64);
            contributions.clear();
            q.generators[g].sample_path(
                view,
                ray.origin,
                x1,
                max_bounces,
                &mut rng,
                &mut counts,
                &mut path,
                &mut contributions,
            );
            for c in &contributions {
                let pdf = q.pdf_path(view, &path, c, max_bounces);
                let f = luminance(c.f);
                if pdf > 0.0 && f > 0.0 {
                    paths.push(view, &path, c, f * f / pdf);
                }
            }
        }
        (paths, counts)
    }

    /// Stores the part of `path` that contribution `c` uses, with its `F²/q` (`sampled`,
    /// the `M` of eq. 10, is the caller's to count).
    pub fn push(&mut self, view: &SceneView, path: &PathVertices, c: &Contribution, f2q: f64) {
        let scattering = if c.nee { c.len - 1 } else { c.len };
        for v in &path.vertices[..scattering] {
            let pdf = if v.delta {
                0.0
            } else {
                let m = view.material(v.point.prim);
                brdf::pdf(m, brdf::facing_normal(v.point.ng, v.wo), v.wo, v.wi)
            };
            self.point.push(v.point.p.as_dvec3());
            self.wi.push(v.wi.as_dvec3());
            self.brdf_pdf.push(pdf);
            self.delta.push(v.delta);
        }
        self.offsets.push(self.point.len() as u32);
        self.len.push(c.len as u32);
        self.nee.push(c.nee);
        let (point, prim) = match (c.nee, path.light) {
            (true, Some(l)) => (l.point, l.prim),
            _ => (DVec3::ZERO, u32::MAX),
        };
        self.light_point.push(point);
        self.light_prim.push(prim);
        self.f2_over_q.push(f2q);
    }

    /// Number of stored (light-carrying) paths.
    pub fn len(&self) -> usize {
        self.f2_over_q.len()
    }

    pub fn is_empty(&self) -> bool {
        self.f2_over_q.is_empty()
    }

    /// The density `p_g` of every stored path, into `out` (`out.len() == self.len()`):
    /// the same value as `PathGenerator::pdf_path` on the original path.
    pub fn generator_pdfs(&self, view: &SceneView, g: &PathGenerator, out: &mut [f64]) {
        let scene = view.scene;
        for (i, out) in out.iter_mut().enumerate() {
            let (start, end) = (self.offsets[i] as usize, self.offsets[i + 1] as usize);
            let mut pdf = 1.0;
            let mut k = 0;
            for j in start..end {
                if self.delta[j] {
                    continue;
                }
                let a = absorption(g, k, j - start + 1, self.max_bounces);
                if a >= 1.0 {
                    pdf = 0.0;
                    break;
                }
                let direction = match &g.steps[k].sampler {
                    DirectionSampler::Brdf => self.brdf_pdf[j],
                    DirectionSampler::Anchor(s) => s.pdf(self.point[j], self.wi[j]),
                };
                pdf *= (1.0 - a) * direction;
                k += 1;
            }
            if self.nee[i] && pdf > 0.0 {
                let len = self.len[i] as usize;
                pdf *= absorption(g, k, len, self.max_bounces)
                    * g.light.pdf_area(
                        &scene.mesh,
                        &scene.emitters,
                        self.light_point[i],
                        self.light_prim[i],
                    );
            }
            *out = pdf;
        }
    }
}
