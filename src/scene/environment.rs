//! The environment: Mitsuba's `constant` emitter, or its `envmap`
//! ([`super::envmap::EnvMap`]), whose light arrives from every direction that escapes the
//! scene.

use super::envmap::EnvMap;
use glam::Vec3;
use std::sync::Arc;

/// The environment emitter: radiance `radiance` from every direction (`constant`), or that
/// times an environment map's lookup (`envmap`, `radiance` its `scale`). Light sampling draws
/// a `constant`'s directions uniformly over the sphere (as Mitsuba's `constant` does, density
/// `1 / 4π`), and a map's by its own distribution.
#[derive(Clone, Debug)]
pub struct Environment {
    pub radiance: Vec3,
    pub map: Option<Arc<EnvMap>>,
    /// Fault injection for statistical tests: multiplies the density of the environment's
    /// directions wherever it is evaluated (not where it is sampled). 1 otherwise.
    pdf_scale: f64,
}

impl Environment {
    /// Mitsuba's `constant` emitter of `radiance`.
    pub fn new(radiance: Vec3) -> Self {
        Self {
            radiance,
            map: None,
            pdf_scale: 1.0,
        }
    }

    /// Mitsuba's `envmap`: `map`, times `scale`.
    pub fn map(map: EnvMap, scale: f32) -> Self {
        Self {
            radiance: Vec3::splat(scale),
            map: Some(Arc::new(map)),
            pdf_scale: 1.0,
        }
    }

    /// The mean of the radiance's channels over the sphere of directions.
    pub fn mean_radiance(&self) -> f64 {
        let r = self.radiance.as_dvec3();
        let mean = (r.x + r.y + r.z) / 3.0;
        match &self.map {
            None => mean,
            Some(map) => mean * map.mean_radiance(),
        }
    }

    /// The radiance that a ray leaving the scene along unit `dir` gathers.
    pub fn eval(&self, dir: Vec3) -> Vec3 {
        match &self.map {
            None => self.radiance,
            Some(map) => self.radiance * map.eval(dir.as_dvec3()),
        }
    }

    /// A unit direction drawn from two uniform numbers in [0, 1): uniform over the sphere,
    /// or by the map's distribution; with the radiance gathered along it ([`Self::eval`])
    /// and its density ([`Self::pdf`], the fault injection's factor included).
    pub fn sample(&self, u1: f32, u2: f32) -> (Vec3, Vec3, f64) {
        match &self.map {
            None => {
                let wi = crate::math::uniform_sphere(u1, u2);
                (
                    wi,
                    self.radiance,
                    self.pdf_scale / (4.0 * std::f64::consts::PI),
                )
            }
            Some(map) => {
                let s = map.sample([f64::from(u1), f64::from(u2)]);
                (
                    s.dir.as_vec3(),
                    self.radiance * s.radiance,
                    self.pdf_scale * s.pdf,
                )
            }
        }
    }

    /// [`Self::eval`] and [`Self::pdf`] at unit `dir`, the map's direction mapping computed
    /// once.
    pub fn eval_pdf(&self, dir: Vec3) -> (Vec3, f64) {
        match &self.map {
            None => (self.radiance, self.pdf(dir)),
            Some(map) => {
                let (radiance, pdf) = map.eval_pdf(dir.as_dvec3());
                (self.radiance * radiance, self.pdf_scale * pdf)
            }
        }
    }

    /// The solid-angle density of [`Self::sample`] at unit `dir`.
    pub fn pdf_solid_angle(&self, dir: Vec3) -> f64 {
        match &self.map {
            None => 1.0 / (4.0 * std::f64::consts::PI),
            Some(map) => map.pdf(dir.as_dvec3()),
        }
    }

    /// [`Self::pdf_solid_angle`] where `pt` evaluates it (times the fault injection's
    /// factor).
    pub fn pdf(&self, dir: Vec3) -> f64 {
        self.pdf_scale * self.pdf_solid_angle(dir)
    }

    /// The factor by which the density of a path that ends at the environment is
    /// evaluated: 1, but for the fault injection of [`Self::with_pdf_error`].
    pub fn escape_pdf_scale(&self) -> f64 {
        self.pdf_scale
    }

    /// This environment with its density deliberately scaled by `factor` where evaluated:
    /// `pt`'s light-sampling density of its directions, and the mixtures' density of paths
    /// that end at it. A wrong input that statistical tests must reject.
    #[cfg(any(test, feature = "testing"))]
    pub fn with_pdf_error(mut self, factor: f64) -> Self {
        self.pdf_scale = factor;
        self
    }
}
