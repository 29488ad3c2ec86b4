//! The emitters light sampling chooses between, and Mitsuba's delta lights (`point`,
//! `directional`).
//!
//! Light sampling (`pt`'s next-event estimation, and the light-point technique of the
//! path-level mixtures) first picks one emitter uniformly, as Mitsuba 3's scene does
//! (`m_emitter_pmf = 1 / n` when no emitter has a `sampling_weight`): the environment (a
//! `constant` or `envmap` emitter), each delta light, and the area emitters, which genpath
//! takes as one emitter whose points are then drawn by area (Mitsuba counts each emitting
//! shape as one; both choices are unbiased, and they agree where the area light is one shape).

use glam::Vec3;

/// A light that no direction can find: only light sampling reaches it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DeltaLight {
    /// Mitsuba's `point`: `intensity` (radiant intensity per channel) from `position`; a
    /// point at distance `d` receives `intensity / d²`.
    Point { position: Vec3, intensity: Vec3 },
    /// Mitsuba's `directional`: `irradiance` (on a surface perpendicular to it) arriving
    /// along the unit `direction` the light travels in.
    Directional { direction: Vec3, irradiance: Vec3 },
}

/// The emitter light sampling picked ([`super::Scene::pick_light`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightPick {
    /// The environment.
    Environment,
    /// Delta light `i` of [`super::Scene::delta_lights`].
    Delta(usize),
    /// A point on the area emitters.
    Area,
}

/// What reaches a point `x` from a delta light: the unit direction towards the light, the
/// radiance-like value a BSDF multiplies (intensity / d², or the irradiance), and the light's
/// position where it has one (a shadow ray ends there; otherwise it goes to infinity).
#[derive(Clone, Copy, Debug)]
pub struct DeltaArrival {
    pub wi: Vec3,
    pub value: Vec3,
    pub position: Option<Vec3>,
}

impl DeltaLight {
    /// What this light sends to `x`; `None` where `x` is the point light's position.
    pub fn arrival(&self, x: Vec3) -> Option<DeltaArrival> {
        match *self {
            DeltaLight::Point {
                position,
                intensity,
            } => {
                let d = position - x;
                let dist2 = d.length_squared();
                (dist2 > 0.0 && dist2.is_finite()).then(|| DeltaArrival {
                    wi: d / dist2.sqrt(),
                    value: intensity / dist2,
                    position: Some(position),
                })
            }
            DeltaLight::Directional {
                direction,
                irradiance,
            } => Some(DeltaArrival {
                wi: -direction,
                value: irradiance,
                position: None,
            }),
        }
    }
}

impl super::Scene {
    /// How many emitters light sampling chooses between: the environment, each delta light,
    /// and the area emitters as one.
    pub fn light_count(&self) -> usize {
        usize::from(self.environment.is_some())
            + self.delta_lights.len()
            + usize::from(!self.emitters.prims.is_empty())
    }

    /// The probability with which light sampling picks each emitter: `1 / light_count`
    /// (0 without any).
    pub fn light_pmf(&self) -> f64 {
        match self.light_count() {
            0 => 0.0,
            n => 1.0 / n as f64,
        }
    }

    /// The probability with which light sampling picks a point on the area emitters: 0
    /// without them.
    pub fn area_light_pmf(&self) -> f64 {
        if self.emitters.prims.is_empty() {
            0.0
        } else {
            self.light_pmf()
        }
    }

    /// The emitter picked by a uniform `u` in [0, 1), in the order environment, delta lights,
    /// area emitters, and `u` rescaled to [0, 1) within its share (unchanged where there is
    /// one emitter, so that an area-only scene draws the numbers it always drew); `None`
    /// without emitters.
    pub fn pick_light(&self, u: f64) -> Option<(LightPick, f64)> {
        let n = self.light_count();
        if n == 0 {
            return None;
        }
        let (i, rescaled) = if n == 1 {
            (0, u)
        } else {
            let i = ((u * n as f64) as usize).min(n - 1);
            let pmf = 1.0 / n as f64;
            (i, ((u - i as f64 * pmf) / pmf).clamp(0.0, 1.0))
        };
        let env = usize::from(self.environment.is_some());
        let pick = if i < env {
            LightPick::Environment
        } else if i - env < self.delta_lights.len() {
            LightPick::Delta(i - env)
        } else {
            LightPick::Area
        };
        Some((pick, rescaled))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_point_light_falls_off_with_the_square_of_the_distance() {
        let light = DeltaLight::Point {
            position: Vec3::new(0.0, 2.0, 0.0),
            intensity: Vec3::splat(8.0),
        };
        let a = light.arrival(Vec3::ZERO).unwrap();
        assert_eq!(a.wi, Vec3::Y);
        assert_eq!(a.value, Vec3::splat(2.0));
        assert!(light.arrival(Vec3::new(0.0, 2.0, 0.0)).is_none());
        let sun = DeltaLight::Directional {
            direction: -Vec3::Y,
            irradiance: Vec3::ONE,
        };
        let a = sun.arrival(Vec3::splat(5.0)).unwrap();
        assert_eq!((a.wi, a.value, a.position), (Vec3::Y, Vec3::ONE, None));
    }
}
