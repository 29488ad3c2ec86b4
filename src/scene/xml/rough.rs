//! Mitsuba's microfacet BSDFs (`roughconductor`, `roughplastic`, `roughdielectric`), and the
//! smooth `plastic` beside the rough one, as genpath materials: the
//! distribution's parameters as Mitsuba's `MicrofacetDistribution` reads them, with
//! roughness refused where it is not a positive, finite number (Mitsuba clamps 0 to 1e-4).

use super::props::Props;
use super::textures::{material_textures, Textures};
use crate::scene::material::microfacet::{
    Distribution, Microfacet, RoughConductor, RoughDielectric, RoughPlastic,
};
use crate::scene::{Glossy, Material, MaterialTextures, SceneError, SmoothPlastic};
use glam::Vec3;

/// The microfacet distribution of `p`: `distribution` (`beckmann`, Mitsuba's default, or
/// `ggx`, in any case), `alpha` or both `alpha_u` and `alpha_v` (0.1 by default), and
/// `sample_visible` (true by default).
fn microfacet(p: &Props) -> Result<Microfacet, SceneError> {
    let distribution = match p.string("distribution")?.map(str::to_lowercase).as_deref() {
        None | Some("beckmann") => Distribution::Beckmann,
        Some("ggx") => Distribution::Ggx,
        Some(other) => {
            return Err(p.error(format!(
                "unknown microfacet `distribution` \"{other}\" (known: beckmann, ggx)"
            )))
        }
    };
    let has = |name: &str| p.object().props.iter().any(|q| q.name == name);
    let (alpha_u, alpha_v) = match (has("alpha"), has("alpha_u"), has("alpha_v")) {
        (true, false, false) | (false, false, false) => {
            let a = roughness(p, "alpha")?;
            (a, a)
        }
        (false, true, true) => (roughness(p, "alpha_u")?, roughness(p, "alpha_v")?),
        (true, _, _) => return Err(p.error("give either `alpha` or `alpha_u` and `alpha_v`")),
        _ => return Err(p.error("give both `alpha_u` and `alpha_v`")),
    };
    let sample_visible = p.bool("sample_visible", true)?;
    Ok(Microfacet::new(
        distribution,
        alpha_u,
        alpha_v,
        sample_visible,
    ))
}

/// A roughness: a positive, finite `<float>` (0.1 by default).
fn roughness(p: &Props, name: &str) -> Result<f64, SceneError> {
    if let Some(prop) = p
        .get(name)
        .filter(|a| matches!(a.value, super::parse::Value::Object(_)))
    {
        return Err(p.prop_error(prop, "a textured roughness is not supported: genpath's roughness is one constant per material (Mitsuba's roughplastic takes a constant too)"));
    }
    let a = p.float(name, 0.1)?;
    match p.get(name) {
        Some(prop) if !(a.is_finite() && a > 0.0) => Err(p.prop_error(
            prop,
            format!("{a} is not a positive, finite roughness (for a smooth surface use the smooth BSDF)"),
        )),
        _ => Ok(a),
    }
}

/// A material with `glossy` as its only lobe (one-sided, as Mitsuba's BSDFs).
fn glossy(name: String, glossy: Glossy) -> Material {
    Material {
        name,
        kd: Vec3::ZERO,
        ks: Vec3::ZERO,
        glossy,
        mirror: false,
        ke: Vec3::ZERO,
        two_sided: false,
        conductor: None,
        dielectric: None,
        textures: None,
    }
}

/// Mitsuba's `roughconductor`: the distribution, the complex index of refraction and
/// `specular_reflectance` as the smooth `conductor` reads them.
pub(super) fn rough_conductor(
    p: &Props,
    name: String,
    tex: &mut Textures,
    warnings: &mut Vec<String>,
) -> Result<Material, SceneError> {
    let microfacet = microfacet(p)?;
    let ks = tex.reflectance(p, "specular_reflectance", 1.0, warnings)?;
    let (eta, k) = super::ior::complex_ior(p, warnings)?;
    let lobe = RoughConductor {
        microfacet,
        eta: eta.as_vec3(),
        k: k.as_vec3(),
        specular_reflectance: ks.constant.as_vec3(),
    };
    let mut m = glossy(name, Glossy::RoughConductor(lobe));
    m.textures = material_textures(MaterialTextures {
        specular: ks.texture,
        ..Default::default()
    });
    Ok(m)
}

/// Mitsuba's `roughplastic`: an isotropic distribution, `int_ior` (polypropylene) over
/// `ext_ior` (air), `diffuse_reflectance` (0.5), `specular_reflectance` (1), `nonlinear`.
pub(super) fn rough_plastic(
    p: &Props,
    name: String,
    tex: &mut Textures,
    warnings: &mut Vec<String>,
) -> Result<Material, SceneError> {
    let microfacet = microfacet(p)?;
    if !microfacet.is_isotropic() {
        return Err(p.error("roughplastic does not support anisotropic roughness (as Mitsuba's)"));
    }
    let c = coating(p, tex, warnings)?;
    let lobe = RoughPlastic::new(microfacet, c.eta, c.diffuse, c.specular, c.nonlinear);
    let mut m = glossy(name, Glossy::RoughPlastic(Box::new(lobe)));
    m.textures = material_textures(c.textures);
    Ok(m)
}

/// What Mitsuba's two plastics read alike: `int_ior` (polypropylene) over `ext_ior` (air),
/// which must differ, `diffuse_reflectance` (0.5) and `specular_reflectance` (1), and
/// `nonlinear`.
struct Coating {
    /// `int_ior / ext_ior`, in single precision as Mitsuba computes it.
    eta: f32,
    /// The reflectances' constants; a texture's is its mean, which weighs the lobe's share
    /// of specular sampling, as in Mitsuba.
    diffuse: Vec3,
    specular: Vec3,
    nonlinear: bool,
    textures: MaterialTextures,
}

fn coating(
    p: &Props,
    tex: &mut Textures,
    warnings: &mut Vec<String>,
) -> Result<Coating, SceneError> {
    let int_ior = super::ior::read(p, "int_ior", "polypropylene")?;
    let ext_ior = super::ior::read(p, "ext_ior", "air")?;
    if int_ior == ext_ior {
        return Err(p.error("the interior and exterior indices of refraction must differ"));
    }
    let diffuse = tex.reflectance(p, "diffuse_reflectance", 0.5, warnings)?;
    let specular = tex.reflectance(p, "specular_reflectance", 1.0, warnings)?;
    Ok(Coating {
        eta: int_ior / ext_ior,
        diffuse: diffuse.constant.as_vec3(),
        specular: specular.constant.as_vec3(),
        nonlinear: p.bool("nonlinear", false)?,
        textures: MaterialTextures {
            specular: specular.texture,
            diffuse: diffuse.texture,
            ..Default::default()
        },
    })
}

/// Mitsuba's smooth `plastic`: `int_ior` (polypropylene) over `ext_ior` (air),
/// `diffuse_reflectance` (0.5) and `specular_reflectance` (1), each a constant or a texture
/// (whose mean weighs the choice of lobe, as in Mitsuba), and `nonlinear`
/// ([`SmoothPlastic`]).
pub(super) fn smooth_plastic(
    p: &Props,
    name: String,
    tex: &mut Textures,
    warnings: &mut Vec<String>,
) -> Result<Material, SceneError> {
    let c = coating(p, tex, warnings)?;
    let lobe = SmoothPlastic::new(c.eta, c.diffuse, c.specular, c.nonlinear);
    let fdr = lobe.internal_reflectance();
    if fdr.is_nan() || fdr >= 1.0 {
        return Err(p.error(format!(
            "int_ior / ext_ior = {}: Mitsuba's fit of the coating's internal diffuse reflectance gives {fdr:.3}, not below 1 (its plastic would reflect negative light; the fit stays below 1 up to about 3.85)",
            lobe.eta
        )));
    }
    let mut m = glossy(name, Glossy::Plastic(Box::new(lobe)));
    m.textures = material_textures(c.textures);
    Ok(m)
}

/// Mitsuba's `roughdielectric`: the distribution (anisotropic too, along the shading
/// frame's `dp/du` as `roughconductor`'s), `int_ior` (bk7) over `ext_ior` (air), numbers or
/// Mitsuba's names, which must differ (as Mitsuba refuses equal ones), and
/// `specular_reflectance` and `specular_transmittance` (1 by default, constants within
/// [0, 1] or textures). Two-sided: light meets the interface from either side, with the index inverted
/// from behind the normal.
pub(super) fn rough_dielectric(
    p: &Props,
    name: String,
    tex: &mut Textures,
    warnings: &mut Vec<String>,
) -> Result<Material, SceneError> {
    let microfacet = microfacet(p)?;
    let int_ior = super::ior::read(p, "int_ior", "bk7")?;
    let ext_ior = super::ior::read(p, "ext_ior", "air")?;
    if int_ior == ext_ior {
        return Err(p.error("the interior and exterior indices of refraction must differ"));
    }
    // A texture's constant is its mean (which nothing here weighs: the lobe's sampling
    // depends on the Fresnel reflectance alone).
    let reflectance = tex.reflectance(p, "specular_reflectance", 1.0, warnings)?;
    let transmittance = tex.reflectance(p, "specular_transmittance", 1.0, warnings)?;
    let lobe = RoughDielectric {
        microfacet,
        // In single precision, as Mitsuba computes it.
        eta: int_ior / ext_ior,
        specular_reflectance: reflectance.constant.as_vec3(),
        specular_transmittance: transmittance.constant.as_vec3(),
    };
    Ok(Material {
        two_sided: true,
        textures: material_textures(MaterialTextures {
            specular: reflectance.texture,
            transmittance: transmittance.texture,
            ..Default::default()
        }),
        ..glossy(name, Glossy::RoughDielectric(lobe))
    })
}
