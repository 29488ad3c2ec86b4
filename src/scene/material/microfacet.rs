//! Microfacet reflection and refraction as Mitsuba 3 models them: the Beckmann and GGX
//! distributions (`include/mitsuba/render/microfacet.h`), isotropic or anisotropic, with
//! Smith's masking-shadowing, sampled from the distribution of visible normals or from the
//! full distribution; and the three BSDFs built on them, `roughconductor`
//! ([`RoughConductor`]), `roughplastic` ([`RoughPlastic`]) and `roughdielectric`
//! ([`RoughDielectric`], the one that transmits).
//!
//! Everything here works in the local shading frame (`z` the normal facing `wo`, `x`
//! Mitsuba's `sh_frame.s`), in `f64`. `wo` is the direction towards the viewer (Mitsuba's
//! `si.wi`) and `wi` towards the light (Mitsuba's `wo`); values are BSDF values without the
//! cosine (Mitsuba's `eval` divided by `|cos θ_i|`).

use super::fresnel::{fresnel_conductor, fresnel_dielectric};
use super::TransportMode;
use crate::math::trig;
use glam::{DVec2, DVec3, Vec3};
use statrs::function::erf::{erf, erf_inv};
use std::f64::consts::{FRAC_1_PI, PI};

/// The microfacet normal distribution.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Distribution {
    Beckmann,
    /// GGX (Trowbridge–Reitz).
    Ggx,
}

impl Distribution {
    /// Mitsuba's name for it.
    pub fn name(self) -> &'static str {
        match self {
            Distribution::Beckmann => "beckmann",
            Distribution::Ggx => "ggx",
        }
    }
}

/// The smallest roughness, as Mitsuba clamps it.
pub const MIN_ALPHA: f64 = 1e-4;

/// A microfacet distribution: its kind, its roughness along the tangent (`alpha_u`) and the
/// bitangent (`alpha_v`), and how its normals are sampled.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Microfacet {
    pub distribution: Distribution,
    pub alpha_u: f64,
    pub alpha_v: f64,
    /// Sample the normals visible from `wo` (Heitz and d'Eon 2014), else the whole
    /// distribution `D(m) cos θ_m`.
    pub sample_visible: bool,
}

impl Microfacet {
    /// The distribution with its roughness clamped to [`MIN_ALPHA`], as Mitsuba's.
    pub fn new(
        distribution: Distribution,
        alpha_u: f64,
        alpha_v: f64,
        sample_visible: bool,
    ) -> Self {
        Self {
            distribution,
            alpha_u: alpha_u.max(MIN_ALPHA),
            alpha_v: alpha_v.max(MIN_ALPHA),
            sample_visible,
        }
    }

    pub fn is_isotropic(&self) -> bool {
        self.alpha_u == self.alpha_v
    }

    /// `D(m)`, the density of microfacet normals per projected area.
    pub fn d(&self, m: DVec3) -> f64 {
        let (au, av) = (self.alpha_u, self.alpha_v);
        let cos2 = m.z * m.z;
        let (x, y) = (m.x / au, m.y / av);
        let d = match self.distribution {
            Distribution::Beckmann => {
                (-(x * x + y * y) / cos2).exp() / (PI * au * av * cos2 * cos2)
            }
            Distribution::Ggx => {
                let q = x * x + y * y + cos2;
                1.0 / (PI * au * av * q * q)
            }
        };
        // Mitsuba's cut of a vanishing density (and of m below the surface).
        if d * m.z > 1e-20 {
            d
        } else {
            0.0
        }
    }

    /// Smith's masking function `G1(v, m)` (Beckmann through Mitsuba's rational fit, < 0.35 %
    /// from the exact one), 0 where `m` faces away from `v` or `v` from the surface.
    pub fn smith_g1(&self, v: DVec3, m: DVec3) -> f64 {
        if v.dot(m) * v.z <= 0.0 {
            return 0.0;
        }
        let xy = (self.alpha_u * v.x).powi(2) + (self.alpha_v * v.y).powi(2);
        if xy == 0.0 {
            return 1.0;
        }
        let tan2 = xy / (v.z * v.z);
        match self.distribution {
            Distribution::Beckmann => {
                let a = 1.0 / tan2.sqrt();
                if a >= 1.6 {
                    1.0
                } else {
                    (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a)
                }
            }
            Distribution::Ggx => 2.0 / (1.0 + (1.0 + tan2).sqrt()),
        }
    }

    /// `G(wo, wi, m)`, the separable masking-shadowing.
    pub fn g(&self, wo: DVec3, wi: DVec3, m: DVec3) -> f64 {
        self.smith_g1(wo, m) * self.smith_g1(wi, m)
    }

    /// The density of [`Self::sample`]'s normal `m` seen from `wo`, per solid angle of `m`.
    pub fn pdf(&self, wo: DVec3, m: DVec3) -> f64 {
        self.pdf_of(self.d(m), wo, m)
    }

    /// [`Self::pdf`] where `d` is `D(m)`, computed already.
    fn pdf_of(&self, d: f64, wo: DVec3, m: DVec3) -> f64 {
        if self.sample_visible {
            d * self.smith_g1(wo, m) * wo.dot(m).abs() / wo.z
        } else {
            d * m.z
        }
    }

    /// A microfacet normal from two uniform numbers, seen from `wo` (above the surface).
    pub fn sample(&self, wo: DVec3, u: [f64; 2]) -> DVec3 {
        if self.sample_visible {
            self.sample_visible_normal(wo, u)
        } else {
            self.sample_all(u)
        }
    }

    /// A normal of density `D(m) cos θ_m`.
    fn sample_all(&self, u: [f64; 2]) -> DVec3 {
        let (au, av) = (self.alpha_u, self.alpha_v);
        let (sin_phi, cos_phi, alpha2) = if self.is_isotropic() {
            let (s, c) = trig::sin_cos_turns(u[1]);
            (s, c, au * au)
        } else {
            let tmp = av / au * (2.0 * PI * u[1]).tan();
            let cos_phi = (1.0 / (tmp * tmp + 1.0).sqrt()).copysign((u[1] - 0.5).abs() - 0.25);
            let sin_phi = cos_phi * tmp;
            let alpha2 = 1.0 / ((cos_phi / au).powi(2) + (sin_phi / av).powi(2));
            (sin_phi, cos_phi, alpha2)
        };
        let cos_theta = match self.distribution {
            Distribution::Beckmann => 1.0 / (1.0 - alpha2 * (1.0 - u[0]).ln()).sqrt(),
            Distribution::Ggx => 1.0 / (1.0 + alpha2 * u[0] / (1.0 - u[0])).sqrt(),
        };
        let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
        DVec3::new(cos_phi * sin_theta, sin_phi * sin_theta, cos_theta)
    }

    /// A normal visible from `wo`: the slopes of the unit-roughness distribution seen at
    /// `wo` stretched back (Heitz and d'Eon 2014).
    fn sample_visible_normal(&self, wo: DVec3, u: [f64; 2]) -> DVec3 {
        let (au, av) = (self.alpha_u, self.alpha_v);
        let stretched = DVec3::new(au * wo.x, av * wo.y, wo.z).normalize();
        let sin2 = stretched.x * stretched.x + stretched.y * stretched.y;
        let (sin_phi, cos_phi) = if sin2 <= 4.0 * f64::from(f32::EPSILON) {
            (0.0, 1.0)
        } else {
            let inv = 1.0 / sin2.sqrt();
            (
                (stretched.y * inv).clamp(-1.0, 1.0),
                (stretched.x * inv).clamp(-1.0, 1.0),
            )
        };
        let slope = self.visible_slope(stretched.z, u);
        let slope = DVec2::new(
            (cos_phi * slope.x - sin_phi * slope.y) * au,
            (sin_phi * slope.x + cos_phi * slope.y) * av,
        );
        DVec3::new(-slope.x, -slope.y, 1.0).normalize()
    }

    /// The slopes of a visible normal of the unit-roughness distribution seen at
    /// `cos_theta` in the x–z plane.
    fn visible_slope(&self, cos_theta: f64, u: [f64; 2]) -> DVec2 {
        match self.distribution {
            Distribution::Beckmann => beckmann_visible_slope(cos_theta, u),
            Distribution::Ggx => {
                let p = concentric_disk(u);
                let s = 0.5 * (1.0 + cos_theta);
                let y = (1.0 - p.x * p.x).max(0.0).sqrt() * (1.0 - s) + p.y * s;
                let x = p.x;
                let z = (1.0 - x * x - y * y).max(0.0).sqrt();
                let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
                let norm = 1.0 / (sin_theta * y + cos_theta * z);
                DVec2::new((cos_theta * y - sin_theta * z) * norm, x * norm)
            }
        }
    }
}

/// Beckmann's visible slopes by Jakob's numerical inversion (Mitsuba's, three Newton steps
/// in the erf domain).
fn beckmann_visible_slope(cos_theta: f64, u: [f64; 2]) -> DVec2 {
    let tan_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt() / cos_theta;
    let cot_theta = 1.0 / tan_theta;
    let max_value = erf(cot_theta);
    let inv_sqrt_pi = 1.0 / PI.sqrt();
    let u = u.map(|x| x.clamp(1e-6, 1.0 - 1e-6));
    let mut x = max_value - (max_value + 1.0) * erf((-u[0].ln()).sqrt());
    let target =
        u[0] * (1.0 + max_value + inv_sqrt_pi * tan_theta * (-cot_theta * cot_theta).exp());
    for _ in 0..3 {
        let slope = erf_inv(x);
        let value = 1.0 + x + inv_sqrt_pi * tan_theta * (-slope * slope).exp() - target;
        let derivative = 1.0 - slope * tan_theta;
        x -= value / derivative;
    }
    DVec2::new(erf_inv(x), erf_inv(2.0 * u[1] - 1.0))
}

/// Shirley and Chiu's concentric map of the unit square onto the unit disk.
fn concentric_disk(u: [f64; 2]) -> DVec2 {
    let (x, y) = (2.0 * u[0] - 1.0, 2.0 * u[1] - 1.0);
    if x == 0.0 && y == 0.0 {
        return DVec2::ZERO;
    }
    // The angle `φ` in turns: `(π/4)(y/x)` or `π/2 − (π/4)(x/y)`.
    let (r, turns) = if x.abs() > y.abs() {
        (x, 0.125 * (y / x))
    } else {
        (y, 0.25 - 0.125 * (x / y))
    };
    let (sin_phi, cos_phi) = trig::sin_cos_turns(turns);
    DVec2::new(r * cos_phi, r * sin_phi)
}

/// `wo` mirrored about `m`.
fn reflect(wo: DVec3, m: DVec3) -> DVec3 {
    2.0 * wo.dot(m) * m - wo
}

/// What a microfacet reflection's value and density share at one pair of directions, both
/// above the surface: the unit half vector `h` of `wo` and `wi` and `D(h)`. Computed once
/// for both by an `eval_pdf`; `None` (nothing reflects) where either lies below.
#[derive(Clone, Copy, Debug)]
pub struct Halfway {
    h: DVec3,
    d: f64,
}

impl Halfway {
    /// The half vector of `wo` and `wi` under `distr`.
    pub fn of(distr: &Microfacet, wo: DVec3, wi: DVec3) -> Option<Self> {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return None;
        }
        let h = (wo + wi).normalize();
        Some(Self { h, d: distr.d(h) })
    }
}

/// The density in `wi` of reflecting `wo` about a normal drawn by `distr` (zero unless both
/// lie above the surface and on the front side of their half vector: Mitsuba's conditions).
fn reflection_pdf(distr: &Microfacet, wo: DVec3, wi: DVec3, half: Option<Halfway>) -> f64 {
    let Some(Halfway { h, d }) = half else {
        return 0.0;
    };
    if !(wo.dot(h) > 0.0 && wi.dot(h) > 0.0) {
        return 0.0;
    }
    if distr.sample_visible {
        d * distr.smith_g1(wo, h) / (4.0 * wo.z)
    } else {
        distr.pdf_of(d, wo, h) / (4.0 * wi.dot(h))
    }
}

/// `D G / (4 cos θ_o cos θ_i)` and the half vector: the microfacet reflection without its
/// Fresnel factor.
fn reflection(
    distr: &Microfacet,
    wo: DVec3,
    wi: DVec3,
    half: Option<Halfway>,
) -> Option<(f64, DVec3)> {
    let Halfway { h, d } = half?;
    (d != 0.0).then(|| (d * distr.g(wo, wi, h) / (4.0 * wo.z * wi.z), h))
}

/// Mitsuba's `roughconductor`: microfacet reflection off a conductor of complex index of
/// refraction `eta + i k` per channel, times `specular_reflectance`.
#[derive(Clone, Debug, PartialEq)]
pub struct RoughConductor {
    pub microfacet: Microfacet,
    pub eta: Vec3,
    pub k: Vec3,
    pub specular_reflectance: Vec3,
}

impl RoughConductor {
    /// `f(wo, wi)`, without the cosine.
    pub fn eval(&self, wo: DVec3, wi: DVec3) -> Vec3 {
        self.eval_with(self.specular_reflectance, wo, wi)
    }

    /// [`Self::eval`] with `specular_reflectance` in place of the lobe's own (a texture's
    /// value at the hit).
    pub fn eval_with(&self, specular_reflectance: Vec3, wo: DVec3, wi: DVec3) -> Vec3 {
        let half = Halfway::of(&self.microfacet, wo, wi);
        self.eval_at(specular_reflectance, wo, wi, half)
    }

    /// [`Self::eval_with`] at the half vector `half` of `wo` and `wi` ([`Halfway::of`]).
    pub fn eval_at(&self, specular: Vec3, wo: DVec3, wi: DVec3, half: Option<Halfway>) -> Vec3 {
        let Some((value, h)) = reflection(&self.microfacet, wo, wi, half) else {
            return Vec3::ZERO;
        };
        let fresnel = fresnel_conductor(wo.dot(h) as f32, self.eta, self.k);
        fresnel * specular * value as f32
    }

    pub fn pdf(&self, wo: DVec3, wi: DVec3) -> f64 {
        self.pdf_at(wo, wi, Halfway::of(&self.microfacet, wo, wi))
    }

    /// [`Self::pdf`] at the half vector `half` of `wo` and `wi` ([`Halfway::of`]).
    pub fn pdf_at(&self, wo: DVec3, wi: DVec3, half: Option<Halfway>) -> f64 {
        reflection_pdf(&self.microfacet, wo, wi, half)
    }

    /// A direction from two uniform numbers; it may lie below the surface (no energy).
    pub fn sample(&self, wo: DVec3, u: [f64; 2]) -> DVec3 {
        reflect(wo, self.microfacet.sample(wo, u))
    }
}

/// Mitsuba's `roughdielectric`: a rough interface between two dielectrics (Walter et al.
/// 2007), which reflects off and refracts through the microfacets with the dielectric
/// Fresnel equations, times `specular_reflectance` or `specular_transmittance`.
///
/// Its methods take `wo` in the local frame whose `z` faces `wo` (genpath's facing normal)
/// and `back`: whether that is the stored shading normal turned around, `wo` seen from
/// inside. The relative index `η` that light from `wo` meets is then `eta` (the interior's
/// over the exterior's, the exterior on the side of the stored normal) from the front and
/// `1/eta` from behind, as Mitsuba selects `m_eta` or `m_inv_eta` by the sign of `cos θ_i`;
/// mirroring Mitsuba's frame so that `wo` lies above changes nothing else, since its
/// distribution is symmetric. Transmitted radiance is scaled by `1/η²` (Mitsuba's radiance
/// mode, the smooth `dielectric`'s `η_ti²` of [`super::specular`]), which makes the
/// transmission `(1 − F) D G |wo·h| |wi·h| / (|cos θ_o| |cos θ_i| (wo·h + η wi·h)²)`;
/// transmitted importance ([`super::TransportMode::Importance`]) is not, and is `η²` times
/// that.
#[derive(Clone, Debug, PartialEq)]
pub struct RoughDielectric {
    pub microfacet: Microfacet,
    /// `int_ior / ext_ior`, in single precision as Mitsuba computes it.
    pub eta: f32,
    pub specular_reflectance: Vec3,
    pub specular_transmittance: Vec3,
}

impl RoughDielectric {
    /// The relative index of refraction light from `wo` meets: `eta` from the front of the
    /// stored normal, `1/eta` from behind it (`back`).
    pub fn eta_seen(&self, back: bool) -> f64 {
        let eta = f64::from(self.eta);
        if back {
            eta.recip()
        } else {
            eta
        }
    }

    /// The distribution normals are drawn from, seen from `wo`: the lobe's own with visible
    /// normals, else with its roughness scaled by `1.2 − 0.2 √cos θ_o` (Walter et al.'s
    /// trick against large weights, Mitsuba's `scale_alpha`, unclamped).
    pub fn sampling_distribution(&self, wo: DVec3) -> Microfacet {
        let d = self.microfacet;
        if d.sample_visible {
            return d;
        }
        let s = 1.2 - 0.2 * wo.z.abs().sqrt();
        Microfacet {
            alpha_u: d.alpha_u * s,
            alpha_v: d.alpha_v * s,
            ..d
        }
    }

    /// The microfacet normal that sends `wo` into `wi` — `wo + wi` for a reflection (`wi`
    /// above), `wo + η wi` for a refraction —, turned into the upper hemisphere, and whether
    /// it reflects; `None` where it does not exist or where the microsurface and the
    /// macrosurface disagree on a side (`wo · h` and `wi · h` against `cos θ`: Mitsuba's
    /// filter, which `G1` applies too).
    fn half(wo: DVec3, wi: DVec3, eta: f64) -> Option<(DVec3, bool)> {
        if wo.z <= 0.0 || wi.z == 0.0 {
            return None;
        }
        let reflect = wi.z > 0.0;
        let h = match reflect {
            true => wo + wi,
            false => wo + wi * eta,
        }
        .normalize();
        let h = if h.z < 0.0 { -h } else { h };
        (wo.dot(h) > 0.0 && wi.dot(h) * wi.z > 0.0).then_some((h, reflect))
    }

    /// `f(wo, wi)` without the cosine, for `wo` above the surface; `wi` anywhere on the
    /// sphere (see the type's documentation).
    pub fn eval(&self, wo: DVec3, wi: DVec3, back: bool) -> Vec3 {
        let reflectances = (self.specular_reflectance, self.specular_transmittance);
        self.eval_with(reflectances, wo, wi, back)
    }

    /// [`Self::eval`] with `specular_reflectance` and `specular_transmittance` in place of
    /// the lobe's own (textures' values at a hit).
    pub fn eval_with(
        &self,
        (specular_reflectance, specular_transmittance): (Vec3, Vec3),
        wo: DVec3,
        wi: DVec3,
        back: bool,
    ) -> Vec3 {
        let crossing = self.crossing(wo, wi, back);
        let reflectances = (specular_reflectance, specular_transmittance);
        self.eval_at(reflectances, wo, wi, crossing, TransportMode::Radiance)
    }

    /// What [`Self::eval_with`] and [`Self::pdf`] share at `wo`, `wi` (`None` where neither
    /// scatters).
    pub fn crossing(&self, wo: DVec3, wi: DVec3, back: bool) -> Option<Crossing> {
        let eta = self.eta_seen(back);
        let (h, reflect) = Self::half(wo, wi, eta)?;
        Some(Crossing {
            eta,
            h,
            reflect,
            d: self.microfacet.d(h),
            fresnel: fresnel_dielectric(wo.dot(h), eta).0,
        })
    }

    /// [`Self::eval_with`] at the [`Crossing`] of `wo` and `wi`, carrying light in `mode`:
    /// the transmission is scaled by `1/η²` for radiance and not for importance (see the
    /// type's documentation).
    pub fn eval_at(
        &self,
        (specular_reflectance, specular_transmittance): (Vec3, Vec3),
        wo: DVec3,
        wi: DVec3,
        crossing: Option<Crossing>,
        mode: TransportMode,
    ) -> Vec3 {
        let Some(Crossing {
            eta,
            h,
            reflect,
            d,
            fresnel,
        }) = crossing
        else {
            return Vec3::ZERO;
        };
        if d == 0.0 {
            return Vec3::ZERO;
        }
        let g = self.microfacet.g(wo, wi, h);
        let (cos_o, cos_i) = (wo.dot(h), wi.dot(h));
        if reflect {
            specular_reflectance * (fresnel * d * g / (4.0 * wo.z * wi.z)) as f32
        } else {
            let denom = cos_o + eta * cos_i;
            let value = (1.0 - fresnel) * d * g * (cos_o * cos_i).abs()
                / (wo.z * wi.z.abs() * denom * denom);
            let value = match mode {
                TransportMode::Radiance => value,
                TransportMode::Importance => value * (eta * eta),
            };
            specular_transmittance * value as f32
        }
    }

    /// The density of [`Self::sample`] in `wi` (solid angle, over the sphere): the sampled
    /// normal's density, times the Fresnel probability of the branch, times the Jacobian of
    /// the half-vector map, `1 / (4 |wi · h|)` for a reflection and `η² |wi · h| / (wo · h +
    /// η wi · h)²` for a refraction.
    pub fn pdf(&self, wo: DVec3, wi: DVec3, back: bool) -> f64 {
        self.pdf_at(wo, wi, self.crossing(wo, wi, back))
    }

    /// [`Self::pdf`] at the [`Crossing`] of `wo` and `wi`.
    pub fn pdf_at(&self, wo: DVec3, wi: DVec3, crossing: Option<Crossing>) -> f64 {
        let Some(Crossing {
            eta,
            h,
            reflect,
            d,
            fresnel,
        }) = crossing
        else {
            return 0.0;
        };
        let distr = self.sampling_distribution(wo);
        // With visible normals the sampling distribution is the lobe's own: `D(h)` is known.
        let p = match distr.sample_visible {
            true => distr.pdf_of(d, wo, h),
            false => distr.pdf(wo, h),
        };
        let (cos_o, cos_i) = (wo.dot(h), wi.dot(h));
        if reflect {
            p * fresnel / (4.0 * cos_i)
        } else {
            let denom = cos_o + eta * cos_i;
            p * (1.0 - fresnel) * eta * eta * cos_i.abs() / (denom * denom)
        }
    }

    /// A direction from three uniform numbers: a normal drawn by `u[1]`, `u[2]` (from
    /// [`Self::sampling_distribution`]), then reflection about it where `u[0]` is below its
    /// Fresnel reflectance (always under total internal reflection), refraction through it
    /// otherwise. `None` where the normal faces away from `wo`, or sends it to the side it
    /// cannot go (a reflection below the surface, a refraction above it), where Mitsuba's
    /// sample has weight 0.
    pub fn sample(&self, wo: DVec3, back: bool, u: [f64; 3]) -> Option<DVec3> {
        if wo.z <= 0.0 {
            return None;
        }
        let eta = self.eta_seen(back);
        let m = self.sampling_distribution(wo).sample(wo, [u[1], u[2]]);
        let cos_i = wo.dot(m);
        if cos_i.is_nan() || cos_i <= 0.0 {
            return None;
        }
        let (fresnel, cos_t, _, eta_ti) = fresnel_dielectric(cos_i, eta);
        if u[0] < fresnel {
            let wi = reflect(wo, m);
            (wi.z > 0.0).then_some(wi)
        } else {
            let wi = (m * (cos_i * eta_ti + cos_t) - wo * eta_ti).normalize();
            (wi.z < 0.0).then_some(wi)
        }
    }
}

/// What a rough dielectric's value and density share at one pair of directions
/// ([`RoughDielectric::crossing`]): the relative index seen from `wo`, the microfacet normal
/// that joins them and whether it reflects, `D` there and the Fresnel reflectance at `wo · h`.
#[derive(Clone, Copy, Debug)]
pub struct Crossing {
    eta: f64,
    h: DVec3,
    reflect: bool,
    d: f64,
    fresnel: f64,
}

/// Entries of the table of the coating's transmittance against `cos θ` (Mitsuba's
/// `MI_ROUGH_TRANSMITTANCE_RES`).
pub const TRANSMITTANCE_RES: usize = 64;

/// Mitsuba's `roughplastic`: a rough dielectric interface of relative index `eta` over a
/// Lambertian base. Reflection off the interface is a microfacet lobe; light that enters
/// reaches the base, and what leaves again is the base's albedo corrected for the
/// interface's internal reflections (`diffuse / (1 − F_dr)`, or `diffuse / (1 − diffuse
/// F_dr)` when `nonlinear`), times the interface's transmittance both ways over `eta²`.
#[derive(Clone, Debug, PartialEq)]
pub struct RoughPlastic {
    /// Isotropic.
    pub microfacet: Microfacet,
    /// `int_ior / ext_ior`.
    pub eta: f32,
    pub diffuse_reflectance: Vec3,
    pub specular_reflectance: Vec3,
    pub nonlinear: bool,
    /// The share of the specular lobe in sampling before the transmittance's: the
    /// specular reflectance's mean over both means.
    specular_sampling_weight: f64,
    /// The interface's hemispherical reflectance from inside, cosine-weighted (Mitsuba's
    /// `m_internal_reflectance`, the diffuse Fresnel reflectance of a rough interface).
    internal_reflectance: f64,
    /// The interface's transmittance into the coating at `cos θ = i / (RES − 1)`.
    external_transmittance: [f64; TRANSMITTANCE_RES],
}

impl RoughPlastic {
    /// The BSDF with Mitsuba's precomputed tables: the transmittance by Gauss–Legendre
    /// quadrature over visible normals (32² nodes for `eta > 1`, else 128²), and the
    /// internal reflectance from the reflectance seen from inside (relative index `1/eta`)
    /// at the same `cos θ`.
    pub fn new(
        microfacet: Microfacet,
        eta: f32,
        diffuse_reflectance: Vec3,
        specular_reflectance: Vec3,
        nonlinear: bool,
    ) -> Self {
        let mean = |c: Vec3| c.as_dvec3().element_sum() / 3.0;
        let s_mean = mean(specular_reflectance);
        let visible = Microfacet {
            sample_visible: true,
            ..microfacet
        };
        let eta64 = f64::from(eta);
        let mut external_transmittance = [0.0; TRANSMITTANCE_RES];
        let mut internal = 0.0;
        for (i, t) in external_transmittance.iter_mut().enumerate() {
            let mu = (i as f64 / (TRANSMITTANCE_RES - 1) as f64).max(1e-6);
            let wo = DVec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
            *t = coating_integral(&visible, wo, eta64, Coating::Transmittance);
            internal += coating_integral(&visible, wo, 1.0 / eta64, Coating::Reflectance) * mu;
        }
        Self {
            microfacet,
            eta,
            diffuse_reflectance,
            specular_reflectance,
            nonlinear,
            specular_sampling_weight: s_mean / (mean(diffuse_reflectance) + s_mean),
            internal_reflectance: 2.0 * internal / TRANSMITTANCE_RES as f64,
            external_transmittance,
        }
    }

    /// The interface's transmittance at `cos θ` (linear in the table, as Mitsuba's).
    pub fn transmittance(&self, cos_theta: f64) -> f64 {
        let x = cos_theta * (TRANSMITTANCE_RES - 1) as f64;
        let i = (x as usize).min(TRANSMITTANCE_RES - 2);
        let (a, b) = (
            self.external_transmittance[i],
            self.external_transmittance[i + 1],
        );
        a + (b - a) * (x - i as f64)
    }

    /// The probability of sampling the specular lobe, seen from `wo` (above the surface).
    pub fn specular_probability(&self, wo: DVec3) -> f64 {
        let t = self.transmittance(wo.z);
        let w = self.specular_sampling_weight;
        let (s, d) = ((1.0 - t) * w, t * (1.0 - w));
        s / (s + d)
    }

    /// `f(wo, wi)`, without the cosine: the interface's reflection and the base's light.
    pub fn eval(&self, wo: DVec3, wi: DVec3) -> Vec3 {
        let reflectances = (self.specular_reflectance, self.diffuse_reflectance);
        self.eval_with(reflectances, wo, wi)
    }

    /// [`Self::eval`] with the (specular, diffuse) reflectances `reflectances` in place of
    /// the lobe's own (textures' values at the hit). The share of specular sampling stays
    /// the one of the lobe's reflectances (a texture's mean, as in Mitsuba).
    pub fn eval_with(&self, reflectances: (Vec3, Vec3), wo: DVec3, wi: DVec3) -> Vec3 {
        let half = Halfway::of(&self.microfacet, wo, wi);
        self.eval_at(reflectances, wo, wi, half)
    }

    /// [`Self::eval_with`] at the half vector `half` of `wo` and `wi` ([`Halfway::of`]).
    pub fn eval_at(
        &self,
        (specular, kd): (Vec3, Vec3),
        wo: DVec3,
        wi: DVec3,
        half: Option<Halfway>,
    ) -> Vec3 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Vec3::ZERO;
        }
        let mut f = Vec3::ZERO;
        if let Some((value, h)) = reflection(&self.microfacet, wo, wi, half) {
            let fresnel = fresnel_dielectric(wo.dot(h), f64::from(self.eta)).0;
            f += specular * (fresnel * value) as f32;
        }
        let fdr = self.internal_reflectance as f32;
        let base = if self.nonlinear {
            kd / (Vec3::ONE - kd * fdr)
        } else {
            kd / (1.0 - fdr)
        };
        let through = self.transmittance(wo.z) * self.transmittance(wi.z);
        let inv_eta2 = 1.0 / (f64::from(self.eta) * f64::from(self.eta));
        f + base * (FRAC_1_PI * inv_eta2 * through) as f32
    }

    pub fn pdf(&self, wo: DVec3, wi: DVec3) -> f64 {
        self.pdf_at(wo, wi, Halfway::of(&self.microfacet, wo, wi))
    }

    /// [`Self::pdf`] at the half vector `half` of `wo` and `wi` ([`Halfway::of`]).
    pub fn pdf_at(&self, wo: DVec3, wi: DVec3, half: Option<Halfway>) -> f64 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let p = self.specular_probability(wo);
        p * reflection_pdf(&self.microfacet, wo, wi, half) + (1.0 - p) * wi.z * FRAC_1_PI
    }

    /// A direction from three uniform numbers: `u[0]` picks the lobe.
    pub fn sample(&self, wo: DVec3, u: [f64; 3]) -> DVec3 {
        if u[0] < self.specular_probability(wo) {
            reflect(wo, self.microfacet.sample(wo, [u[1], u[2]]))
        } else {
            let (r, (sin_phi, cos_phi)) = (u[1].sqrt(), trig::sin_cos_turns(u[2]));
            DVec3::new(r * cos_phi, r * sin_phi, (1.0 - u[1]).max(0.0).sqrt())
        }
    }
}

#[derive(Clone, Copy)]
enum Coating {
    Transmittance,
    Reflectance,
}

/// Mitsuba's `eval_transmittance` or `eval_reflectance` of a rough dielectric interface of
/// relative index `eta` at `wo`: the Fresnel transmittance (reflectance) of visible normals
/// times the masking of the refracted (reflected) direction, by Gauss–Legendre quadrature.
fn coating_integral(distr: &Microfacet, wo: DVec3, eta: f64, what: Coating) -> f64 {
    let nodes = crate::math::gauss_legendre(if eta > 1.0 { 32 } else { 128 });
    let mut sum = 0.0;
    for &(x, wx) in &nodes {
        for &(y, wy) in &nodes {
            let m = distr.sample(wo, [0.5 * x + 0.5, 0.5 * y + 0.5]);
            let cos_i = wo.dot(m);
            let (r, cos_t, _, eta_ti) = fresnel_dielectric(cos_i, eta);
            let value = match what {
                Coating::Transmittance => {
                    let wi = m * (cos_i * eta_ti + cos_t) - wo * eta_ti;
                    if wi.z * wo.z >= 0.0 {
                        0.0
                    } else {
                        distr.smith_g1(wi, m) * (1.0 - r)
                    }
                }
                Coating::Reflectance => {
                    let wi = reflect(wo, m);
                    if wi.z <= 0.0 || wo.z <= 0.0 {
                        0.0
                    } else {
                        distr.smith_g1(wi, m) * r
                    }
                }
            };
            sum += value * wx * wy * 0.25;
        }
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `∫ D(m) cos θ_m dm = 1` over the hemisphere, by a midpoint rule in (cos θ, φ).
    #[test]
    fn distributions_are_normalised() {
        for distribution in [Distribution::Beckmann, Distribution::Ggx] {
            for (au, av) in [(0.3, 0.3), (0.5, 0.1), (0.05, 0.2)] {
                let d = Microfacet::new(distribution, au, av, true);
                let (nt, np) = (4000, 400);
                let mut sum = 0.0;
                for i in 0..nt {
                    let c = (i as f64 + 0.5) / nt as f64;
                    let s = (1.0 - c * c).sqrt();
                    for j in 0..np {
                        let phi = 2.0 * PI * (j as f64 + 0.5) / np as f64;
                        sum += d.d(DVec3::new(s * phi.cos(), s * phi.sin(), c)) * c;
                    }
                }
                let integral = sum * 2.0 * PI / (nt * np) as f64;
                assert!(
                    (integral - 1.0).abs() < 2e-3,
                    "{distribution:?} {au} {av}: {integral}"
                );
            }
        }
    }

    /// The roughplastic tables are plausible: below the smooth interface's transmittance at
    /// normal incidence, falling towards grazing angles (their values against Mitsuba's are
    /// checked through `eval` in `tests/brdf_sampler`).
    #[test]
    fn transmittance_is_below_one_and_falls_at_grazing_angles() {
        let p = RoughPlastic::new(
            Microfacet::new(Distribution::Ggx, 0.2, 0.2, true),
            1.49,
            Vec3::splat(0.5),
            Vec3::ONE,
            false,
        );
        let normal = p.transmittance(1.0);
        // 1 − ((1.49 − 1)/(1.49 + 1))² at normal incidence, a little less for roughness.
        assert!(normal < 1.0 - 0.0387 && normal > 0.94, "{normal}");
        assert!(p.transmittance(0.05) < normal);
        assert!(p.internal_reflectance > 0.4 && p.internal_reflectance < 0.8);
    }
}
