//! One eye path of a [`PathGenerator`] being sampled ([`Walk`]), for either estimator
//! ([`Nee`]; see [`super::generator`]).

use super::generator::{
    Connection, Contribution, DirectionSampler, LightEnd, LightVertex, Nee, PathGenerator,
    PathVertex, PathVertices,
};
use super::pt::Receiver;
use super::{emitted, EndPoint, RayCounts, SceneView};
use crate::accel::Ray;
use crate::sampling::{uniform, Rng};
use crate::scene::material::bsdf::{self, Frame};
use crate::scene::material::specular;
use crate::scene::{DirectPick, LightSampler, MaterialAt, SurfacePoint};
use glam::{DVec3, Vec3};

/// The ray a [`Walk`] waits on before it can go on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Query {
    /// The closest surface along the ray; answer with [`Walk::hit`].
    Closest(Ray),
    /// Whether the shadow ray (from [`SceneView::shadow_ray`]) is unblocked; answer with
    /// [`Walk::shadow`] (with [`Nee::End`] the walk's last query).
    Shadow(Ray),
}

/// One eye path of a [`PathGenerator`] being sampled, as a resumable state machine: it runs
/// until it needs a ray traced, returns that [`Query`], and goes on when handed the answer.
/// A driver can thus trace the rays of many walks as packets, or one at a time
/// ([`PathGenerator::sample_path`]); either way a walk draws the same random numbers in the
/// same order and does the same arithmetic. The random stream, the vertices and the
/// contributions are the caller's, so that a walk is a few plain values and allocates nothing.
///
/// With [`Nee::Every`] a non-delta vertex draws its light point, its absorption and its
/// direction at once, and asks for the shadow ray first, then for the closest hit.
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
    estimator: Nee,
    /// Direction of the pending closest-hit query, whether it leaves a delta vertex (a
    /// mirror, glass), and the density it was sampled with (`(1 − a)·p`).
    wi: Vec3,
    mirror: bool,
    pdf_dir: f64,
    /// [`Nee::End`]: contribution of the pending shadow query, counted if it is unblocked,
    /// and whether it goes to the environment.
    nee: DVec3,
    nee_escapes: bool,
    /// [`Nee::Every`]: the light point's contribution, counted if its shadow ray is
    /// unblocked, and the closest-hit query that follows it.
    pending: Option<Contribution>,
    then: Option<Ray>,
}

/// The single-lane driver of a [`Walk`], kept here beside it so that `generator` need not
/// import the walk that is built on its types.
impl PathGenerator {
    /// Samples an eye path starting at the first hit `x1` (reached from `camera`) for the
    /// estimator `nee`, traces it one ray at a time, and appends every light-carrying
    /// sub-path to `contributions`: the single-lane driver of a [`Walk`].
    #[allow(clippy::too_many_arguments)]
    pub fn sample_path(
        &self,
        view: &SceneView,
        camera: Vec3,
        x1: SurfacePoint,
        (max_bounces, nee): (u32, Nee),
        rng: &mut Rng,
        counts: &mut RayCounts,
        path: &mut PathVertices,
        contributions: &mut Vec<Contribution>,
    ) {
        let (mut walk, mut query) =
            Walk::start(self, view, camera, x1, (max_bounces, nee), rng, path);
        while let Some(q) = query {
            query = match q {
                Query::Closest(ray) => {
                    let y = view.trace_through(&ray, rng, counts);
                    walk.hit(self, view, rng, path, contributions, y)
                }
                Query::Shadow(ray) => {
                    let free = view.unblocked_through(&ray, rng, counts);
                    walk.shadow(free, contributions)
                }
            };
        }
    }
}

impl Walk {
    /// Starts an eye path of `g` for the estimator `nee` at the first hit `x1` (reached
    /// from `camera`), clearing `path`; returns the walk and its first query (`None`: the
    /// path ended without one).
    pub fn start(
        g: &PathGenerator,
        view: &SceneView,
        camera: Vec3,
        x1: SurfacePoint,
        (max_bounces, nee): (u32, Nee),
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
            estimator: nee,
            ..Self::default()
        };
        let query = walk.scatter(g, view, rng, path);
        (walk, query)
    }

    /// Answers a [`Query::Closest`]: moves to the hit `y` (counting the emission found
    /// there where the estimator does) and scatters there; returns the next query, `None`
    /// at the end.
    pub fn hit(
        &mut self,
        g: &PathGenerator,
        view: &SceneView,
        rng: &mut Rng,
        path: &mut PathVertices,
        contributions: &mut Vec<Contribution>,
        y: Option<SurfacePoint>,
    ) -> Option<Query> {
        let Some(y) = y else {
            self.escaped(view, contributions);
            return None;
        };
        if self.mirror || self.estimator == Nee::Every {
            self.emission_found(view, &y, contributions);
        }
        self.x = y;
        self.wo = -self.wi;
        self.bounce += 1;
        self.scatter(g, view, rng, path)
    }

    /// The emission the pending direction found at `y`, as a contribution: after a delta
    /// vertex (no shadow ray can find it, so it counts on hit), or with [`Nee::Every`] as
    /// the direction technique's sample.
    fn emission_found(&self, view: &SceneView, y: &SurfacePoint, out: &mut Vec<Contribution>) {
        let le = emitted(view.material(y.prim), y, -self.wi);
        if le.max_element() <= 0.0 {
            return;
        }
        let light = match (self.mirror, self.estimator) {
            (true, _) | (_, Nee::End) => None,
            (false, Nee::Every) => {
                let dist2 = (y.p.as_dvec3() - self.x.p.as_dvec3()).length_squared();
                let cos_y = f64::from(y.ng.dot(-self.wi));
                if !(dist2 > 0.0 && cos_y > 0.0) {
                    return;
                }
                Some(Connection {
                    end: LightEnd::Area {
                        point: y.p.as_dvec3(),
                        prim: y.prim,
                    },
                    wi: self.wi,
                    area_to_solid_angle: dist2 / cos_y,
                    pdf_sampled: self.pdf_dir,
                })
            }
        };
        out.push(Contribution {
            f: self.throughput * le.as_dvec3(),
            len: self.bounce,
            nee: false,
            light,
            escaped: false,
        });
    }

    /// The environment's radiance that the pending direction found by escaping the scene, as
    /// a contribution where the estimator counts it: after a delta vertex (direction
    /// sampling alone), or with [`Nee::Every`] as the direction technique's sample (the
    /// light technique samples the environment too). With [`Nee::End`] the environment, as
    /// an area emitter, is found by the absorbing vertex's light sample.
    fn escaped(&self, view: &SceneView, out: &mut Vec<Contribution>) {
        let le = view.escaped(self.wi);
        if le.max_element() <= 0.0 {
            return;
        }
        let light = match (self.mirror, self.estimator) {
            (true, _) => None,
            (false, Nee::End) => return,
            (false, Nee::Every) => Some(Connection {
                end: LightEnd::Environment,
                wi: self.wi,
                area_to_solid_angle: 1.0,
                pdf_sampled: self.pdf_dir,
            }),
        };
        out.push(Contribution {
            f: self.throughput * le.as_dvec3(),
            len: self.bounce,
            nee: false,
            light,
            escaped: true,
        });
    }

    /// Answers a [`Query::Shadow`]: the light point counts if `unblocked`; returns the next
    /// query (with [`Nee::End`] none: the walk is over).
    pub fn shadow(
        &mut self,
        unblocked: bool,
        contributions: &mut Vec<Contribution>,
    ) -> Option<Query> {
        match self.estimator {
            Nee::End => {
                if unblocked {
                    contributions.push(Contribution {
                        f: self.nee,
                        len: self.bounce,
                        nee: true,
                        light: None,
                        escaped: self.nee_escapes,
                    });
                }
                None
            }
            Nee::Every => {
                let pending = self.pending.take();
                if let (true, Some(c)) = (unblocked, pending) {
                    contributions.push(c);
                }
                self.then.take().map(Query::Closest)
            }
        }
    }

    /// The current vertex's scattering event for the walk's estimator; `None` where the
    /// path ends.
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
        let material = view.scattering_material(&self.x, self.wo);
        if !material.scatters() {
            return None;
        }
        match self.estimator {
            Nee::End => self.scatter_at_end(g, view, rng, path, material),
            Nee::Every => self.scatter_every(g, view, rng, path, material),
        }
    }

    /// [`Nee::End`]: absorb (then a light point and a shadow query) or sample a direction
    /// (then a closest-hit query).
    fn scatter_at_end(
        &mut self,
        g: &PathGenerator,
        view: &SceneView,
        rng: &mut Rng,
        path: &mut PathVertices,
        material: MaterialAt,
    ) -> Option<Query> {
        let (x, wo, bounce, k) = (self.x, self.wo, self.bounce, self.k);
        let frame = Frame::facing(&x, wo);
        let mut vertex = PathVertex {
            point: x,
            wo,
            frame,
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
            // Absorbed: one shadow ray to a light sample (next-event estimation).
            path.vertices.push(vertex);
            let u = [
                uniform(rng) as f64,
                uniform(rng) as f64,
                uniform(rng) as f64,
            ];
            let drawn = LightDraw::sample(g, view, (&x, &material, frame), u)?;
            path.light = Some(LightVertex {
                end: drawn.end,
                wi: drawn.wi,
                pdf_sampled: absorption * drawn.pdf,
            });
            let f = bsdf::eval(material, frame, wo, drawn.wi).as_dvec3() * drawn.le;
            if f.max_element() > 0.0 {
                // In the light sample's own measure: area for an emitter point.
                self.nee = self.throughput * f * drawn.geometry;
                self.nee_escapes = drawn.end == LightEnd::Environment;
                return Some(Query::Shadow(drawn.shadow));
            }
            return None;
        }
        let (wi, pdf) = self.direction(g, rng, (material, frame), absorption)?;
        vertex.wi = wi;
        vertex.pdf_sampled = pdf;
        path.vertices.push(vertex);
        self.wi = wi;
        self.mirror = material.mirror;
        self.pdf_dir = pdf;
        Some(Query::Closest(view.spawn(&x, wi)))
    }

    /// [`Nee::Every`]: at a non-delta vertex a light point first (its shadow query comes
    /// first), then absorption or a direction (its closest-hit query after); at a delta
    /// vertex the mirror direction alone.
    fn scatter_every(
        &mut self,
        g: &PathGenerator,
        view: &SceneView,
        rng: &mut Rng,
        path: &mut PathVertices,
        material: MaterialAt,
    ) -> Option<Query> {
        let (x, wo) = (self.x, self.wo);
        let frame = Frame::facing(&x, wo);
        // Pushed first: the light point's contribution ends here whatever follows.
        path.vertices.push(PathVertex {
            point: x,
            wo,
            frame,
            wi: Vec3::ZERO,
            delta: material.mirror,
            pdf_sampled: 1.0,
        });
        self.then = None;
        let (shadow, absorption) = if material.mirror {
            (None, 0.0)
        } else {
            let shadow = self.light_point(g, view, rng, (material, frame));
            let a = g.absorption_after_light(self.k, self.bounce, self.max_bounces);
            (shadow, a)
        };
        if (uniform(rng) as f64) >= absorption {
            if let Some((wi, pdf)) = self.direction(g, rng, (material, frame), absorption) {
                if let Some(v) = path.vertices.last_mut() {
                    v.wi = wi;
                    v.pdf_sampled = pdf;
                }
                self.wi = wi;
                self.mirror = material.mirror;
                self.pdf_dir = pdf;
                self.then = Some(view.spawn(&x, wi));
            }
        }
        match shadow {
            Some(ray) => Some(Query::Shadow(ray)),
            None => self.then.take().map(Query::Closest),
        }
    }

    /// [`Nee::Every`]'s light sample at the current (non-delta) vertex, shading frame `frame`: its
    /// contribution (solid angle at the vertex, or a delta light's) becomes pending and its
    /// shadow ray is returned; `None` where it can carry nothing.
    fn light_point(
        &mut self,
        g: &PathGenerator,
        view: &SceneView,
        rng: &mut Rng,
        (material, frame): (MaterialAt, Frame),
    ) -> Option<Ray> {
        self.pending = None;
        if view.scene.light_count() == 0 {
            return None;
        }
        let u = [
            uniform(rng) as f64,
            uniform(rng) as f64,
            uniform(rng) as f64,
        ];
        let drawn = LightDraw::sample(g, view, (&self.x, &material, frame), u)?;
        let f = bsdf::eval(material, frame, self.wo, drawn.wi).as_dvec3() * drawn.le;
        // Also false for a NaN.
        let carries = f.max_element() > 0.0;
        if !carries {
            return None;
        }
        self.pending = Some(Contribution {
            f: self.throughput * f * f64::from(drawn.cos_x),
            len: self.bounce,
            nee: true,
            light: Some(Connection {
                end: drawn.end,
                wi: drawn.wi,
                area_to_solid_angle: drawn.area_to_solid_angle,
                pdf_sampled: drawn.pdf,
            }),
            escaped: drawn.end == LightEnd::Environment,
        });
        Some(drawn.shadow)
    }

    /// A direction out of the current vertex (shading frame `frame`), where the path goes on with
    /// probability `1 − absorption`: the delta BSDF's (a mirror's, or a dielectric's
    /// reflection or transmission, chosen by one more uniform number), or one from the
    /// generator's step; the throughput takes the BRDF × cos (a delta's weight). Returns it
    /// with its density `(1 − a)·p` (1 for a delta: see [`specular`]); `None` where it
    /// carries nothing.
    fn direction(
        &mut self,
        g: &PathGenerator,
        rng: &mut Rng,
        (material, frame): (MaterialAt, Frame),
        absorption: f64,
    ) -> Option<(Vec3, f64)> {
        let (x, wo) = (self.x, self.wo);
        if material.mirror {
            // Only a dielectric draws its choice: mirrors keep their random streams.
            let u = match material.dielectric {
                Some(_) => f64::from(uniform(rng)),
                None => 0.0,
            };
            let s = specular::sample(material, x.ns, wo, u)?;
            self.throughput *= s.weight.as_dvec3();
            return Some((s.wi, s.pdf));
        }
        let u = [
            uniform(rng) as f64,
            uniform(rng) as f64,
            uniform(rng) as f64,
        ];
        let (at, bsdf) = (x.p.as_dvec3(), (material, frame, wo));
        let s = match &g.steps[self.k].sampler {
            DirectionSampler::Brdf => bsdf::sample_scattered(material, frame, wo, u)?,
            DirectionSampler::Anchor(a) => {
                let wi = a.sample(at, u).as_vec3().normalize();
                scattered(bsdf, wi, a.pdf(at, wi.as_dvec3()))?
            }
            DirectionSampler::Patch(p) => {
                let wi = p.sample(at, u).as_vec3().normalize();
                scattered(bsdf, wi, p.pdf(at, wi.as_dvec3()))?
            }
        };
        if s.f.max_element() <= 0.0 {
            return None;
        }
        self.throughput *= s.f.as_dvec3() * s.cos as f64;
        self.k += 1;
        Some((s.wi, (1.0 - absorption) * s.pdf))
    }
}

/// A direction `wi` that a sampler other than the BSDF's drew with density `pdf`, with the
/// cosine and value there of the BSDF of `material` in `frame` seen from `wo`; `None` where
/// the material sends nothing into it (it may go anywhere above the surface, or anywhere off
/// it through a rough dielectric).
fn scattered(
    (material, frame, wo): (MaterialAt, Frame, Vec3),
    wi: Vec3,
    pdf: f64,
) -> Option<bsdf::Scattered> {
    Some(bsdf::Scattered {
        wi,
        pdf,
        cos: bsdf::cosine(&material, frame, wi)?,
        f: bsdf::eval(material, frame, wo, wi),
    })
}

/// A generator's light sample at a vertex `x` (see [`Receiver`]), before its shadow ray: the
/// emitter picked as `pt` picks it ([`crate::scene::Scene::pick_light`]), then a point from
/// the generator's light-point sampler on the area emitters, a direction towards the
/// environment, or a delta light.
struct LightDraw {
    end: LightEnd,
    /// Unit direction from `x` towards it, and its `|cos|` with the facing normal
    /// ([`bsdf::cosine`], positive).
    wi: Vec3,
    cos_x: f32,
    /// What arrives along `wi`: radiance, or a delta light's intensity / d² or irradiance.
    le: DVec3,
    /// `d² / cos_y` for an emitter point, else 1.
    area_to_solid_angle: f64,
    /// `cos_x · cos_y / d²` for an emitter point, else `cos_x`: the geometry term in the
    /// sample's own measure (with [`Nee::End`]).
    geometry: f64,
    /// [`PathGenerator::light_pdf`] of the sample.
    pdf: f64,
    shadow: Ray,
}

impl LightDraw {
    /// From three uniform numbers: `u[0]` picks the emitter (rescaled, it then serves the
    /// light-point sampler), the others place the point or direction. `None` where the
    /// sample cannot reach `x` (behind a surface that only reflects, facing away, or no
    /// emitter).
    fn sample(
        g: &PathGenerator,
        view: &SceneView,
        (x, material, frame): Receiver,
        u: [f64; 3],
    ) -> Option<Self> {
        let scene = view.scene;
        // The paper's light technique: the uniform pick (whatever `pt`'s light sampler), so
        // that every generator's density of a light end is the same but for its light-point
        // sampler ([`super::generator::fixed_light_pdf`]).
        let (pick, _, u0) = scene.pick_direct(LightSampler::Uniform, x.p, frame.n, u[0])?;
        let (end, wi, le, area, shadow) = match pick {
            DirectPick::Environment => {
                let env = scene.environment.as_ref()?;
                let (wi, le, _) = env.sample(u[1] as f32, u[2] as f32);
                (LightEnd::Environment, wi, le, (1.0, 1.0), view.spawn(x, wi))
            }
            DirectPick::Delta(i) => {
                let a = scene.delta_lights[i].arrival(x.p)?;
                let shadow = match a.position {
                    Some(p) => view.shadow_ray(x, &EndPoint { p, ng: Vec3::ZERO }),
                    None => view.spawn(x, a.wi),
                };
                (LightEnd::Delta, a.wi, a.value, (1.0, 1.0), shadow)
            }
            DirectPick::AreaGroup | DirectPick::Prim(_) => {
                let (y, prim) = g
                    .light
                    .sample(&scene.mesh, &scene.emitters, [u0, u[1], u[2]]);
                let y_point = EndPoint {
                    p: y.as_vec3(),
                    ng: scene.mesh.normal_at(prim, y).as_vec3(),
                };
                let d = y_point.p - x.p;
                let dist2 = d.length_squared();
                let wi = d / dist2.sqrt();
                let cos_y = -y_point.ng.dot(wi);
                if !(cos_y > 0.0 && dist2 > 0.0) {
                    return None;
                }
                let end = LightEnd::Area { point: y, prim };
                let le = view.material(prim).ke;
                let shadow = view.shadow_ray(x, &y_point);
                (end, wi, le, (cos_y, dist2), shadow)
            }
        };
        let cos_x = bsdf::cosine(material, frame, wi)?;
        let (cos_y, dist2) = area;
        let (area_to_solid_angle, geometry) = match end {
            LightEnd::Area { .. } => (
                f64::from(dist2) / f64::from(cos_y),
                cos_x as f64 * cos_y as f64 / dist2 as f64,
            ),
            _ => (1.0, f64::from(cos_x)),
        };
        Some(Self {
            end,
            wi,
            cos_x,
            le: le.as_dvec3(),
            area_to_solid_angle,
            geometry,
            pdf: g.light_pdf(view, &end, wi),
            shadow,
        })
    }
}
