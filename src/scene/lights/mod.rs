//! The emitters light sampling chooses between, and Mitsuba's delta lights (`point`,
//! `spot`, `directional`); every emitter's emission sampling for light-started paths
//! ([`emission`]), and the light sampler of next-event estimation ([`bvh`]).
//!
//! Next-event estimation picks a light by the light tree ([`bvh`], the default
//! [`LightSampler::Bvh`]): each light by an estimate of what it sends to the point. The
//! other picker, [`LightSampler::Uniform`], and the light-point technique of the path-level
//! mixtures, pick one emitter uniformly, as Mitsuba 3's scene does (`m_emitter_pmf = 1 / n`
//! when no emitter has a `sampling_weight`): the environment (a `constant` or `envmap`
//! emitter), each delta light, and the area emitters, which genpath takes as one emitter
//! whose points are then drawn by area (Mitsuba counts each emitting shape as one; both
//! choices are unbiased, and they agree where the area light is one shape).

pub mod bvh;
pub mod emission;

use glam::Vec3;

/// A light that no direction can find: only light sampling reaches it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DeltaLight {
    /// Mitsuba's `point`: `intensity` (radiant intensity per channel) from `position`; a
    /// point at distance `d` receives `intensity / d²`.
    Point { position: Vec3, intensity: Vec3 },
    /// Mitsuba's `spot`: a point light whose intensity falls off with the angle from its
    /// axis ([`Spot::falloff`]).
    Spot(Spot),
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
            DeltaLight::Spot(spot) => {
                let d = spot.position - x;
                let dist2 = d.length_squared();
                if !(dist2 > 0.0 && dist2.is_finite()) {
                    return None;
                }
                let wi = d / dist2.sqrt();
                let falloff = spot.falloff(-wi);
                (falloff > 0.0).then(|| DeltaArrival {
                    wi,
                    value: spot.intensity * (falloff / dist2),
                    position: Some(spot.position),
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

/// Mitsuba 3's `spot` (`src/emitters/spot.cpp`): `intensity` at the centre of the beam,
/// full out to `beam_width` from the axis, falling linearly in the angle to 0 at
/// `cutoff_angle`, nothing beyond.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spot {
    pub position: Vec3,
    /// Unit axis of the beam (`to_world` applied to +z).
    pub axis: Vec3,
    pub intensity: Vec3,
    /// The angles in radians, `0 < beam_width ≤ cutoff_angle < π`, and their cosines.
    pub cutoff_angle: f32,
    pub beam_width: f32,
    pub cos_cutoff: f32,
    pub cos_beam: f32,
}

impl Spot {
    /// The spot of `intensity` at `position` along unit `axis`, angles in degrees; `None`
    /// unless `0 < beam_width ≤ cutoff < 180°` (Mitsuba asserts the order).
    pub fn new(
        position: Vec3,
        axis: Vec3,
        intensity: Vec3,
        cutoff_deg: f32,
        beam_deg: f32,
    ) -> Option<Self> {
        if !(beam_deg > 0.0 && beam_deg <= cutoff_deg && cutoff_deg < 180.0) {
            return None;
        }
        let (cutoff_angle, beam_width) = (cutoff_deg.to_radians(), beam_deg.to_radians());
        Some(Self {
            position,
            axis,
            intensity,
            cutoff_angle,
            beam_width,
            cos_cutoff: cutoff_angle.cos(),
            cos_beam: beam_width.cos(),
        })
    }

    /// The fraction of `intensity` sent along unit direction `w` (away from the light):
    /// 1 inside the beam, `(cutoff − θ) / (cutoff − beam_width)` in the transition, 0 beyond
    /// the cutoff (Mitsuba's `falloff_curve`, in `f32` as its scalar variants).
    pub fn falloff(&self, w: Vec3) -> f32 {
        let cos_theta = w.dot(self.axis);
        if cos_theta <= self.cos_cutoff {
            0.0
        } else if cos_theta >= self.cos_beam {
            1.0
        } else {
            let theta = cos_theta.clamp(-1.0, 1.0).acos();
            ((self.cutoff_angle - theta) / (self.cutoff_angle - self.beam_width)).clamp(0.0, 1.0)
        }
    }
}

/// How next-event estimation picks the light it samples.
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    serde::Serialize,
    serde::Deserialize,
    clap::ValueEnum,
)]
#[serde(rename_all = "lowercase")]
pub enum LightSampler {
    /// The light tree where the scene has more than one light (each connected emitting
    /// surface counted as one, [`super::Scene::light_shapes`]), else uniform picking, which
    /// for a single light is its points by area, what picking per shape gives too.
    #[default]
    Auto,
    /// Mitsuba 3's uniform pick among the environment, each delta light and the area
    /// emitters taken as one, whose points are then drawn by area ([`super::Scene::pick_light`]).
    Uniform,
    /// The light tree ([`bvh::LightBvh`]): each light by what it may send to the point.
    Bvh,
}

impl LightSampler {
    /// The picker this one is in `scene`: [`Self::Auto`] resolved, the others as they are.
    pub fn resolve(self, scene: &super::Scene) -> Self {
        match self {
            Self::Auto if scene.light_shapes() > 1 => Self::Bvh,
            Self::Auto => Self::Uniform,
            other => other,
        }
    }
}

/// The emitter next-event estimation picked ([`super::Scene::pick_direct`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DirectPick {
    /// The environment, delta light `i`, or the area emitters as one (uniform picking).
    Environment,
    Delta(usize),
    AreaGroup,
    /// One emitting primitive (the light tree).
    Prim(u32),
}

/// What a scene builds about its lights on first use: the emitters by power, for emission
/// sampling, and the light tree, for next-event estimation with [`LightSampler::Bvh`].
#[derive(Clone, Debug, Default)]
pub struct LightTables {
    pub(super) emission: std::sync::OnceLock<Option<emission::EmissionTable>>,
    bvh: std::sync::OnceLock<bvh::LightBvh>,
    shapes: std::sync::OnceLock<usize>,
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

impl super::Scene {
    /// How many lights the scene has, counting each connected emitting surface as one (an
    /// analytic shape, or triangles that share a vertex position: a quad, a mesh lamp), as
    /// Mitsuba counts its emitting shapes; the environment and each delta light one each.
    pub fn light_shapes(&self) -> usize {
        *self.lights.shapes.get_or_init(|| {
            usize::from(self.environment.is_some())
                + self.delta_lights.len()
                + emitting_surfaces(&self.mesh, &self.emitters.prims)
        })
    }

    /// The light tree over the scene's lights (built once, on first use).
    pub fn light_bvh(&self) -> &bvh::LightBvh {
        self.lights.bvh.get_or_init(|| bvh::LightBvh::new(self))
    }

    /// The light that next-event estimation at `p` (unit normal `n`, or zero) samples, picked
    /// by `sampler` from a uniform `u` in [0, 1): the pick, its probability and `u`
    /// rescaled within the choice; `None` where no light can be picked.
    pub fn pick_direct(
        &self,
        sampler: LightSampler,
        p: Vec3,
        n: Vec3,
        u: f64,
    ) -> Option<(DirectPick, f64, f64)> {
        match sampler.resolve(self) {
            LightSampler::Uniform => {
                let (pick, rescaled) = self.pick_light(u)?;
                let pick = match pick {
                    LightPick::Environment => DirectPick::Environment,
                    LightPick::Delta(i) => DirectPick::Delta(i),
                    LightPick::Area => DirectPick::AreaGroup,
                };
                Some((pick, self.light_pmf(), rescaled))
            }
            LightSampler::Bvh | LightSampler::Auto => {
                let (emitter, pmf, rescaled) = self.light_bvh().sample(p, n, u)?;
                let pick = match emitter {
                    emission::Emitter::Environment => DirectPick::Environment,
                    emission::Emitter::Delta(i) => DirectPick::Delta(i as usize),
                    emission::Emitter::Area(prim) => DirectPick::Prim(prim),
                };
                Some((pick, pmf, rescaled))
            }
        }
    }

    /// The probability with which [`Self::pick_direct`] picks emitter `emitter` at `p`
    /// (normal `n`): with uniform picking, the area emitters' group's for a primitive.
    pub fn pmf_direct(
        &self,
        sampler: LightSampler,
        p: Vec3,
        n: Vec3,
        emitter: emission::Emitter,
    ) -> f64 {
        match sampler.resolve(self) {
            LightSampler::Uniform => match emitter {
                emission::Emitter::Environment => self.environment_share(),
                emission::Emitter::Delta(_) => self.light_pmf(),
                emission::Emitter::Area(_) => self.area_light_pmf(),
            },
            LightSampler::Bvh | LightSampler::Auto => self.light_bvh().pmf(self, p, n, emitter),
        }
    }
}

/// The connected surfaces the emitting primitives `prims` of `mesh` form: each analytic
/// shape alone, triangles joined where they share a vertex position (union-find).
fn emitting_surfaces(mesh: &crate::accel::TriangleMesh, prims: &[u32]) -> usize {
    let mut parent: Vec<usize> = (0..prims.len()).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    let mut first_at: std::collections::HashMap<[u32; 3], usize> = Default::default();
    for (k, &prim) in prims.iter().enumerate() {
        if mesh.analytic(prim).is_some() {
            continue;
        }
        for v in mesh.vertices(prim) {
            let key = v.to_array().map(f32::to_bits);
            let other = *first_at.entry(key).or_insert(k);
            let (a, b) = (root(&mut parent, k), root(&mut parent, other));
            parent[a] = b;
        }
    }
    (0..prims.len())
        .filter(|&k| root(&mut parent, k) == k)
        .count()
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
