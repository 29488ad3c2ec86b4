//! Path generators and their weighted sets (paper §5.1–5.3, design §5).
//!
//! A [`PathGenerator`] is a sequence of (directional sampler, absorption) pairs plus a
//! light-point sampler. It samples an eye path vertex by vertex: at the k-th non-delta
//! vertex it absorbs with probability `a_k` (then draws a point on a light and traces one
//! shadow ray: next-event estimation only at the path's end) or samples a direction with
//! `s_k` and traces on. Mirror (delta) vertices consume no sampler and never absorb. The
//! sampling is a [`Walk`], a state machine that stops at each ray it needs traced, so that
//! one implementation serves single rays ([`PathGenerator::sample_path`]) and packets.
//!
//! Every generator evaluates the density of a path that *any* generator produced from the
//! stored vertices alone ([`PathGenerator::pdf_path`]), which is what the balance-heuristic
//! estimator of a [`Mixture`](super::mixture::Mixture) (paper eq. 7–8) and the fitness of the genetic algorithm need.

use super::{RayCounts, SceneView, SurfacePoint};
use crate::accel::Ray;
use crate::sampling::anchor::AnchorSampler;
use crate::sampling::brdf;
use crate::sampling::light_point::LightPointSampler;
use crate::sampling::patch::PatchSampler;
use crate::sampling::{uniform, Rng};
use glam::{DVec3, Vec3};

/// Smallest and largest absorption before the last sampler: keeps every path length
/// reachable (unbiasedness) and every generator able to continue.
pub const ABSORPTION_MIN: f64 = 1e-3;
pub const ABSORPTION_MAX: f64 = 1.0 - 1e-3;
/// The default absorption of the `srt` generator at each vertex (`[srt] srt_absorption`).
pub const SRT_ABSORPTION: f64 = 0.5;

/// How a generator picks the direction out of a vertex.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub enum DirectionSampler {
    /// Proportional to BRDF × cos (the material's own sampler).
    Brdf,
    /// A cone towards an anchor point (paper §5.2).
    Anchor(AnchorSampler),
    /// Points on a parallelogram in space (beyond the paper: light that arrives from a
    /// long, thin region, which cones cover poorly).
    Patch(PatchSampler),
}

/// One step of a generator: a directional sampler and the absorption before it.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Step {
    pub sampler: DirectionSampler,
    /// Probability of ending the path at this vertex (then a light point is sampled).
    pub absorption: f64,
}

/// A path generator: steps for the non-delta vertices 1, 2, … and a light-point sampler.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PathGenerator {
    pub steps: Vec<Step>,
    pub light: LightPointSampler,
}

/// One vertex of a sampled eye path, with what any generator needs to evaluate its density.
#[derive(Clone, Copy, Debug)]
pub struct PathVertex {
    pub point: SurfacePoint,
    /// Unit direction towards the previous vertex (the camera for the first).
    pub wo: Vec3,
    /// Unit direction sampled out of this vertex (zero at the path's end).
    pub wi: Vec3,
    /// A mirror vertex: its direction was determined, not sampled.
    pub delta: bool,
    /// Density with which the sampling generator continued here: `(1 − a)·p(wi)`; 1 at a
    /// delta vertex. Kept to check [`PathGenerator::pdf_path`] against.
    pub pdf_sampled: f64,
}

/// The light point drawn at the absorbing vertex.
#[derive(Clone, Copy, Debug)]
pub struct LightVertex {
    pub point: DVec3,
    pub prim: u32,
    /// Density with which the sampling generator ended here: `a · p_area(y)`.
    pub pdf_sampled: f64,
}

/// An eye path `x1 … xn` and, when it ended by absorption, its light point.
#[derive(Clone, Debug, Default)]
pub struct PathVertices {
    pub vertices: Vec<PathVertex>,
    pub light: Option<LightVertex>,
}

/// A path that carries light to the camera: its contribution `F(X)` (RGB, measurement
/// contribution with the pixel filter factored out) and where it ends.
#[derive(Clone, Copy, Debug)]
pub struct Contribution {
    pub f: DVec3,
    /// Number of vertices of the path (`x1 … x_len`).
    pub len: usize,
    /// Ends with the light point (`true`) or on an emitter hit after a delta vertex.
    pub nee: bool,
}

impl PathGenerator {
    /// The paper's "stochastic ray tracing" generator: BRDF sampling at every vertex with the
    /// fixed absorption `absorption`, uniform light sampling by area.
    pub fn srt(max_bounces: u32, absorption: f64, light: LightPointSampler) -> Self {
        let steps = (0..max_bounces)
            .map(|_| Step {
                sampler: DirectionSampler::Brdf,
                absorption,
            })
            .collect();
        Self { steps, light }
    }

    /// Absorption at the `k`-th non-delta vertex, which is scattering event `bounce`: 1 after
    /// the last step and at `max_bounces`.
    pub fn absorption(&self, k: usize, bounce: usize, max_bounces: u32) -> f64 {
        if bounce >= max_bounces as usize || k >= self.steps.len() {
            1.0
        } else {
            self.steps[k].absorption
        }
    }

    fn direction_pdf(&self, view: &SceneView, k: usize, v: &PathVertex) -> f64 {
        match &self.steps[k].sampler {
            DirectionSampler::Brdf => {
                let m = view.scattering_material(&v.point, v.wo);
                brdf::pdf(m, brdf::facing_normal(v.point.ng, v.wo), v.wo, v.wi)
            }
            DirectionSampler::Anchor(a) => a.pdf(v.point.p.as_dvec3(), v.wi.as_dvec3()),
            DirectionSampler::Patch(s) => s.pdf(v.point.p.as_dvec3(), v.wi.as_dvec3()),
        }
    }

    /// Density with which this generator produces the first `len` vertices of `path`
    /// followed by its light point (`nee`), or by an emitter hit through a delta vertex.
    /// Directions in solid angle, the light point in area: the measure all generators share.
    pub fn pdf_path(
        &self,
        view: &SceneView,
        path: &PathVertices,
        len: usize,
        nee: bool,
        max_bounces: u32,
    ) -> f64 {
        let mut pdf = 1.0;
        let mut k = 0;
        let scattering = if nee { len - 1 } else { len };
        for (j, v) in path.vertices[..scattering].iter().enumerate() {
            if v.delta {
                continue;
            }
            let a = self.absorption(k, j + 1, max_bounces);
            if a >= 1.0 {
                return 0.0;
            }
            pdf *= (1.0 - a) * self.direction_pdf(view, k, v);
            k += 1;
        }
        if nee {
            let (Some(light), Some(last)) = (path.light, path.vertices.get(len - 1)) else {
                return 0.0;
            };
            if last.delta {
                return 0.0;
            }
            let scene = view.scene;
            pdf *= self.absorption(k, len, max_bounces)
                * self
                    .light
                    .pdf_area(&scene.mesh, &scene.emitters, light.point, light.prim);
        }
        pdf
    }

    /// Samples an eye path starting at the first hit `x1` (reached from `camera`), traces it
    /// one ray at a time, and appends every light-carrying sub-path to `contributions`: the
    /// single-lane driver of a [`Walk`].
    #[allow(clippy::too_many_arguments)]
    pub fn sample_path(
        &self,
        view: &SceneView,
        camera: Vec3,
        x1: SurfacePoint,
        max_bounces: u32,
        rng: &mut Rng,
        counts: &mut RayCounts,
        path: &mut PathVertices,
        contributions: &mut Vec<Contribution>,
    ) {
        let (mut walk, mut query) = Walk::start(self, view, camera, x1, max_bounces, rng, path);
        while let Some(q) = query {
            query = match q {
                Query::Closest(ray) => {
                    let y = view.trace(&ray, counts);
                    walk.hit(self, view, rng, path, contributions, y)
                }
                Query::Shadow(ray) => {
                    walk.shadow(view.unblocked(&ray, counts), contributions);
                    None
                }
            };
        }
    }
}

/// The ray a [`Walk`] waits on before it can go on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Query {
    /// The closest surface along the ray; answer with [`Walk::hit`].
    Closest(Ray),
    /// Whether the shadow ray (from [`SceneView::shadow_ray`]) is unblocked; answer with
    /// [`Walk::shadow`], which ends the walk.
    Shadow(Ray),
}

/// One eye path of a [`PathGenerator`] being sampled, as a resumable state machine: it runs
/// until it needs a ray traced, returns that [`Query`], and goes on when handed the answer.
/// A driver can thus trace the rays of many walks as packets, or one at a time
/// ([`PathGenerator::sample_path`]); either way a walk draws the same random numbers in the
/// same order and does the same arithmetic. The random stream, the vertices and the
/// contributions are the caller's, so that a walk is a few plain values and allocates nothing.
#[derive(Clone, Copy, Debug, Default)]
pub struct Walk {
    /// The current vertex, the unit direction back towards the previous one, and the
    /// throughput of the path up to it.
    x: SurfacePoint,
    wo: Vec3,
    throughput: DVec3,
    /// Non-delta vertices passed (the generator's next step), and the current vertex's
    /// scattering event (1 at `x1`).
    k: usize,
    bounce: usize,
    max_bounces: u32,
    /// Direction of the pending closest-hit query, and whether it leaves a mirror.
    wi: Vec3,
    mirror: bool,
    /// Contribution of the pending shadow query, counted if it is unblocked.
    nee: DVec3,
}

impl Walk {
    /// Starts an eye path of `g` at the first hit `x1` (reached from `camera`), clearing
    /// `path`; returns the walk and its first query (`None`: the path ended without one).
    pub fn start(
        g: &PathGenerator,
        view: &SceneView,
        camera: Vec3,
        x1: SurfacePoint,
        max_bounces: u32,
        rng: &mut Rng,
        path: &mut PathVertices,
    ) -> (Self, Option<Query>) {
        path.vertices.clear();
        path.light = None;
        let mut walk = Self {
            x: x1,
            wo: (camera - x1.p).normalize(),
            throughput: DVec3::ONE,
            bounce: 1,
            max_bounces,
            ..Self::default()
        };
        let query = walk.scatter(g, view, rng, path);
        (walk, query)
    }

    /// Answers a [`Query::Closest`]: moves to the hit `y` (counting an emitter reached
    /// through a mirror) and scatters there; returns the next query, `None` at the end.
    pub fn hit(
        &mut self,
        g: &PathGenerator,
        view: &SceneView,
        rng: &mut Rng,
        path: &mut PathVertices,
        contributions: &mut Vec<Contribution>,
        y: Option<SurfacePoint>,
    ) -> Option<Query> {
        let y = y?;
        if self.mirror {
            let le = super::emitted(view.material(y.prim), &y, -self.wi);
            if le.max_element() > 0.0 {
                // Reached through a delta: no shadow ray can find it, so it counts on hit.
                contributions.push(Contribution {
                    f: self.throughput * le.as_dvec3(),
                    len: self.bounce,
                    nee: false,
                });
            }
        }
        self.x = y;
        self.wo = -self.wi;
        self.bounce += 1;
        self.scatter(g, view, rng, path)
    }

    /// Answers a [`Query::Shadow`], the walk's last: the light point counts if `unblocked`.
    pub fn shadow(&self, unblocked: bool, contributions: &mut Vec<Contribution>) {
        if unblocked {
            contributions.push(Contribution {
                f: self.nee,
                len: self.bounce,
                nee: true,
            });
        }
    }

    /// The current vertex's scattering event: absorb (then a light point and a shadow
    /// query) or sample a direction (then a closest-hit query); `None` where the path ends.
    fn scatter(
        &mut self,
        g: &PathGenerator,
        view: &SceneView,
        rng: &mut Rng,
        path: &mut PathVertices,
    ) -> Option<Query> {
        if self.bounce > self.max_bounces as usize {
            return None;
        }
        let scene = view.scene;
        let (x, wo, bounce, k) = (self.x, self.wo, self.bounce, self.k);
        let material = view.scattering_material(&x, wo);
        if !material.scatters() {
            return None;
        }
        let n = brdf::facing_normal(x.ng, wo);
        let mut vertex = PathVertex {
            point: x,
            wo,
            wi: Vec3::ZERO,
            delta: material.mirror,
            pdf_sampled: 1.0,
        };
        let absorption = if material.mirror {
            0.0
        } else {
            g.absorption(k, bounce, self.max_bounces)
        };
        if (uniform(rng) as f64) < absorption {
            // Absorbed: one shadow ray to a light point (next-event estimation).
            path.vertices.push(vertex);
            let u = [
                uniform(rng) as f64,
                uniform(rng) as f64,
                uniform(rng) as f64,
            ];
            let (y, prim) = g.light.sample(&scene.mesh, &scene.emitters, u);
            let pdf_area = g.light.pdf_area(&scene.mesh, &scene.emitters, y, prim);
            path.light = Some(LightVertex {
                point: y,
                prim,
                pdf_sampled: absorption * pdf_area,
            });
            let y_point = SurfacePoint {
                p: y.as_vec3(),
                ng: scene.mesh.normals[prim as usize],
                prim,
            };
            let d = y_point.p - x.p;
            let dist2 = d.length_squared();
            let wi = d / dist2.sqrt();
            let (cos_x, cos_y) = (n.dot(wi), -y_point.ng.dot(wi));
            if cos_x > 0.0 && cos_y > 0.0 && dist2 > 0.0 {
                let f =
                    brdf::eval(material, n, wo, wi).as_dvec3() * view.material(prim).ke.as_dvec3();
                if f.max_element() > 0.0 {
                    let geometry = cos_x as f64 * cos_y as f64 / dist2 as f64;
                    self.nee = self.throughput * f * geometry;
                    return Some(Query::Shadow(view.shadow_ray(&x, &y_point)));
                }
            }
            return None;
        }
        let wi = if material.mirror {
            self.throughput *= material.mirror_reflectance(n.dot(wo)).as_dvec3();
            brdf::reflect(wo, n).normalize()
        } else {
            let u = [
                uniform(rng) as f64,
                uniform(rng) as f64,
                uniform(rng) as f64,
            ];
            let (wi, pdf) = match &g.steps[k].sampler {
                DirectionSampler::Brdf => {
                    let s = brdf::sample(material, n, wo, u)?;
                    (s.wi, s.pdf)
                }
                DirectionSampler::Anchor(a) => {
                    let wi = a.sample(x.p.as_dvec3(), u).as_vec3().normalize();
                    (wi, a.pdf(x.p.as_dvec3(), wi.as_dvec3()))
                }
                DirectionSampler::Patch(s) => {
                    let wi = s.sample(x.p.as_dvec3(), u).as_vec3().normalize();
                    (wi, s.pdf(x.p.as_dvec3(), wi.as_dvec3()))
                }
            };
            vertex.pdf_sampled = (1.0 - absorption) * pdf;
            let cos = n.dot(wi);
            let f = brdf::eval(material, n, wo, wi);
            if cos <= 0.0 || f.max_element() <= 0.0 {
                return None;
            }
            self.throughput *= f.as_dvec3() * cos as f64;
            self.k += 1;
            wi
        };
        vertex.wi = wi;
        path.vertices.push(vertex);
        self.wi = wi;
        self.mirror = material.mirror;
        Some(Query::Closest(view.spawn(&x, wi)))
    }
}
