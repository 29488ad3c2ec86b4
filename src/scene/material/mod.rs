//! Materials and their BSDFs, in one module: what a surface is made of (a Lambertian
//! albedo, a glossy or delta BSDF, an emission), their textured parameters, and Mitsuba's
//! smooth plastic, which holds a material of its own for its delta choice (so the two types
//! live in one file); and how they scatter:
//!
//! * [`bsdf`]: the one BSDF interface of every method for a non-delta vertex — `eval`,
//!   `pdf`, `eval_pdf` (both at once, their shared work done once, Mitsuba's `eval_pdf`) and
//!   `sample` in a shading [`bsdf::Frame`], in either [`TransportMode`];
//! * [`specular`]: the delta BSDFs (mirrors, smooth conductors and dielectrics) and their
//!   sampler;
//! * [`microfacet`]: Mitsuba's microfacet lobes (rough conductor, plastic, dielectric);
//! * [`fresnel`]: the Fresnel equations they share.
//!
//! Directions follow pbrt-v4's and Mitsuba's convention in both transport modes: `wo` is the
//! direction the path arrived from (the frame faces it) and `wi` the one it continues along
//! or is connected along; in [`TransportMode::Importance`] (a path started at a light) the
//! BSDF value is the adjoint's (see there).
//!
//! # How a textured material is evaluated at a hit
//!
//! A [`Material`] stays constant per primitive: its untextured parameters are its fields,
//! and its textures, if any, sit in [`Material::textures`] beside them. Every method looks a
//! material up at a hit through `SceneView::scattering_material`, which returns a
//! [`MaterialAt`]: the material by reference plus, for a textured material only, the small
//! `Copy` value of its textured parameters evaluated at the hit's texture coordinates
//! ([`Resolved`]: the Lambertian albedo, the delta BSDF's reflectance, the glossy lobe's
//! specular and diffuse reflectances, a dielectric's transmittance; a smooth plastic's
//! look-up also takes its choice of lobe there, [`Material::scattering_at`]). The BSDF code
//! ([`bsdf`], [`specular`]) reads those parameters through [`MaterialAt`]'s accessors,
//! which return the material's own field where nothing is textured. So an untextured
//! scene allocates nothing, clones no name and computes exactly what it computed before
//! (bit-identical renders), and a textured one costs a texture lookup per material look-up
//! and no allocation either. Since every method's evaluations at a vertex — its own
//! sampling, another generator's density at a vertex it did not draw, a guide's training
//! records — go through the same look-up at the same [`super::SurfacePoint`] (which
//! carries the hit's texture coordinates), all of them see the same textured values.
//!
//! What textures do not vary: a rough plastic's share of specular sampling is computed from
//! the textures' means, as Mitsuba computes it; roughness (`alpha`) is a constant (a
//! textured one is refused when the scene is loaded).

pub mod bsdf;
pub mod fresnel;
pub mod microfacet;
pub mod specular;

use super::normals::Perturbation;
use super::texture::Texture;
use fresnel::{fresnel_conductor, fresnel_dielectric, fresnel_diffuse_reflectance};
use glam::{Vec2, Vec3};
use microfacet::{RoughConductor, RoughDielectric, RoughPlastic};
use std::f64::consts::FRAC_1_PI;

// The vector helpers and the sample type that both the non-delta BSDF (`bsdf`) and the
// delta one (`specular`) use: here, so that `bsdf` may call `specular` without a circle.

/// The (shading) normal `ns` turned towards `wo`: the side a two-sided surface scatters on.
pub fn facing_normal(ns: Vec3, wo: Vec3) -> Vec3 {
    if ns.dot(wo) >= 0.0 {
        ns
    } else {
        -ns
    }
}

/// Mirror reflection of `wo` about `n`.
pub fn reflect(wo: Vec3, n: Vec3) -> Vec3 {
    2.0 * n.dot(wo) * n - wo
}

/// A sampled direction.
#[derive(Clone, Copy, Debug)]
pub struct BrdfSample {
    pub wi: Vec3,
    /// Solid-angle density; 1 for a delta (it then cancels in `weight`).
    pub pdf: f64,
    /// `f · |cos| / pdf` (for a mirror: its reflectance).
    pub weight: Vec3,
    pub delta: bool,
}

/// Which way a path carries light through a BSDF (pbrt-v4's and Mitsuba's
/// `TransportMode`). `wo` is the direction the path arrived from in both.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TransportMode {
    /// A path started at the camera: it carries radiance, `wo` towards the camera. The BSDF
    /// is `f(wo, wi)`, and radiance refracted through an interface is scaled by `1/η²`.
    #[default]
    Radiance,
    /// A path started at a light: it carries importance (light flows along the path), `wo`
    /// towards the light. The BSDF is the adjoint `f*(wo, wi) = f(wi, wo)`, times the
    /// shading-normal correction `|wo·ns| |wi·ng| / (|wo·ng| |wi·ns|)` (Veach's thesis
    /// §5.3, pbrt-v4's `CorrectShadingNormal`), and nothing scales refracted light: the
    /// `1/η²` of radiance is not importance's.
    Importance,
}

impl TransportMode {
    /// The shading-normal correction `|wo·ns| |wi·ng| / (|wo·ng| |wi·ns|)` that the adjoint
    /// BSDF carries at a point of shading normal `ns` and geometric normal `ng` (Veach's
    /// thesis §5.3, pbrt-v4's `CorrectShadingNormal`): 1 for [`TransportMode::Radiance`] or
    /// where `ng` is zero (no geometric normal to tell apart), 0 where `wo` or `wi` grazes a
    /// normal it is divided by.
    pub fn correction(self, ns: Vec3, ng: Vec3, wo: Vec3, wi: Vec3) -> f32 {
        if self == TransportMode::Radiance || ng == Vec3::ZERO {
            return 1.0;
        }
        let (ns, ng) = (ns.as_dvec3(), ng.as_dvec3());
        let (wo, wi) = (wo.as_dvec3(), wi.as_dvec3());
        let num = wo.dot(ns).abs() * wi.dot(ng).abs();
        let denom = wo.dot(ng).abs() * wi.dot(ns).abs();
        if denom > 0.0 {
            (num / denom) as f32
        } else {
            0.0
        }
    }
}

/// A surface material: a two-sided Lambertian lobe plus a glossy lobe ([`Glossy`]: a
/// normalised modified-Phong lobe, or Mitsuba's rough conductor, rough plastic or rough
/// dielectric), or a delta BSDF (an ideal mirror, a smooth conductor, a smooth or thin
/// dielectric); and a one-sided emission.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    /// Two-sided Lambertian albedo (`Kd`).
    pub kd: Vec3,
    /// The delta BSDF's reflectance (a mirror's `Ks`, Mitsuba's `specular_reflectance`).
    pub ks: Vec3,
    /// The non-delta lobe beside the Lambertian one.
    pub glossy: Glossy,
    /// A delta BSDF: an ideal mirror (`illum 3`) of reflectance `ks`, or, with
    /// [`Self::dielectric`], a dielectric interface. Transport treats every such vertex
    /// alike: no next-event estimation there, no sampler of a generator or guide, and the
    /// emission its direction finds counted in full.
    pub mirror: bool,
    /// Radiance emitted on the normal side (`Ke`).
    pub ke: Vec3,
    /// Whether the surface scatters on both sides (every TOML material; Mitsuba's
    /// `twosided`). A one-sided material is black seen from behind its normal.
    pub two_sided: bool,
    /// A smooth conductor's complex index of refraction (η, k) per channel: the mirror's
    /// reflectance is then `ks` times its Fresnel reflectance (Mitsuba's `conductor`).
    pub conductor: Option<[Vec3; 2]>,
    /// A smooth (or thin) dielectric (Mitsuba's `dielectric`, `thindielectric`): with
    /// `mirror`, a delta BSDF that reflects with reflectance `ks` or transmits (see
    /// [`specular`]).
    pub dielectric: Option<Dielectric>,
    /// The textured parameters, if any (see [`super::texture`]): they override the fields above
    /// at each hit, through [`Material::at`].
    pub textures: Option<std::sync::Arc<MaterialTextures>>,
}

/// The glossy (non-delta, non-Lambertian) lobe of a [`Material`], evaluated, weighed and
/// sampled by [`bsdf`] in the shading frame.
#[derive(Clone, Debug, PartialEq)]
pub enum Glossy {
    None,
    /// MTL's normalised modified-Phong lobe `ks (ns + 2)/(2π) cos^ns α` about the mirror
    /// direction (`Ks`, `Ns`).
    Phong {
        ks: Vec3,
        ns: f32,
    },
    /// Mitsuba's `roughconductor` (the material's `kd` is zero).
    RoughConductor(RoughConductor),
    /// Mitsuba's `roughplastic`, its diffuse base included (the material's `kd` is zero).
    RoughPlastic(Box<RoughPlastic>),
    /// Mitsuba's `roughdielectric` (the material's `kd` is zero): the one non-delta lobe
    /// that transmits, into the whole sphere ([`Material::transmits`]).
    RoughDielectric(RoughDielectric),
    /// Mitsuba's smooth `plastic` (the material's `kd` is zero): a vertex that chooses
    /// between a delta reflection and a diffuse lobe where a ray meets it
    /// ([`Material::scattering_at`]); as a glossy lobe, the diffuse choice's BSDF
    /// ([`SmoothPlastic`]).
    Plastic(Box<SmoothPlastic>),
}

impl Glossy {
    /// Whether the lobe is present and can reflect anything.
    pub fn reflects(&self) -> bool {
        match self {
            Glossy::None => false,
            Glossy::Phong { ks, .. } => ks.max_element() > 0.0,
            Glossy::RoughConductor(c) => c.specular_reflectance.max_element() > 0.0,
            Glossy::RoughPlastic(p) => {
                p.specular_reflectance.max_element() > 0.0
                    || p.diffuse_reflectance.max_element() > 0.0
            }
            Glossy::Plastic(p) => {
                p.specular_reflectance.max_element() > 0.0
                    || p.diffuse_reflectance.max_element() > 0.0
            }
            Glossy::RoughDielectric(d) => {
                d.specular_reflectance.max_element() > 0.0
                    || d.specular_transmittance.max_element() > 0.0
            }
        }
    }

    /// The lobe's specular reflectance (Phong's `ks`, a microfacet lobe's
    /// `specular_reflectance`) and diffuse one (a rough plastic's base); zero where absent.
    pub fn reflectances(&self) -> (Vec3, Vec3) {
        match self {
            Glossy::None => (Vec3::ZERO, Vec3::ZERO),
            Glossy::Phong { ks, .. } => (*ks, Vec3::ZERO),
            Glossy::RoughConductor(c) => (c.specular_reflectance, Vec3::ZERO),
            Glossy::RoughPlastic(p) => (p.specular_reflectance, p.diffuse_reflectance),
            Glossy::Plastic(p) => (p.specular_reflectance, p.diffuse_reflectance),
            Glossy::RoughDielectric(d) => (d.specular_reflectance, Vec3::ZERO),
        }
    }

    /// Whether the lobe reads the shading frame's tangent (Mitsuba's `sh_frame.s`).
    pub fn is_anisotropic(&self) -> bool {
        match self {
            Glossy::RoughConductor(c) => !c.microfacet.is_isotropic(),
            Glossy::RoughDielectric(d) => !d.microfacet.is_isotropic(),
            _ => false,
        }
    }
}

/// A dielectric interface: its relative index of refraction and what it transmits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dielectric {
    /// η = interior / exterior index of refraction; the exterior is on the side of the
    /// (shading) normal.
    pub eta: f32,
    /// What transmission passes (Mitsuba's `specular_transmittance`).
    pub transmittance: Vec3,
    /// A thin sheet (`thindielectric`): light passes straight through, and reflection
    /// includes the sheet's internal reflections.
    pub thin: bool,
}

/// What a one-sided material is seen from behind: it neither scatters nor emits.
pub static BLACK: Material = Material {
    name: String::new(),
    kd: Vec3::ZERO,
    ks: Vec3::ZERO,
    glossy: Glossy::None,
    mirror: false,
    ke: Vec3::ZERO,
    two_sided: true,
    conductor: None,
    dielectric: None,
    textures: None,
};

impl Material {
    pub fn is_emitter(&self) -> bool {
        self.ke.max_element() > 0.0
    }

    /// Whether a glossy lobe is present (and the surface is not a mirror). A smooth
    /// plastic's diffuse choice is no glossy lobe: what it scatters is nearly Lambertian.
    pub fn is_glossy(&self) -> bool {
        !self.mirror && self.glossy.reflects() && !self.chooses_lobe()
    }

    /// Whether the material chooses between a delta and a non-delta lobe where a ray
    /// meets it (a smooth plastic: [`Material::scattering_at`]).
    #[inline]
    pub fn chooses_lobe(&self) -> bool {
        matches!(self.glossy, Glossy::Plastic(_))
    }

    /// Whether the non-delta BSDF scatters into the whole sphere (a rough dielectric), not
    /// only into the hemisphere of the normal that faces `wo`: where it does, a direction
    /// below that hemisphere carries light (weighed by `|cos θ|`), and next-event
    /// estimation reaches lights behind the surface.
    pub fn transmits(&self) -> bool {
        !self.mirror && matches!(self.glossy, Glossy::RoughDielectric(_))
    }

    /// The relative index of refraction `η` (interior over exterior, the exterior on the
    /// side of the shading normal) of an interface that refracts: a smooth dielectric that
    /// is not thin, or a rough dielectric; `None` for every other material.
    pub fn interface_eta(&self) -> Option<f32> {
        match (&self.dielectric, &self.glossy) {
            (Some(d), _) if self.mirror && !d.thin => Some(d.eta),
            (None, Glossy::RoughDielectric(d)) if !self.mirror => Some(d.eta),
            _ => None,
        }
    }

    /// The mirror's reflectance for an incident direction at `cos_theta` to the normal:
    /// `ks`, times the conductor's Fresnel reflectance for a conductor.
    pub fn mirror_reflectance(&self, cos_theta: f32) -> Vec3 {
        match self.conductor {
            None => self.ks,
            Some([eta, k]) => self.ks * fresnel_conductor(cos_theta, eta, k),
        }
    }

    /// Whether light can scatter off the surface at all.
    pub fn scatters(&self) -> bool {
        if self.mirror {
            self.ks.max_element() > 0.0
                || self
                    .dielectric
                    .is_some_and(|d| d.transmittance.max_element() > 0.0)
        } else {
            self.kd.max_element() > 0.0 || self.glossy.reflects()
        }
    }
}

/// The textures of a material's spectrum parameters; `None` where the parameter is a
/// constant (the material's field).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MaterialTextures {
    /// The Lambertian albedo ([`Material::kd`]: `diffuse`'s `reflectance`).
    pub kd: Option<Texture>,
    /// The delta BSDF's reflectance ([`Material::ks`]: `conductor`'s and the dielectrics'
    /// `specular_reflectance`).
    pub ks: Option<Texture>,
    /// The glossy lobe's `specular_reflectance` (`roughconductor`, `roughplastic`).
    pub specular: Option<Texture>,
    /// The rough plastic's `diffuse_reflectance`.
    pub diffuse: Option<Texture>,
    /// The dielectrics' `specular_transmittance` (`dielectric`, `thindielectric`,
    /// `roughdielectric`).
    pub transmittance: Option<Texture>,
    /// The shading normals of a `normalmap` or `bumpmap` around the BSDF (see
    /// [`super::normals`]).
    pub perturbation: Option<Perturbation>,
    /// The opacity of a `mask` around the BSDF (see [`Opacity`]).
    pub opacity: Option<Opacity>,
}

/// Mitsuba's `mask` around a BSDF: at a hit, the surface scatters (by the nested BSDF) with
/// probability `opacity` and lets the ray pass straight through otherwise, a forward delta
/// that every method takes where a ray meets the surface (the path layer's `SceneView::trace_through`
/// and `unblocked_through`), so that no path vertex is ever a pass-through.
#[derive(Clone, Debug, PartialEq)]
pub enum Opacity {
    /// A constant opacity in [0, 1].
    Constant(f32),
    /// A grey texture (every texel's or colour's channels equal) whose value is the opacity,
    /// within [0, 1], read as Mitsuba's `eval_1` reads it (for a checkerboard, see
    /// [`Checkerboard::eval_1`](super::texture::Checkerboard::eval_1)).
    Texture(Texture),
}

impl Opacity {
    /// The opacity at texture coordinates `uv`, clamped to [0, 1] as Mitsuba clamps it.
    pub fn at(&self, uv: Vec2) -> f32 {
        match self {
            Opacity::Constant(a) => *a,
            Opacity::Texture(Texture::Checkerboard(c)) => c.eval_1(uv).clamp(0.0, 1.0),
            Opacity::Texture(Texture::Bitmap(b)) => b.eval(uv).x.clamp(0.0, 1.0),
        }
    }

    /// Whether the opacity varies over the surface (the hit's texture coordinates matter).
    pub fn is_textured(&self) -> bool {
        matches!(self, Opacity::Texture(_))
    }
}

/// A material's textured parameters evaluated at one hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Resolved {
    pub kd: Vec3,
    pub ks: Vec3,
    pub specular: Vec3,
    pub diffuse: Vec3,
    pub transmittance: Vec3,
}

/// A material as it scatters at one hit: the material, and its textured parameters there
/// (see the module documentation). Dereferences to the material for what textures do not
/// vary.
#[derive(Clone, Copy, Debug)]
pub struct MaterialAt<'a> {
    pub material: &'a Material,
    resolved: Option<Resolved>,
}

impl<'a> From<&'a Material> for MaterialAt<'a> {
    /// The material with its constant parameters (its textures, if any, unread).
    fn from(material: &'a Material) -> Self {
        Self {
            material,
            resolved: None,
        }
    }
}

impl std::ops::Deref for MaterialAt<'_> {
    type Target = Material;
    fn deref(&self) -> &Material {
        self.material
    }
}

impl Material {
    /// The material at texture coordinates `uv`: its textures evaluated there.
    #[inline]
    pub fn at(&self, uv: Vec2) -> MaterialAt<'_> {
        let Some(t) = &self.textures else {
            return MaterialAt::from(self);
        };
        let pick = |tex: &Option<Texture>, constant: Vec3| match tex {
            Some(t) => t.eval(uv),
            None => constant,
        };
        let (specular, diffuse) = self.glossy.reflectances();
        MaterialAt {
            material: self,
            resolved: Some(Resolved {
                kd: pick(&t.kd, self.kd),
                ks: pick(&t.ks, self.ks),
                specular: pick(&t.specular, specular),
                diffuse: pick(&t.diffuse, diffuse),
                transmittance: pick(&t.transmittance, self.transmittance()),
            }),
        }
    }

    /// The material that scatters at a hit with texture coordinates `uv`, seen from `wo` at
    /// `cos_theta_o` (against the shading normal, positive), where the hit drew the uniform
    /// number `lobe_u`: [`Material::at`], except for a smooth plastic, which chooses its lobe
    /// there ([`SmoothPlastic`]): with probability `P_s` (`lobe_u < P_s`) its delta
    /// reflection, a mirror of reflectance `specular_reflectance · F / P_s`, and otherwise
    /// itself, whose BSDF is then its diffuse lobe over `1 − P_s`.
    #[inline]
    pub fn scattering_at(&self, uv: Vec2, cos_theta_o: f32, lobe_u: f32) -> MaterialAt<'_> {
        let Glossy::Plastic(p) = &self.glossy else {
            return self.at(uv);
        };
        let cos = f64::from(cos_theta_o);
        if f64::from(lobe_u) >= p.specular_probability(cos) {
            return self.at(uv);
        }
        let specular = match self.textures.as_ref().and_then(|t| t.specular.as_ref()) {
            Some(t) => t.eval(uv),
            None => p.specular_reflectance,
        };
        MaterialAt {
            material: &p.specular,
            resolved: Some(Resolved {
                kd: Vec3::ZERO,
                ks: p.specular_weight(specular, cos),
                specular: Vec3::ZERO,
                diffuse: Vec3::ZERO,
                transmittance: Vec3::ZERO,
            }),
        }
    }

    /// What a dielectric transmits (`specular_transmittance`: a smooth or thin
    /// dielectric's, a rough one's), as a constant; zero for other materials.
    pub fn transmittance(&self) -> Vec3 {
        match (&self.dielectric, &self.glossy) {
            (Some(d), _) => d.transmittance,
            (None, Glossy::RoughDielectric(d)) => d.specular_transmittance,
            _ => Vec3::ZERO,
        }
    }

    /// Whether any parameter is textured (the hit's texture coordinates matter).
    pub fn is_textured(&self) -> bool {
        self.textures.is_some()
    }

    /// The perturbation of the shading normal (`normalmap`, `bumpmap`), if any.
    #[inline]
    pub fn perturbation(&self) -> Option<&Perturbation> {
        self.textures.as_ref().and_then(|t| t.perturbation.as_ref())
    }

    /// The opacity of a `mask` around the material, if any.
    #[inline]
    pub fn opacity(&self) -> Option<&Opacity> {
        self.textures.as_ref().and_then(|t| t.opacity.as_ref())
    }
}

impl MaterialAt<'_> {
    /// The Lambertian albedo here.
    #[inline]
    pub fn kd(&self) -> Vec3 {
        self.resolved.map_or(self.material.kd, |r| r.kd)
    }

    /// The delta BSDF's reflectance here.
    #[inline]
    pub fn ks(&self) -> Vec3 {
        self.resolved.map_or(self.material.ks, |r| r.ks)
    }

    /// The glossy lobe's specular and diffuse reflectances here (see
    /// [`Glossy::reflectances`]).
    #[inline]
    pub fn glossy_reflectances(&self) -> (Vec3, Vec3) {
        match self.resolved {
            None => self.material.glossy.reflectances(),
            Some(r) => (r.specular, r.diffuse),
        }
    }

    /// What a dielectric transmits here ([`Material::transmittance`]).
    #[inline]
    pub fn transmittance(&self) -> Vec3 {
        self.resolved
            .map_or_else(|| self.material.transmittance(), |r| r.transmittance)
    }

    /// Whether the glossy lobe is present and reflects anything here.
    pub fn glossy_reflects(&self) -> bool {
        match self.resolved {
            None => self.material.glossy.reflects(),
            Some(r) => match self.material.glossy {
                Glossy::None => false,
                Glossy::RoughPlastic(_) | Glossy::Plastic(_) => {
                    r.specular.max_element() > 0.0 || r.diffuse.max_element() > 0.0
                }
                Glossy::RoughDielectric(_) => {
                    r.specular.max_element() > 0.0 || r.transmittance.max_element() > 0.0
                }
                _ => r.specular.max_element() > 0.0,
            },
        }
    }

    /// [`Material::is_glossy`] here.
    pub fn is_glossy(&self) -> bool {
        !self.mirror && self.glossy_reflects() && !self.chooses_lobe()
    }

    /// [`Material::scatters`] here.
    pub fn scatters(&self) -> bool {
        if self.resolved.is_none() {
            return self.material.scatters();
        }
        if self.mirror {
            self.ks().max_element() > 0.0
                || (self.dielectric.is_some() && self.transmittance().max_element() > 0.0)
        } else {
            self.kd().max_element() > 0.0 || self.glossy_reflects()
        }
    }

    /// [`Material::mirror_reflectance`] here.
    pub fn mirror_reflectance(&self, cos_theta: f32) -> Vec3 {
        match self.conductor {
            None => self.ks(),
            Some([eta, k]) => self.ks() * fresnel_conductor(cos_theta, eta, k),
        }
    }
}

/// Mitsuba 3's smooth `plastic` (`src/bsdfs/plastic.cpp`): a smooth dielectric coating
/// (relative index `η` = `int_ior / ext_ior`) over a Lambertian base. Light seen from `wo`
/// reflects off the coating by the dielectric Fresnel reflectance `F(cos θ_o)`, a delta
/// reflection times `specular_reflectance`, or enters it and leaves diffusely:
/// `f_d(wo, wi) = ρ / (1 − F_dr,int) · (1 − F(cos θ_o)) (1 − F(cos θ_i)) / (π η²)`, with
/// `ρ / (1 − ρ F_dr,int)` under `nonlinear` (`F_dr,int` the coating's diffuse reflectance
/// from inside, Mitsuba's fit [`fresnel_diffuse_reflectance`] of `1/η`).
///
/// # A vertex that chooses its lobe
///
/// Mitsuba samples the delta reflection with probability
/// `P_s = F w_s / (F w_s + (1 − F)(1 − w_s))` (`w_s` the specular reflectance's mean over
/// both means, [`SmoothPlastic::specular_probability`]) and the diffuse lobe otherwise. In
/// genpath that choice is taken where a ray meets the plastic, with one uniform number per
/// hit (`SurfacePoint::lobe_u`, drawn by `SceneView::trace_through`), and the vertex is
/// then either a delta vertex — a mirror of reflectance `specular_reflectance · F / P_s`
/// ([`SmoothPlastic::specular`]) — or an ordinary non-delta vertex whose BSDF is the
/// diffuse lobe over its probability, `f_d / (1 − P_s)` ([`SmoothPlastic::eval_chosen`]),
/// sampled by its cosine. Every method looks a material up at a vertex through
/// `SceneView::scattering_material`, which makes the choice, so every method sees the same
/// choice at the same vertex, as it sees glass's choice between reflection and refraction:
/// a delta choice has no light sample, no generator step and no guide, and the emission its
/// direction finds counts in full; a diffuse choice takes its light sample, its generator's
/// step or its guide with the diffuse lobe's value and density. For paths that all arrive
/// from the camera's side the choice's probability is the same for every generator and
/// technique that reaches the vertex (it depends on `wo` alone), so it is left out of their
/// densities, as glass's Fresnel choice is, and only its weight (`1 / P_s` or
/// `1 / (1 − P_s)`) enters the path's value. A path started at a light arrives from the
/// other direction, and makes its choice from that one: the choice's probability as a
/// function of either direction is [`bsdf::delta_choice`], and the diffuse lobe before the
/// choice, for any `(wo, wi)`, is [`bsdf::eval_non_delta`] with its density
/// [`bsdf::pdf_non_delta`] (Mitsuba's unchosen `eval` and `pdf`).
#[derive(Clone, Debug, PartialEq)]
pub struct SmoothPlastic {
    /// `int_ior / ext_ior`, in single precision as Mitsuba computes it.
    pub eta: f32,
    /// The base's reflectance and the coating's specular one (constants; a texture's mean).
    pub diffuse_reflectance: Vec3,
    pub specular_reflectance: Vec3,
    pub nonlinear: bool,
    /// `w_s`: the specular reflectance's mean over both means.
    specular_sampling_weight: f64,
    /// The coating's diffuse reflectance from inside, `F_dr(1/η)`.
    fdr_int: f64,
    /// The delta choice as a material: a one-sided mirror, whose reflectance at a hit is
    /// `specular_reflectance · F / P_s` (set there: `Material::scattering_at`).
    pub specular: Material,
}

impl SmoothPlastic {
    /// The plastic of relative index `eta`, base reflectance `diffuse` and coating
    /// reflectance `specular` (for textures, their means: what Mitsuba's `w_s` is made of).
    pub fn new(eta: f32, diffuse: Vec3, specular: Vec3, nonlinear: bool) -> Self {
        let mean = |c: Vec3| c.as_dvec3().element_sum() / 3.0;
        let s_mean = mean(specular);
        Self {
            eta,
            diffuse_reflectance: diffuse,
            specular_reflectance: specular,
            nonlinear,
            specular_sampling_weight: s_mean / (mean(diffuse) + s_mean),
            fdr_int: fresnel_diffuse_reflectance(1.0 / f64::from(eta)),
            specular: Material {
                name: "smooth plastic's specular reflection".into(),
                kd: Vec3::ZERO,
                ks: specular,
                glossy: Glossy::None,
                mirror: true,
                ke: Vec3::ZERO,
                two_sided: false,
                conductor: None,
                dielectric: None,
                textures: None,
            },
        }
    }

    /// `F_dr,int`, the coating's diffuse reflectance from inside (Mitsuba's fit of `1/η`,
    /// which reaches 1 near `η` = 3.85 and grows beyond: the diffuse lobe would be negative).
    pub fn internal_reflectance(&self) -> f64 {
        self.fdr_int
    }

    /// The coating's Fresnel reflectance at `cos θ` (above the surface).
    pub fn fresnel(&self, cos_theta: f64) -> f64 {
        fresnel_dielectric(cos_theta, f64::from(self.eta)).0
    }

    /// `P_s`, the probability of the delta choice seen from `wo` at `cos θ_o` (Mitsuba's
    /// `prob_specular`); 0 where neither lobe can be chosen.
    pub fn specular_probability(&self, cos_theta_o: f64) -> f64 {
        let f = self.fresnel(cos_theta_o);
        let w = self.specular_sampling_weight;
        let (s, d) = (f * w, (1.0 - f) * (1.0 - w));
        if s + d > 0.0 {
            s / (s + d)
        } else {
            0.0
        }
    }

    /// The delta choice's weight at `cos θ_o` for the coating reflectance `specular`:
    /// `specular · F / P_s` (Mitsuba's sampled value).
    pub fn specular_weight(&self, specular: Vec3, cos_theta_o: f64) -> Vec3 {
        let p = self.specular_probability(cos_theta_o);
        if p > 0.0 {
            specular * (self.fresnel(cos_theta_o) / p) as f32
        } else {
            Vec3::ZERO
        }
    }

    /// The diffuse lobe `f_d(wo, wi)` (no cosine) for the base reflectance `diffuse`, both
    /// directions above the surface at `cos θ_o` and `cos θ_i`: Mitsuba's `eval` over
    /// `cos θ_i`.
    pub fn eval_diffuse(&self, diffuse: Vec3, cos_theta_o: f64, cos_theta_i: f64) -> Vec3 {
        let d = diffuse.as_dvec3();
        let d = match self.nonlinear {
            true => d / (1.0 - d * self.fdr_int),
            false => d / (1.0 - self.fdr_int),
        };
        let eta = f64::from(self.eta);
        let t = (1.0 - self.fresnel(cos_theta_o)) * (1.0 - self.fresnel(cos_theta_i));
        (d * (FRAC_1_PI * t / (eta * eta))).as_vec3()
    }

    /// The BSDF of the diffuse choice: `f_d / (1 − P_s)`, `P_s` seen from `wo`.
    pub fn eval_chosen(&self, diffuse: Vec3, cos_theta_o: f64, cos_theta_i: f64) -> Vec3 {
        let p_diffuse = 1.0 - self.specular_probability(cos_theta_o);
        if p_diffuse <= 0.0 {
            return Vec3::ZERO;
        }
        self.eval_diffuse(diffuse, cos_theta_o, cos_theta_i) / p_diffuse as f32
    }
}

#[cfg(test)]
mod tests;
