//! Mitsuba's `mask` BSDF adapter: the nested BSDF as a material with an [`Opacity`] (a
//! `<float>`, 0.5 by default, or a grey `checkerboard` or `bitmap` texture, read as
//! Mitsuba's `eval_1` reads it), through which rays pass with probability `1 − opacity`
//! (the path layer's `SceneView::trace_through`). Any nested BSDF genpath implements may be
//! masked (a `twosided`, a `normalmap` or `bumpmap` too); refused: a mask inside a mask, a
//! `twosided` around a mask (as Mitsuba refuses it: a mask transmits), a mask on an area
//! emitter (refused where the shape is built), and an opacity outside [0, 1] or not finite.

use super::parse::Value;
use super::props::Props;
use super::textures::Textures;
use crate::scene::{Material, Opacity, SceneError};
use std::sync::Arc;

/// The `mask` `p` around its nested BSDF, as one material named `name`. Leaves `p`'s own
/// unread properties to the caller's [`Props::finish`].
/// `nested_bsdf` builds the nested BSDF: the caller's dispatcher (`build::bsdf`), passed in
/// because it is also what calls this adapter, so that the two files do not import each
/// other.
pub(super) fn mask(
    p: &Props,
    name: String,
    tex: &mut Textures,
    warnings: &mut Vec<String>,
    nested_bsdf: fn(&Props, &mut Textures, &mut Vec<String>) -> Result<Material, SceneError>,
) -> Result<Material, SceneError> {
    let [nested] = p.children_of("bsdf")[..] else {
        return Err(p.error("`mask` takes exactly one nested BSDF"));
    };
    let q = Props::new(p.doc, nested);
    if q.object().plugin == "mask" {
        return Err(q.error(
            "a `mask` inside a `mask` (genpath masks a surface once; multiply the opacities)",
        ));
    }
    let opacity = opacity(p, tex, warnings)?;
    let mut m = nested_bsdf(&q, tex, warnings)?;
    let mut textures = m
        .textures
        .take()
        .map(Arc::unwrap_or_clone)
        .unwrap_or_default();
    textures.opacity = Some(opacity);
    m.textures = Some(Arc::new(textures));
    m.name = name;
    Ok(m)
}

/// The mask's `opacity`: a `<float>` within [0, 1] (0.5 where absent, Mitsuba's default)
/// or a grey texture whose values lie within [0, 1].
fn opacity(
    p: &Props,
    tex: &mut Textures,
    warnings: &mut Vec<String>,
) -> Result<Opacity, SceneError> {
    let Some(prop) = p.get("opacity") else {
        return Ok(Opacity::Constant(0.5));
    };
    let Value::Object(i) = prop.value else {
        let a = p.float("opacity", 0.5)?;
        if !(0.0..=1.0).contains(&a) {
            return Err(p.prop_error(prop, format!("{a} is not within [0, 1]")));
        }
        return Ok(Opacity::Constant(a as f32));
    };
    if p.doc.objects[i].tag != "texture" {
        return Err(p.prop_error(prop, "`opacity` must be a <float> or a <texture>"));
    }
    let t = tex.texture(&Props::new(p.doc, i), warnings)?;
    if !t.is_grey() {
        return Err(p.prop_error(
            prop,
            "an opacity texture must be grey (its channels equal): Mitsuba reads a coloured one by a rule of each texture's own (a bitmap's luminance, a colour's mean)",
        ));
    }
    let (_, hi) = t.range();
    if hi > 1.0 {
        return Err(p.prop_error(
            prop,
            format!("the texture reaches {hi}, beyond 1 (an opacity lies within [0, 1])"),
        ));
    }
    Ok(Opacity::Texture(t))
}
