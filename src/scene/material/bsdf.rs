//! The BSDF of genpath's materials and its sampler: a two-sided Lambertian lobe plus a
//! glossy lobe ([`Glossy`]: normalised modified Phong, Mitsuba's rough conductor, rough
//! plastic or rough dielectric, [`super::microfacet`], or a smooth plastic's diffuse choice,
//! [`super::SmoothPlastic`]), the Lambertian one chosen by albedo;
//! or a delta BSDF (an ideal mirror or conductor here; smooth dielectrics, which tell their
//! sides apart, in [`super::specular`]). This is the one BSDF interface of every method:
//! `pt`, `pg`, `srt`, `mixture`, `ga` and `ga-pt` evaluate, weigh and sample every non-delta
//! lobe through it (the GA's BRDF sampler is [`sample`]).
//!
//! Directions are unit vectors pointing away from the surface; the [`Frame`]'s `n` is the
//! shading normal (the geometric one where a mesh has no vertex normals) turned to the side
//! of `wo` ([`facing_normal`]), its `s` Mitsuba's shading tangent, which only anisotropic
//! lobes read, and `back` whether `n` is the stored normal turned around (which a rough
//! dielectric's index of refraction depends on). Densities are solid-angle densities over
//! the full sphere (zero below the surface for the Lambertian lobe), in `f64`.
//!
//! Every lobe but the rough dielectric's reflects only, into the hemisphere of `n`: [`eval`]
//! is zero below it. The rough dielectric ([`Material::transmits`]) scatters into the whole
//! sphere, and what scatters into `wi` is weighed by `|cos θ_i|`: [`cosine`] is the one
//! place that says which directions a material can send light into, and with which
//! cosine, for every caller (the samplers here, the path tracer's and the generators'
//! next-event estimation, the guide's samples).
//!
//! The interface: [`eval`], [`pdf`], [`eval_pdf`] (both at once, bit for bit theirs, with
//! the work they share done once: Mitsuba's `eval_pdf`), [`sample`] (and its parts,
//! [`sample_direction`], [`sample_scattered`]) and [`cosine`], in the [`Frame`]'s
//! [`TransportMode`]: for a path started at a light, [`TransportMode::Importance`] makes
//! the value and a sample's weight the adjoint's. For a material that chooses its lobe at
//! the hit (a smooth plastic), the choice's probability seen from either direction
//! ([`delta_choice`]) and the non-delta part before the choice ([`eval_non_delta`],
//! [`pdf_non_delta`]).

use super::microfacet::{Crossing, Halfway, Microfacet, RoughDielectric};
use super::{facing_normal, reflect, specular, BrdfSample};
use super::{Glossy, Material, MaterialAt, TransportMode};
use crate::scene::{normals, SurfacePoint};
use glam::{DVec3, Vec3};
use std::cell::OnceCell;
use std::f64::consts::{FRAC_1_PI, PI};

/// The shading frame a BSDF scatters in at one vertex.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// The unit shading normal, turned towards `wo`.
    pub n: Vec3,
    /// Mitsuba's unit shading tangent (`sh_frame.s`), orthogonal to `n`; read only by
    /// anisotropic lobes (zero, any tangent, for the others).
    pub s: Vec3,
    /// Whether `n` is the stored shading normal turned around: `wo` lies behind the surface
    /// (inside a dielectric, whose exterior is on the stored normal's side). Read only by
    /// the rough dielectric.
    pub back: bool,
    /// Where a normal or bump map perturbs the frame (`n` is then the perturbed normal):
    /// the unperturbed shading normal, turned with `n`; zero elsewhere. No light scatters
    /// into a `wi` on different sides of `n` and `base`, and what scatters is attenuated by
    /// Mitsuba's shadowing term ([`crate::scene::normals`]).
    pub base: Vec3,
    /// The geometric normal (either orientation), read only in
    /// [`TransportMode::Importance`] for the shading-normal correction; zero where there is
    /// none to correct for (the shading normal is the geometric one).
    pub ng: Vec3,
    /// Which way the path that scatters here carries light: the BSDF's value and a sample's
    /// weight are the adjoint's in [`TransportMode::Importance`].
    pub mode: TransportMode,
}

impl Frame {
    /// The frame of normal `n` (facing `wo`, on the stored normal's side) and tangent `s`.
    pub fn new(n: Vec3, s: Vec3) -> Self {
        Self {
            n,
            s,
            back: false,
            base: Vec3::ZERO,
            ng: Vec3::ZERO,
            mode: TransportMode::Radiance,
        }
    }

    /// The frame of normal `n` facing `wo` where the stored normal is `−n` (`wo` behind the
    /// surface), tangent `s`.
    pub fn behind(n: Vec3, s: Vec3) -> Self {
        Self {
            back: true,
            ..Self::new(n, s)
        }
    }

    /// This frame for a path that carries light in `mode` (see [`Frame::mode`]).
    pub fn with_mode(self, mode: TransportMode) -> Self {
        Self { mode, ..self }
    }

    /// This frame at a point of geometric normal `ng` (see [`Frame::ng`]).
    pub fn with_geometric_normal(self, ng: Vec3) -> Self {
        Self { ng, ..self }
    }

    /// The frame at `x` seen from `wo`: about its shading normal, or about its normal or
    /// bump map's as the nested BSDF sees it from `wo` ([`normals::resolve`]; lobes inside a
    /// map are isotropic, so any tangent serves).
    pub fn facing(x: &SurfacePoint, wo: Vec3) -> Self {
        if x.np != Vec3::ZERO {
            let (n, base) = normals::resolve(x.ns, x.np, x.np_twosided_outside, wo);
            // Turned towards `wo` (a two-sided BSDF inside the map; one-sided ones seen from
            // behind are black already).
            let (n, base) = match n.dot(wo) >= 0.0 {
                true => (n, base),
                false => (-n, -base),
            };
            return Self {
                n,
                s: Vec3::ZERO,
                back: false,
                base,
                ng: x.ng,
                mode: TransportMode::Radiance,
            };
        }
        let n = facing_normal(x.ns, wo);
        Self {
            n,
            s: x.ts,
            back: n != x.ns,
            base: Vec3::ZERO,
            ng: x.ng,
            mode: TransportMode::Radiance,
        }
    }

    /// The shading-normal correction of [`TransportMode::correction`], about this frame's
    /// normal and geometric normal, in its mode.
    pub fn adjoint_correction(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.mode.correction(self.n, self.ng, wo, wi)
    }

    /// The orthonormal basis (s, t, n) in `f64`: `s` made orthogonal to `n`, or any tangent
    /// where it is zero.
    fn basis(&self) -> [DVec3; 3] {
        let n = self.n.as_dvec3().normalize();
        let s = self.s.as_dvec3();
        let s = (s - n * n.dot(s)).normalize_or_zero();
        let s = if s == DVec3::ZERO {
            crate::math::basis(n).0
        } else {
            s
        };
        [s, n.cross(s), n]
    }

    fn to_local(basis: &[DVec3; 3], w: Vec3) -> DVec3 {
        let w = w.as_dvec3().normalize();
        DVec3::new(basis[0].dot(w), basis[1].dot(w), basis[2].dot(w))
    }

    fn to_world(basis: &[DVec3; 3], l: DVec3) -> Vec3 {
        (basis[0] * l.x + basis[1] * l.y + basis[2] * l.z)
            .normalize()
            .as_vec3()
    }
}

fn channel_sum(c: Vec3) -> f64 {
    (c.x + c.y + c.z) as f64
}

/// Probability of sampling the Lambertian lobe rather than the glossy lobe: by albedo
/// (Phong's `ks`, a microfacet lobe's reflectance), at the hit; 1 without a glossy lobe.
fn diffuse_probability(m: &MaterialAt) -> f64 {
    if matches!(m.glossy, Glossy::None) {
        return 1.0;
    }
    let (specular, diffuse) = m.glossy_reflectances();
    let s = match &m.glossy {
        Glossy::None => 0.0,
        Glossy::Phong { .. } | Glossy::RoughConductor(_) => channel_sum(specular),
        Glossy::RoughPlastic(_) | Glossy::Plastic(_) => channel_sum(specular + diffuse),
        Glossy::RoughDielectric(d) => {
            channel_sum(d.specular_reflectance + d.specular_transmittance)
        }
    };
    let d = channel_sum(m.kd());
    if d + s > 0.0 {
        d / (d + s)
    } else {
        1.0
    }
}

/// `cos α` between `wi` and the mirror direction of `wo`, in f64. `wi` is renormalised too:
/// an f32 unit vector is off by up to ~1e-7 in length, which `cos^ns` would multiply by `ns`
/// (a 3e-4 relative error of the density at `ns = 1e4`).
fn cos_lobe(n: Vec3, wo: Vec3, wi: Vec3) -> f64 {
    reflect(wo, n)
        .as_dvec3()
        .normalize()
        .dot(wi.as_dvec3().normalize())
}

/// The `|cos θ|` of `wi` against the frame's normal where `m` can scatter light arriving
/// from `wo` into `wi`: above the surface, or anywhere off it for a material that transmits
/// ([`Material::transmits`]); `None` elsewhere (and at grazing `wi`), where [`eval`] is
/// zero. The cosine by which every method weighs `f` and tests whether a sampled direction
/// or a light sample can carry anything.
pub fn cosine(m: &Material, frame: Frame, wi: Vec3) -> Option<f32> {
    let c = frame.n.dot(wi);
    if frame.base != Vec3::ZERO && frame.base.dot(wi) * c <= 0.0 {
        // A normal or bump map's refusal (see [`Frame::base`]).
        return None;
    }
    if c > 0.0 {
        Some(c)
    } else if c < 0.0 && m.transmits() {
        Some(-c)
    } else {
        None
    }
}

/// What [`eval`] and [`pdf`] both compute at one `(wo, wi)`, each part when first asked
/// for: [`eval_pdf`] computes it once for both, with the arithmetic each does alone.
struct Shared {
    frame: Frame,
    wo: Vec3,
    wi: Vec3,
    /// `wo` and `wi` in the frame's basis (`f64`).
    local: OnceCell<(DVec3, DVec3)>,
    /// Phong's `cos^ns α` about the mirror direction, `None` where `cos α ≤ 0`.
    phong: OnceCell<Option<f64>>,
    /// A microfacet reflection's half vector, or a rough dielectric's crossing.
    halfway: OnceCell<Option<Halfway>>,
    crossing: OnceCell<Option<Crossing>>,
}

impl Shared {
    fn new(frame: Frame, wo: Vec3, wi: Vec3) -> Self {
        Self {
            frame,
            wo,
            wi,
            local: OnceCell::new(),
            phong: OnceCell::new(),
            halfway: OnceCell::new(),
            crossing: OnceCell::new(),
        }
    }

    fn local(&self) -> (DVec3, DVec3) {
        *self.local.get_or_init(|| {
            let b = self.frame.basis();
            (Frame::to_local(&b, self.wo), Frame::to_local(&b, self.wi))
        })
    }

    /// Phong's `cos^ns α` for a lobe of specular reflectance `ks` (`cos α` is taken as 0
    /// where `ks` is black).
    fn phong(&self, ks: Vec3, ns: f32) -> Option<f64> {
        *self.phong.get_or_init(|| {
            let c = if ks.max_element() > 0.0 {
                cos_lobe(self.frame.n, self.wo, self.wi)
            } else {
                0.0
            };
            (c > 0.0).then(|| c.powf(ns as f64))
        })
    }

    fn halfway(&self, distr: &Microfacet) -> Option<Halfway> {
        *self.halfway.get_or_init(|| {
            let (wo, wi) = self.local();
            Halfway::of(distr, wo, wi)
        })
    }

    fn crossing(&self, d: &RoughDielectric) -> Option<Crossing> {
        *self.crossing.get_or_init(|| {
            let (wo, wi) = self.local();
            d.crossing(wo, wi, self.frame.back)
        })
    }
}

/// BSDF value `f(wo, wi)` (no cosine); zero for mirrors (a delta), and below the surface
/// for every lobe but a rough dielectric's. `m` is a material at a hit ([`MaterialAt`]), or
/// a plain `&Material` (its constant parameters), as for every function here. In a frame
/// that a normal or bump map perturbs ([`Frame::base`]): zero for a `wi` on different sides
/// of the two normals, else attenuated by Mitsuba's shadowing term. In
/// [`TransportMode::Importance`] the adjoint's value (see [`TransportMode`]).
pub fn eval<'a>(m: impl Into<MaterialAt<'a>>, frame: Frame, wo: Vec3, wi: Vec3) -> Vec3 {
    eval_shared(m.into(), &Shared::new(frame, wo, wi))
}

/// Solid-angle density of [`sample`] for `wi`; zero for mirrors (a delta is no density).
/// In a frame that a normal or bump map perturbs, the nested BSDF's in the perturbed frame,
/// also for the directions whose value [`eval`] zeroes (Mitsuba zeroes their density: they
/// carry nothing either way). The same in either [`TransportMode`].
pub fn pdf<'a>(m: impl Into<MaterialAt<'a>>, frame: Frame, wo: Vec3, wi: Vec3) -> f64 {
    pdf_shared(m.into(), &Shared::new(frame, wo, wi))
}

/// [`eval`] and [`pdf`] at once (Mitsuba's `eval_pdf`), bit for bit theirs, the work they
/// share done once: the local frame's directions, Phong's power, a microfacet lobe's half
/// vector and distribution.
pub fn eval_pdf<'a>(m: impl Into<MaterialAt<'a>>, frame: Frame, wo: Vec3, wi: Vec3) -> (Vec3, f64) {
    let m = m.into();
    let shared = Shared::new(frame, wo, wi);
    (eval_shared(m, &shared), pdf_shared(m, &shared))
}

/// [`eval`] through `shared`.
#[inline]
fn eval_shared(m: MaterialAt, shared: &Shared) -> Vec3 {
    in_frame(shared.frame, shared.wo, shared.wi, || {
        eval_in_frame(m, shared)
    })
}

/// The value `f` of the lobes in the frame (the nested BSDF's under a map), with what the
/// frame adds: a map's refusal and shadowing term, and the adjoint's correction.
#[inline]
fn in_frame(frame: Frame, wo: Vec3, wi: Vec3, f: impl FnOnce() -> Vec3) -> Vec3 {
    let base = frame.base;
    let f = if base == Vec3::ZERO {
        f()
    } else if base.dot(wi) * frame.n.dot(wi) <= 0.0 {
        return Vec3::ZERO;
    } else {
        f() * normals::shadow_terminator(frame.n, base, wi)
    };
    match frame.mode {
        TransportMode::Radiance => f,
        TransportMode::Importance => f * frame.adjoint_correction(wo, wi),
    }
}

/// The probability that a path arriving from `w` at a point of stored shading normal `ns`
/// meets `m`'s delta part: for a material that chooses its lobe at the hit (a smooth
/// plastic), the choice [`Material::scattering_at`] makes, from `|ns · w|`; 1 for a delta
/// BSDF, 0 for the others. A function of the direction the path arrives from, either of the
/// two: a camera path arrives from `wo`, a path started at a light from the direction a
/// camera path would leave along, so the two techniques' densities of one vertex differ by
/// it (for every other material it is the same for both). A `mask` makes no choice here:
/// the ray passes through it with probability `1 − opacity` at the hit's texture
/// coordinates ([`super::Opacity::at`]), whichever way it travels, before any BSDF is met.
pub fn delta_choice(m: &Material, ns: Vec3, w: Vec3) -> f64 {
    match &m.glossy {
        _ if m.mirror => 1.0,
        Glossy::Plastic(p) => p.specular_probability(f64::from(ns.dot(w).abs())),
        _ => 0.0,
    }
}

/// The non-delta part of `m`'s BSDF before any choice at the hit, for any `(wo, wi)` (no
/// cosine): a smooth plastic's diffuse lobe `f_d(wo, wi)` (Mitsuba's `eval`, which the
/// diffuse choice's [`eval`] is over `1 − P_s`), [`eval`] for every other material (zero for
/// a delta BSDF). In the frame's transport mode.
pub fn eval_non_delta<'a>(m: impl Into<MaterialAt<'a>>, frame: Frame, wo: Vec3, wi: Vec3) -> Vec3 {
    let m = m.into();
    let Glossy::Plastic(p) = &m.glossy else {
        return eval(m, frame, wo, wi);
    };
    in_frame(frame, wo, wi, || {
        let (cos_o, cos_i) = (frame.n.dot(wo), frame.n.dot(wi));
        if m.mirror || cos_o <= 0.0 || cos_i <= 0.0 {
            return Vec3::ZERO;
        }
        let diffuse = m.glossy_reflectances().1;
        p.eval_diffuse(diffuse, f64::from(cos_o), f64::from(cos_i))
    })
}

/// The density with which a path arriving from `wo` at a point of stored shading normal
/// `ns` samples `wi` out of `m`'s non-delta part, the choice at the hit included:
/// `(1 − `[`delta_choice`]`(m, ns, wo)) · `[`pdf`] (Mitsuba's smooth plastic's `pdf`); for
/// a material that makes no choice, [`pdf`]. A light-started path arriving from `wi` has
/// `pdf_non_delta(m, frame, ns, wi, wo)`, with the frame facing `wi`.
pub fn pdf_non_delta<'a>(
    m: impl Into<MaterialAt<'a>>,
    frame: Frame,
    ns: Vec3,
    wo: Vec3,
    wi: Vec3,
) -> f64 {
    let m = m.into();
    if !m.chooses_lobe() {
        return pdf(m, frame, wo, wi);
    }
    (1.0 - delta_choice(&m, ns, wo)) * pdf(m, frame, wo, wi)
}

/// [`eval`] in the frame, whether or not a map perturbs it.
#[inline]
fn eval_in_frame(m: MaterialAt, shared: &Shared) -> Vec3 {
    let (frame, wo, wi) = (shared.frame, shared.wo, shared.wi);
    let n = frame.n;
    if m.mirror || n.dot(wo) <= 0.0 {
        return Vec3::ZERO;
    }
    if let Glossy::RoughDielectric(d) = &m.glossy {
        let (lo, li) = shared.local();
        let reflectances = (m.glossy_reflectances().0, m.transmittance());
        return d.eval_at(reflectances, lo, li, shared.crossing(d), frame.mode);
    }
    if n.dot(wi) <= 0.0 {
        return Vec3::ZERO;
    }
    let f = m.kd() * std::f32::consts::FRAC_1_PI;
    if matches!(m.glossy, Glossy::None) {
        return f;
    }
    let (ks, diffuse) = m.glossy_reflectances();
    match &m.glossy {
        Glossy::None => f,
        Glossy::Phong { ns, .. } => match shared.phong(ks, *ns) {
            Some(power) => {
                let ns = *ns as f64;
                f + ks * ((ns + 2.0) * 0.5 * FRAC_1_PI * power) as f32
            }
            None => f,
        },
        Glossy::RoughConductor(c) => {
            let (lo, li) = shared.local();
            f + c.eval_at(ks, lo, li, shared.halfway(&c.microfacet))
        }
        Glossy::RoughPlastic(p) => {
            let (lo, li) = shared.local();
            f + p.eval_at((ks, diffuse), lo, li, shared.halfway(&p.microfacet))
        }
        // A smooth plastic's diffuse choice (see `super::SmoothPlastic`).
        Glossy::Plastic(p) => {
            let (cos_o, cos_i) = (f64::from(n.dot(wo)), f64::from(n.dot(wi)));
            f + p.eval_chosen(diffuse, cos_o, cos_i)
        }
        Glossy::RoughDielectric(_) => unreachable!("evaluated above"),
    }
}

/// [`pdf`] through `shared`.
#[inline]
fn pdf_shared(m: MaterialAt, shared: &Shared) -> f64 {
    if m.mirror {
        return 0.0;
    }
    let n = shared.frame.n;
    let p_diffuse = diffuse_probability(&m);
    // Both are unit vectors: their `f32` dot is the cosine to rounding (no renormalising).
    let cos = n.dot(shared.wi);
    let diffuse = if cos > 0.0 {
        p_diffuse * f64::from(cos) * FRAC_1_PI
    } else {
        0.0
    };
    if matches!(m.glossy, Glossy::None) {
        return diffuse;
    }
    diffuse + pdf_glossy(m, shared, 1.0 - p_diffuse, cos)
}

/// The glossy lobe's part of [`pdf`], chosen with probability `p_glossy`; `cos` is `wi`'s
/// against the normal.
#[inline]
fn pdf_glossy(m: MaterialAt, shared: &Shared, p_glossy: f64, cos: f32) -> f64 {
    let (n, wo, wi) = (shared.frame.n, shared.wo, shared.wi);
    match &m.glossy {
        Glossy::None => 0.0,
        Glossy::Phong { ns, .. } => match shared.phong(m.glossy_reflectances().0, *ns) {
            Some(power) => {
                let ns = *ns as f64;
                p_glossy * (ns + 1.0) * 0.5 * FRAC_1_PI * power
            }
            None => 0.0,
        },
        // Seen from below, no microfacet lobe scatters.
        _ if n.dot(wo) <= 0.0 => 0.0,
        // The rough dielectric transmits: its density covers the sphere.
        Glossy::RoughDielectric(d) => {
            let (lo, li) = shared.local();
            p_glossy * d.pdf_at(lo, li, shared.crossing(d))
        }
        // The others reflect only: nothing below the surface.
        _ if n.dot(wi) <= 0.0 => 0.0,
        Glossy::RoughConductor(c) => {
            let (lo, li) = shared.local();
            p_glossy * c.pdf_at(lo, li, shared.halfway(&c.microfacet))
        }
        Glossy::RoughPlastic(p) => {
            let (lo, li) = shared.local();
            p_glossy * p.pdf_at(lo, li, shared.halfway(&p.microfacet))
        }
        // A smooth plastic's diffuse choice: its cosine (the choice itself is no density).
        Glossy::Plastic(_) => p_glossy * f64::from(cos) * FRAC_1_PI,
    }
}

/// A unit direction around unit `axis` with `cos θ = c` and azimuth `phi`.
fn around(axis: DVec3, c: f64, phi: f64) -> DVec3 {
    let s = (1.0 - c * c).max(0.0).sqrt();
    let (t, b) = crate::math::basis(axis);
    (t * (s * phi.cos()) + b * (s * phi.sin()) + axis * c).normalize()
}

/// A direction about the unit normal `n` with density `cos θ / π` (the Lambertian lobe's)
/// from two uniform numbers: `cos θ = √(1 − u1)`, so `sin θ = √u1`, and azimuth `2π u2`. In
/// `f32`, in Duff et al.'s branchless basis ("Building an Orthonormal Basis, Revisited",
/// glam's `any_orthonormal_pair`); unit to rounding, as the basis is, so not renormalised.
fn cosine_weighted(n: Vec3, u1: f32, u2: f32) -> Vec3 {
    let (t, b) = n.any_orthonormal_pair();
    let (cos_theta, sin_theta) = ((1.0 - u1).max(0.0).sqrt(), u1.max(0.0).sqrt());
    let (sin_phi, cos_phi) = (std::f32::consts::TAU * u2).sin_cos();
    t * (sin_theta * cos_phi) + b * (sin_theta * sin_phi) + n * cos_theta
}

/// The direction [`sample`] draws from `u` for a non-mirror material (`None` for one that
/// does not scatter), without its density and weight: for callers that evaluate both for a
/// mixture anyway. `u[0]` picks the lobe (rescaled, it picks a rough plastic's lobe, or a
/// rough dielectric's reflection or refraction, too), `u[1]` and `u[2]` drive it. A rough
/// dielectric's direction may lie below the surface.
pub fn sample_direction<'a>(
    m: impl Into<MaterialAt<'a>>,
    frame: Frame,
    wo: Vec3,
    u: [f64; 3],
) -> Option<Vec3> {
    let m = m.into();
    if !m.scatters() {
        return None;
    }
    let n = frame.n;
    let p_diffuse = diffuse_probability(&m);
    if u[0] < p_diffuse {
        return Some(cosine_weighted(n, u[1] as f32, u[2] as f32));
    }
    let wi = match &m.glossy {
        Glossy::None => return None,
        Glossy::Phong { ns, .. } => {
            let c = u[1].powf(1.0 / (*ns as f64 + 1.0));
            around(reflect(wo, n).as_dvec3().normalize(), c, 2.0 * PI * u[2]).as_vec3()
        }
        _ if n.dot(wo) <= 0.0 => return None,
        Glossy::RoughConductor(c) => {
            let b = frame.basis();
            Frame::to_world(&b, c.sample(Frame::to_local(&b, wo), [u[1], u[2]]))
        }
        Glossy::RoughPlastic(p) => {
            let b = frame.basis();
            let pick = ((u[0] - p_diffuse) / (1.0 - p_diffuse)).clamp(0.0, 1.0);
            Frame::to_world(&b, p.sample(Frame::to_local(&b, wo), [pick, u[1], u[2]]))
        }
        Glossy::Plastic(_) => cosine_weighted(n, u[1] as f32, u[2] as f32),
        // `u[0]` rescaled picks reflection or refraction by the Fresnel reflectance.
        Glossy::RoughDielectric(d) => {
            let b = frame.basis();
            let pick = ((u[0] - p_diffuse) / (1.0 - p_diffuse)).clamp(0.0, 1.0);
            let wi = d.sample(Frame::to_local(&b, wo), frame.back, [pick, u[1], u[2]])?;
            Frame::to_world(&b, wi)
        }
    };
    Some(wi)
}

/// A direction sampled out of a non-delta BSDF with the parts of its weight: for callers
/// that weigh it by something else than [`BrdfSample::weight`] (a path generator's throughput
/// takes `f · cos`, its density goes to the mixture).
#[derive(Clone, Copy, Debug)]
pub struct Scattered {
    pub wi: Vec3,
    /// Solid-angle density of the sampler that drew it ([`pdf`] for [`sample_scattered`]).
    pub pdf: f64,
    /// `|cos θ_i|` ([`cosine`]) and `f(wo, wi)` ([`eval`]).
    pub cos: f32,
    pub f: Vec3,
}

/// [`sample`] for a non-mirror material, the sample's density, cosine and value apart;
/// `None` where [`sample`] gives none.
pub fn sample_scattered<'a>(
    m: impl Into<MaterialAt<'a>>,
    frame: Frame,
    wo: Vec3,
    u: [f64; 3],
) -> Option<Scattered> {
    let m = m.into();
    let wi = sample_direction(m, frame, wo, u)?;
    let (f, pdf) = eval_pdf(m, frame, wo, wi);
    let cos = cosine(&m, frame, wi)?;
    if pdf <= 0.0 {
        return None;
    }
    Some(Scattered { wi, pdf, cos, f })
}

/// Samples `wi` from three uniform numbers; `None` when the sample carries no energy
/// (where [`cosine`] says the material sends nothing, or a black material), and for a smooth
/// dielectric, whose sampling needs the stored (not facing) normal's side:
/// [`specular::sample`] samples every delta BSDF. The weight is `f |cos θ_i| / pdf`.
pub fn sample<'a>(
    m: impl Into<MaterialAt<'a>>,
    frame: Frame,
    wo: Vec3,
    u: [f64; 3],
) -> Option<BrdfSample> {
    let m = m.into();
    if m.mirror {
        return match m.dielectric {
            Some(_) => None,
            None => specular::sample_in(m, frame.n, wo, u[0], frame.mode, frame.ng),
        };
    }
    let s = sample_scattered(m, frame, wo, u)?;
    Some(BrdfSample {
        wi: s.wi,
        pdf: s.pdf,
        weight: s.f * (s.cos as f64 / s.pdf) as f32,
        delta: false,
    })
}
