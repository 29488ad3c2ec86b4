//! Emission sampling: a point on a light and a direction leaving it, for paths that start at
//! the lights (pbrt-v4's `Light::SampleLe` / `PDF_Le`, Mitsuba 3's `Emitter::sample_ray`).
//!
//! Every emitter genpath loads is one [`Emitter`]: each emitting primitive (triangle, sphere,
//! disk), each delta light (`point`, `spot`, `directional`) and the environment (`constant`,
//! `envmap`). One is picked by its power ([`Emitter::power`], an [`AliasTable`]); then
//!
//! * an area emitter's point is uniform by area and its direction cosine-distributed about
//!   its normal, on the side it emits to (one-sided, as genpath's area lights);
//! * a point light's direction is uniform over the sphere, a spot's uniform in its cutoff
//!   cone (Mitsuba's `sample_ray`);
//! * a directional light's and the environment's light enters through a disk that covers the
//!   scene: the scene's bounding sphere seen along the direction, a point uniform on it; the
//!   environment's direction drawn as its light sampling draws it.
//!
//! Densities are kept apart: of the position (per unit area; a delta position has none),
//! and of the direction (per unit solid angle; a delta direction has none), as light tracing
//! and bidirectional methods need them.

use super::DeltaLight;
use crate::accel::concentric_disk;
use crate::math::alias::AliasTable;
use crate::math::{basis, uniform_in_triangle};
use crate::scene::Scene;
use glam::{DVec3, Vec3};
use std::f64::consts::PI;

/// One emitter of the scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Emitter {
    /// The `constant` or `envmap` emitter.
    Environment,
    /// Delta light `i` of [`Scene::delta_lights`].
    Delta(u32),
    /// An emitting primitive (triangle or analytic shape).
    Area(u32),
}

/// A ray leaving a light: where, which way, what it carries, and its densities.
#[derive(Clone, Copy, Debug)]
pub struct EmissionSample {
    pub emitter: Emitter,
    /// The ray's origin and unit direction.
    pub origin: Vec3,
    pub dir: Vec3,
    /// The unit normal at the origin (an area emitter's; the direction itself for the
    /// environment's and a directional light's disk; zero for a point or spot).
    pub normal: Vec3,
    /// Radiance (area, environment), intensity in `dir` (point, spot, the spot's falloff
    /// included) or irradiance (directional).
    pub value: Vec3,
    /// The probability of the emitter's pick.
    pub pick: f64,
    /// Density of the origin per unit area; 1 for a delta position (point, spot).
    pub pdf_pos: f64,
    /// Density of the direction per unit solid angle; 1 for a delta direction
    /// (directional).
    pub pdf_dir: f64,
    pub delta_pos: bool,
    pub delta_dir: bool,
}

impl EmissionSample {
    /// What the ray carries per unit of its densities: `value · |cos| / (pick · pdf_pos ·
    /// pdf_dir)` (the cosine at the origin; 1 for a disk, a point or a spot), the weight a
    /// light path starts with.
    pub fn weight(&self) -> DVec3 {
        let cos = if self.normal == Vec3::ZERO {
            1.0
        } else {
            f64::from(self.normal.dot(self.dir).abs())
        };
        self.value.as_dvec3() * (cos / (self.pick * self.pdf_pos * self.pdf_dir))
    }
}

/// The densities of a ray leaving an emitter ([`Scene::pdf_emission`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmissionPdf {
    pub pick: f64,
    pub pos: f64,
    pub dir: f64,
}

/// The emitters of a scene by power, and the sphere that bounds the scene (for the
/// environment's and directional lights' entry disk). Built once, on first use.
#[derive(Clone, Debug)]
pub struct EmissionTable {
    pub emitters: Vec<Emitter>,
    table: AliasTable,
    pub center: DVec3,
    pub radius: f64,
}

impl Scene {
    /// Every emitter: the environment, the delta lights, the emitting primitives, in that
    /// order.
    pub fn all_emitters(&self) -> Vec<Emitter> {
        let env = self.environment.iter().map(|_| Emitter::Environment);
        let delta = (0..self.delta_lights.len() as u32).map(Emitter::Delta);
        let area = self.emitters.prims.iter().map(|&p| Emitter::Area(p));
        env.chain(delta).chain(area).collect()
    }

    /// The place of `emitter` in [`Self::all_emitters`]' order; `None` for one the scene
    /// lacks.
    pub fn emitter_index(&self, emitter: Emitter) -> Option<usize> {
        let env = usize::from(self.environment.is_some());
        match emitter {
            Emitter::Environment => (env == 1).then_some(0),
            Emitter::Delta(i) => ((i as usize) < self.delta_lights.len()).then(|| env + i as usize),
            Emitter::Area(prim) => (self.emitters.prims.binary_search(&prim).ok())
                .map(|k| env + self.delta_lights.len() + k),
        }
    }

    /// The sphere that bounds the scene's geometry: centre and radius (at least a tiny
    /// positive one).
    pub fn bounding_sphere(&self) -> (DVec3, f64) {
        let (lo, hi) = self.mesh.bounds();
        if !(lo.cmple(hi).all()) {
            return (DVec3::ZERO, 1.0);
        }
        let (lo, hi) = (lo.as_dvec3(), hi.as_dvec3());
        let center = 0.5 * (lo + hi);
        (center, (0.5 * (hi - lo).length()).max(1e-6))
    }

    /// The power of `emitter` (the mean of its channels; what emission sampling picks it
    /// by): `π·A·L` for an area emitter, `4π·I` for a point, the spot's intensity over its
    /// cone with the transition counted half, `π r²·E` for a directional light and `π r²·4π`
    /// times the mean radiance for the environment (`r` the scene's bounding radius).
    pub fn power(&self, emitter: Emitter, radius: f64) -> f64 {
        let mean = |v: Vec3| f64::from(v.x + v.y + v.z) / 3.0;
        let disk = PI * radius * radius;
        match emitter {
            Emitter::Area(prim) => PI * self.mesh.area(prim) * mean(self.material(prim).ke),
            Emitter::Delta(i) => match &self.delta_lights[i as usize] {
                DeltaLight::Point { intensity, .. } => 4.0 * PI * mean(*intensity),
                DeltaLight::Spot(s) => {
                    let cos = 0.5 * (f64::from(s.cos_beam) + f64::from(s.cos_cutoff));
                    2.0 * PI * (1.0 - cos) * mean(s.intensity)
                }
                DeltaLight::Directional { irradiance, .. } => disk * mean(*irradiance),
            },
            Emitter::Environment => {
                let env = self.environment.as_ref().expect("an environment emitter");
                disk * 4.0 * PI * env.mean_radiance()
            }
        }
    }

    /// The scene's emitters by power (built once, on first use).
    pub fn emission_table(&self) -> Option<&EmissionTable> {
        self.lights
            .emission
            .get_or_init(|| {
                let (center, radius) = self.bounding_sphere();
                let emitters = self.all_emitters();
                let power: Vec<f64> = emitters.iter().map(|&e| self.power(e, radius)).collect();
                AliasTable::new(&power).map(|table| EmissionTable {
                    emitters,
                    table,
                    center,
                    radius,
                })
            })
            .as_ref()
    }

    /// A ray leaving a light from five uniform numbers in [0, 1): `u[0]` picks the emitter by
    /// power, `u[1..3]` place the origin, `u[3..5]` the direction. `None` without emitters
    /// or where the sample carries nothing (a spot's direction in no beam, a dark map).
    pub fn sample_emission(&self, u: [f64; 5]) -> Option<EmissionSample> {
        let table = self.emission_table()?;
        let (i, pick, _) = table.table.sample(u[0]);
        self.emit(table.emitters[i], pick, [u[1], u[2], u[3], u[4]])
    }

    /// [`Self::sample_emission`] once `emitter` is picked with probability `pick`: `u[0..2]`
    /// place the origin, `u[2..4]` the direction.
    pub fn emit(&self, emitter: Emitter, pick: f64, u: [f64; 4]) -> Option<EmissionSample> {
        let table = self.emission_table()?;
        let (center, radius) = (table.center, table.radius);
        let u = [0.0, u[0], u[1], u[2], u[3]];
        let sample = match emitter {
            Emitter::Area(prim) => {
                let (p, n) = self.area_point(prim, u[1], u[2]);
                let local = cosine_hemisphere(u[3], u[4]);
                let (t, b) = basis(n);
                let dir = (t * local.x + b * local.y + n * local.z).normalize();
                EmissionSample {
                    emitter,
                    origin: p.as_vec3(),
                    dir: dir.as_vec3(),
                    normal: n.as_vec3(),
                    value: self.material(prim).ke,
                    pick,
                    pdf_pos: 1.0 / self.mesh.area(prim),
                    pdf_dir: local.z / PI,
                    delta_pos: false,
                    delta_dir: false,
                }
            }
            Emitter::Delta(d) => match self.delta_lights[d as usize] {
                DeltaLight::Point {
                    position,
                    intensity,
                } => EmissionSample {
                    emitter,
                    origin: position,
                    dir: crate::math::uniform_sphere(u[3] as f32, u[4] as f32),
                    normal: Vec3::ZERO,
                    value: intensity,
                    pick,
                    pdf_pos: 1.0,
                    pdf_dir: 1.0 / (4.0 * PI),
                    delta_pos: true,
                    delta_dir: false,
                },
                DeltaLight::Spot(s) => {
                    let local = uniform_cone(u[3], u[4], f64::from(s.cos_cutoff));
                    let axis = s.axis.as_dvec3();
                    let (t, b) = basis(axis);
                    let dir = (t * local.x + b * local.y + axis * local.z)
                        .normalize()
                        .as_vec3();
                    EmissionSample {
                        emitter,
                        origin: s.position,
                        dir,
                        normal: Vec3::ZERO,
                        value: s.intensity * s.falloff(dir),
                        pick,
                        pdf_pos: 1.0,
                        pdf_dir: uniform_cone_pdf(f64::from(s.cos_cutoff)),
                        delta_pos: true,
                        delta_dir: false,
                    }
                }
                DeltaLight::Directional {
                    direction,
                    irradiance,
                } => {
                    let w = direction.as_dvec3();
                    EmissionSample {
                        emitter,
                        origin: disk_origin(center, radius, w, u[1], u[2]).as_vec3(),
                        dir: direction,
                        normal: direction,
                        value: irradiance,
                        pick,
                        pdf_pos: 1.0 / (PI * radius * radius),
                        pdf_dir: 1.0,
                        delta_pos: false,
                        delta_dir: true,
                    }
                }
            },
            Emitter::Environment => {
                let env = self.environment.as_ref()?;
                // The direction towards the environment, as its light sampling draws it;
                // the light travels the other way.
                let (towards, radiance, pdf) = env.sample(u[3] as f32, u[4] as f32);
                let w = -towards.as_dvec3();
                EmissionSample {
                    emitter,
                    origin: disk_origin(center, radius, w, u[1], u[2]).as_vec3(),
                    dir: w.as_vec3(),
                    normal: w.as_vec3(),
                    value: radiance,
                    pick,
                    pdf_pos: 1.0 / (PI * radius * radius),
                    pdf_dir: pdf,
                    delta_pos: false,
                    delta_dir: false,
                }
            }
        };
        let carries = sample.value.max_element() > 0.0 && sample.pdf_dir > 0.0;
        carries.then_some(sample)
    }

    /// The densities with which [`Self::sample_emission`] draws a ray leaving `emitter` from
    /// `origin` along unit `dir` (`origin` on the emitter: a point of an area emitter, any
    /// point of the entry disk; unused for a point or spot).
    pub fn pdf_emission(&self, emitter: Emitter, origin: Vec3, dir: Vec3) -> Option<EmissionPdf> {
        let table = self.emission_table()?;
        let pick = table.table.pmf(self.emitter_index(emitter)?);
        let radius = table.radius;
        let disk = 1.0 / (PI * radius * radius);
        let (pos, dir) = match emitter {
            Emitter::Area(prim) => {
                let n = self.mesh.normal_at(prim, origin.as_dvec3());
                let cos = n.dot(dir.as_dvec3());
                (1.0 / self.mesh.area(prim), cos.max(0.0) / PI)
            }
            Emitter::Delta(d) => match &self.delta_lights[d as usize] {
                DeltaLight::Point { .. } => (1.0, 1.0 / (4.0 * PI)),
                DeltaLight::Spot(s) => {
                    let inside = f64::from(dir.dot(s.axis)) >= f64::from(s.cos_cutoff);
                    (
                        1.0,
                        f64::from(u8::from(inside)) * uniform_cone_pdf(f64::from(s.cos_cutoff)),
                    )
                }
                DeltaLight::Directional { .. } => (disk, 1.0),
            },
            Emitter::Environment => {
                let env = self.environment.as_ref()?;
                (disk, env.pdf(-dir))
            }
        };
        Some(EmissionPdf { pick, pos, dir })
    }

    /// A point uniform by area on emitting primitive `prim` and its unit normal there.
    pub fn area_point(&self, prim: u32, u1: f64, u2: f64) -> (DVec3, DVec3) {
        match self.mesh.analytic(prim) {
            Some(shape) => {
                let p = shape.sample_area(u1, u2);
                (p, shape.normal_at(p))
            }
            None => {
                let vertices = self.mesh.vertices(prim).map(|v| v.as_dvec3());
                let p = uniform_in_triangle(vertices, u1, u2);
                (p, self.mesh.normals[prim as usize].as_dvec3())
            }
        }
    }
}

/// The origin of a ray entering the scene along unit `w` through the disk of the bounding
/// sphere (`center`, `radius`) perpendicular to `w`: a point uniform on the disk, moved back
/// by `radius` so that the ray starts outside the sphere.
pub fn disk_origin(center: DVec3, radius: f64, w: DVec3, u1: f64, u2: f64) -> DVec3 {
    let (t, b) = basis(w);
    let (x, y) = concentric_disk(u1, u2);
    center + (t * x + b * y) * radius - w * radius
}

/// A direction about +z with density `cos θ / π` (Malley's method).
pub fn cosine_hemisphere(u1: f64, u2: f64) -> DVec3 {
    let (x, y) = concentric_disk(u1, u2);
    DVec3::new(x, y, (1.0 - x * x - y * y).max(0.0).sqrt())
}

/// A direction uniform in the cone `cos θ ≥ cos_max` about +z (Mitsuba's
/// `square_to_uniform_cone`).
pub fn uniform_cone(u1: f64, u2: f64, cos_max: f64) -> DVec3 {
    let cos = 1.0 - u1 * (1.0 - cos_max);
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let (s, c) = (2.0 * PI * u2).sin_cos();
    DVec3::new(sin * c, sin * s, cos)
}

/// The density of [`uniform_cone`]: `1 / (2π (1 − cos_max))`.
pub fn uniform_cone_pdf(cos_max: f64) -> f64 {
    1.0 / (2.0 * PI * (1.0 - cos_max))
}
