//! Mitsuba's `checkerboard` and `bitmap` textures on the BSDFs' spectrum parameters: each
//! texture object is built once (a bitmap read once, however many BSDFs refer to it), and
//! a parameter that may be textured reads as a constant and, where given, a texture
//! ([`Reflectance`]).

use super::parse::Value;
use super::props::Props;
use super::spectrum::ColorUse;
use crate::scene::texture::{Bitmap, Checkerboard, Filter, Wrap};
use crate::scene::{MaterialTextures, SceneError, Texture};
use glam::{Affine2, DMat4, DVec3, Vec2};
use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::Arc;

/// The textures built so far, by object index, and the files they were read from.
#[derive(Default)]
pub struct Textures {
    built: HashMap<usize, Texture>,
    pub files: Vec<PathBuf>,
}

/// A spectrum-or-texture parameter: its constant value (for a texture, its mean in every
/// channel, what Mitsuba's rough plastic weighs its sampling by) and its texture, if any.
pub struct Reflectance {
    pub constant: DVec3,
    pub texture: Option<Texture>,
}

impl Textures {
    /// Reflectance parameter `name` of `p` (`default` where absent): an `<rgb>`,
    /// `<spectrum>` or `<float>`, or a nested or referenced `<texture>`, within [0, 1]
    /// (beyond it the BSDF would create energy).
    pub fn reflectance(
        &mut self,
        p: &Props,
        name: &str,
        default: f64,
        warnings: &mut Vec<String>,
    ) -> Result<Reflectance, SceneError> {
        let Some(prop) = p.get(name) else {
            return Ok(Reflectance {
                constant: DVec3::splat(default),
                texture: None,
            });
        };
        let Value::Object(i) = prop.value else {
            let c = p
                .color(name, ColorUse::Reflectance, warnings)?
                .unwrap_or(DVec3::splat(default));
            if c.max_element() > 1.0 || c.min_element() < 0.0 {
                return Err(p.error(format!(
                    "`{name}` {c} is outside [0, 1] (it would create energy)"
                )));
            }
            return Ok(Reflectance {
                constant: c,
                texture: None,
            });
        };
        let object = &p.doc.objects[i];
        if object.tag != "texture" {
            return Err(p.prop_error(
                prop,
                format!(
                    "expected an <rgb>, <spectrum>, <float> or <texture>, got a <{}>",
                    object.tag
                ),
            ));
        }
        let texture = self.texture(&Props::new(p.doc, i), warnings)?;
        let (lo, hi) = texture.range();
        if hi > 1.0 {
            return Err(p.prop_error(
                prop,
                format!("the texture reaches {hi}, beyond 1 (a reflectance above 1 would create energy)"),
            ));
        }
        debug_assert!(lo >= 0.0);
        Ok(Reflectance {
            constant: DVec3::splat(f64::from(texture.mean())),
            texture: Some(texture),
        })
    }

    /// The texture object `p`, built once.
    pub fn texture(
        &mut self,
        p: &Props,
        warnings: &mut Vec<String>,
    ) -> Result<Texture, SceneError> {
        if let Some(t) = self.built.get(&p.index) {
            return Ok(t.clone());
        }
        let texture = match p.object().plugin.as_str() {
            "checkerboard" => Texture::Checkerboard(checkerboard(p, warnings)?),
            "bitmap" => Texture::Bitmap(Arc::new(self.bitmap(p, warnings)?)),
            other => {
                return Err(p.error(format!(
                    "genpath does not implement the `{other}` texture (supported: bitmap, checkerboard)"
                )))
            }
        };
        p.finish()?;
        self.built.insert(p.index, texture.clone());
        Ok(texture)
    }

    /// Mitsuba's `bitmap`: `filename`, `raw`, `filter_type`, `wrap_mode`, `to_uv`.
    fn bitmap(&mut self, p: &Props, warnings: &mut Vec<String>) -> Result<Bitmap, SceneError> {
        let name = p
            .string("filename")?
            .ok_or_else(|| p.error("needs a `filename`"))?;
        let raw = p.bool("raw", false)?;
        let filter = match p.string("filter_type")?.unwrap_or("bilinear") {
            "bilinear" => Filter::Bilinear,
            "nearest" => Filter::Nearest,
            other => {
                return Err(p.error(format!(
                    "`filter_type` \"{other}\" is not nearest or bilinear"
                )))
            }
        };
        let wrap = match p.string("wrap_mode")?.unwrap_or("repeat") {
            "repeat" => Wrap::Repeat,
            "mirror" => Wrap::Mirror,
            "clamp" => Wrap::Clamp,
            other => {
                return Err(p.error(format!(
                    "`wrap_mode` \"{other}\" is not repeat, mirror or clamp"
                )))
            }
        };
        let to_uv = to_uv(p)?;
        p.ignore(
            &["format", "accel"],
            "genpath stores texels as 32-bit floats",
            warnings,
        );
        let path = p.doc.resolve(p.loc(), name);
        self.files.push(path.clone());
        Bitmap::read(&path, raw, (filter, wrap, to_uv)).map_err(|e| p.error(e.to_string()))
    }
}

/// Mitsuba's `checkerboard` with constant `color0` (0.4) and `color1` (0.2).
fn checkerboard(p: &Props, warnings: &mut Vec<String>) -> Result<Checkerboard, SceneError> {
    let mut colour = |name: &str, default: f64| -> Result<glam::Vec3, SceneError> {
        if let Some(prop) = p.get(name) {
            if let Value::Object(_) = prop.value {
                return Err(p.prop_error(
                    prop,
                    "a texture inside a checkerboard is not supported (give an <rgb>, <spectrum> or <float>)",
                ));
            }
        }
        let c = p
            .color(name, ColorUse::Reflectance, warnings)?
            .unwrap_or(DVec3::splat(default));
        if !(c.min_element() >= 0.0 && c.is_finite()) {
            return Err(p.error(format!("`{name}` {c} is negative or not finite")));
        }
        Ok(c.as_vec3())
    };
    let color0 = colour("color0", 0.4)?;
    let color1 = colour("color1", 0.2)?;
    Ok(Checkerboard {
        color0,
        color1,
        to_uv: to_uv(p)?,
    })
}

/// `to_uv` as Mitsuba reads a 4×4 transform for texture coordinates: its rows and columns
/// 0, 1 and 3 (the z row and column dropped).
fn to_uv(p: &Props) -> Result<Affine2, SceneError> {
    let m: DMat4 = p.transform("to_uv")?;
    let t = Affine2::from_cols(
        Vec2::new(m.x_axis.x as f32, m.x_axis.y as f32),
        Vec2::new(m.y_axis.x as f32, m.y_axis.y as f32),
        Vec2::new(m.w_axis.x as f32, m.w_axis.y as f32),
    );
    if !t.is_finite() {
        return Err(p.error("`to_uv` is not finite"));
    }
    Ok(t)
}

/// The textures of a material, `None` without any.
pub fn material_textures(t: MaterialTextures) -> Option<Arc<MaterialTextures>> {
    let any = t.kd.is_some()
        || t.ks.is_some()
        || t.specular.is_some()
        || t.diffuse.is_some()
        || t.transmittance.is_some()
        || t.perturbation.is_some()
        || t.opacity.is_some();
    any.then(|| Arc::new(t))
}
