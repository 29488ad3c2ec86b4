//! Mitsuba's `normalmap` and `bumpmap` BSDF adapters: the nested BSDF as a material whose
//! shading normal a texture perturbs ([`crate::scene::normals`]). The nested BSDF must be
//! isotropic and non-delta and must not transmit (`diffuse`, `roughplastic`, an isotropic
//! `roughconductor`, or `twosided` around one of them); a `twosided` may also wrap the
//! adapter. Mitsuba's `flip_invalid_normals` and `use_shadowing_function` are implemented
//! at their defaults (true) only.

use super::parse::Value;
use super::props::Props;
use super::textures::Textures;
use crate::scene::normals::{NormalSource, Perturbation};
use crate::scene::{Material, SceneError, Texture};
use std::sync::Arc;

/// The adapter `p` (`normalmap` or `bumpmap`) around its nested BSDF, as one material named
/// `name`; `twosided_outside` where a `twosided` wraps it. Leaves `p`'s own unread
/// properties to the caller's [`Props::finish`].
/// `nested_bsdf` builds the nested BSDF: the caller's dispatcher (`build::bsdf`), passed in
/// because it is also what calls this adapter, so that the two files do not import each
/// other.
pub(super) fn adapter(
    p: &Props,
    name: String,
    tex: &mut Textures,
    warnings: &mut Vec<String>,
    twosided_outside: bool,
    nested_bsdf: fn(&Props, &mut Textures, &mut Vec<String>) -> Result<Material, SceneError>,
) -> Result<Material, SceneError> {
    let plugin = p.object().plugin.clone();
    let [nested] = p.children_of("bsdf")[..] else {
        return Err(p.error(format!("`{plugin}` takes exactly one nested BSDF")));
    };
    let q = Props::new(p.doc, nested);
    let inner = q.object().plugin.as_str();
    match inner {
        "normalmap" | "bumpmap" => {
            return Err(q.error(format!(
                "a `{inner}` inside a `{plugin}`: genpath perturbs a shading frame once"
            )))
        }
        "twosided" if twosided_outside => {
            return Err(q.error(format!("a twosided both around and inside the `{plugin}`")))
        }
        _ => {}
    }
    let mut m = nested_bsdf(&q, tex, warnings)?;
    if m.mirror || m.transmits() || m.chooses_lobe() {
        return Err(q.error(format!(
            "genpath's `{plugin}` perturbs non-delta BSDFs that do not transmit only (diffuse, roughplastic, roughconductor; not `{inner}`)"
        )));
    }
    if m.glossy.is_anisotropic() {
        return Err(q.error(format!(
            "an anisotropic BSDF inside a `{plugin}`: genpath perturbs isotropic lobes only"
        )));
    }
    for option in ["flip_invalid_normals", "use_shadowing_function"] {
        if !p.bool(option, true)? {
            return Err(p.error(format!(
                "`{option}` false is not implemented (genpath implements Mitsuba's default, true)"
            )));
        }
    }
    let source = match plugin.as_str() {
        "normalmap" => NormalSource::NormalMap(normal_map(p, tex, warnings)?),
        _ => bump_map(p, tex, warnings)?,
    };
    let mut textures = m
        .textures
        .take()
        .map(Arc::unwrap_or_clone)
        .unwrap_or_default();
    textures.perturbation = Some(Perturbation {
        source,
        twosided_outside,
    });
    m.textures = Some(Arc::new(textures));
    m.name = name;
    Ok(m)
}

/// `normalmap`'s texture `normalmap`: one whose blue channel stays above 1/2 everywhere (a
/// normal above the surface, `2c − 1` with a positive z; genpath then tells a one-sided
/// BSDF's sides apart as Mitsuba does).
fn normal_map(
    p: &Props,
    tex: &mut Textures,
    warnings: &mut Vec<String>,
) -> Result<Texture, SceneError> {
    let prop = p
        .get("normalmap")
        .ok_or_else(|| p.error("needs a texture `normalmap`"))?;
    let Value::Object(i) = prop.value else {
        return Err(p.prop_error(prop, "`normalmap` must be a <texture>"));
    };
    if p.doc.objects[i].tag != "texture" {
        return Err(p.prop_error(prop, "`normalmap` must be a <texture>"));
    }
    let t = tex.texture(&Props::new(p.doc, i), warnings)?;
    let blue = t.channel_min(2);
    if blue <= 0.5 {
        return Err(p.prop_error(
            prop,
            format!("the normal map's blue channel reaches {blue}, not above 1/2: a normal at or below the surface"),
        ));
    }
    Ok(t)
}

/// `bumpmap`'s one nested texture (of any name): a bitmap, whose luminance is the height
/// field, times `scale` (1 by default).
fn bump_map(
    p: &Props,
    tex: &mut Textures,
    warnings: &mut Vec<String>,
) -> Result<NormalSource, SceneError> {
    let [i] = p.children_of("texture")[..] else {
        return Err(p.error("`bumpmap` takes exactly one nested texture"));
    };
    let t = Props::new(p.doc, i);
    let height = match tex.texture(&t, warnings)? {
        Texture::Bitmap(b) => b,
        Texture::Checkerboard(_) => {
            return Err(t.error(
                "a checkerboard has no gradient (Mitsuba's eval_1_grad is not implemented for it); a bump map needs a bitmap",
            ))
        }
    };
    let scale = p.float("scale", 1.0)?;
    if !(scale.is_finite() && scale.abs() <= 1e6) {
        return Err(p.error(format!("`scale` {scale} is not finite or beyond 1e6")));
    }
    Ok(NormalSource::BumpMap {
        height,
        scale: scale as f32,
    })
}
