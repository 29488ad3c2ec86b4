//! Mitsuba's emitters beside the area emitter: the delta lights `point`, `spot` and `directional`,
//! each a [`DeltaLight`], and the environment map `envmap`.

use super::props::Props;
use super::spectrum::ColorUse;
use crate::scene::envmap::EnvMap;
use crate::scene::{DeltaLight, Environment, SceneError, Spot};
use glam::{DMat3, DMat4, DVec3, Vec3};
use std::path::PathBuf;

/// The emitters given in the scene itself (not nested in a shape).
#[derive(Default)]
pub struct SceneLights {
    /// A `constant` or `envmap` emitter (at most one).
    pub environment: Option<Environment>,
    /// `point` and `directional` emitters.
    pub delta_lights: Vec<DeltaLight>,
}

impl SceneLights {
    /// Adds the emitter `p` (a map's file to `files`); `false` for a plugin that does not
    /// belong here (the caller refuses it).
    pub fn add(
        &mut self,
        p: &Props,
        files: &mut Vec<PathBuf>,
        warnings: &mut Vec<String>,
    ) -> Result<bool, SceneError> {
        match p.object().plugin.as_str() {
            "constant" | "envmap" if self.environment.is_some() => Err(p.error(
                "a second environment (`constant` or `envmap`) emitter (genpath takes one)",
            )),
            "constant" => {
                self.environment = Some(constant_emitter(p, warnings)?);
                Ok(true)
            }
            "envmap" => {
                self.environment = Some(envmap(p, files, warnings)?);
                Ok(true)
            }
            "point" | "spot" | "directional" => {
                self.delta_lights.push(delta_light(p, warnings)?);
                Ok(true)
            }
            _ => Ok(false),
        }
    }
}

/// Whether property `name` is given (without marking it read).
fn given(p: &Props, name: &str) -> bool {
    p.object().props.iter().any(|q| q.name == name)
}

/// An emitter's `what` colour (intensity, irradiance): given explicitly (genpath does not
/// assume Mitsuba's default), finite and not negative.
fn emission(p: &Props, what: &str, warnings: &mut Vec<String>) -> Result<DVec3, SceneError> {
    let c = p
        .color(what, ColorUse::Emission, warnings)?
        .ok_or_else(|| {
            p.error(format!(
                "needs an `{what}` (genpath does not assume Mitsuba's default)"
            ))
        })?;
    if !(c.is_finite() && c.min_element() >= 0.0 && c.max_element() <= 1e30) {
        return Err(p.error(format!(
            "`{what}` {c} is negative, not a number or beyond 1e30"
        )));
    }
    Ok(c)
}

/// The affine `to_world`, refused where `alone` is also given (as Mitsuba refuses it).
fn to_world(p: &Props, alone: &str) -> Result<Option<DMat4>, SceneError> {
    match (given(p, "to_world"), given(p, alone)) {
        (true, true) => Err(p.error(format!(
            "give either `{alone}` or `to_world`, not both (as Mitsuba refuses them)"
        ))),
        (true, false) => Ok(Some(p.transform("to_world")?)),
        (false, _) => Ok(None),
    }
}

/// Mitsuba's `point` (`position` or the translation of `to_world`; `intensity`), `spot`
/// (`to_world`, shining along its +z; `intensity`, `cutoff_angle` (20°) and `beam_width` (¾
/// of the cutoff)) or `directional` (`direction`, or `to_world` applied to +z;
/// `irradiance`).
pub fn delta_light(p: &Props, warnings: &mut Vec<String>) -> Result<DeltaLight, SceneError> {
    let light = match p.object().plugin.as_str() {
        "point" => {
            let position = match to_world(p, "position")? {
                Some(m) => m.w_axis.truncate(),
                None => p.point("position", DVec3::ZERO)?,
            };
            if !position.is_finite() {
                return Err(p.error(format!("`position` {position} is not finite")));
            }
            DeltaLight::Point {
                position: position.as_vec3(),
                intensity: emission(p, "intensity", warnings)?.as_vec3(),
            }
        }
        "spot" => {
            let m = match given(p, "to_world") {
                true => p.transform("to_world")?,
                false => DMat4::IDENTITY,
            };
            let position = m.w_axis.truncate();
            let axis = m.transform_vector3(DVec3::Z);
            let length = axis.length();
            if !(position.is_finite() && length.is_finite() && length > 1e-12) {
                return Err(p.error("`to_world` places the spot nowhere or points it nowhere"));
            }
            let cutoff = p.float("cutoff_angle", 20.0)?;
            let beam = p.float("beam_width", cutoff * 0.75)?;
            let intensity = emission(p, "intensity", warnings)?.as_vec3();
            let axis = (axis / length).as_vec3();
            let spot = Spot::new(position.as_vec3(), axis, intensity, cutoff as f32, beam as f32)
                .ok_or_else(|| {
                    p.error(format!(
                        "`beam_width` {beam} and `cutoff_angle` {cutoff} must satisfy 0 < beam_width <= cutoff_angle < 180 (degrees)"
                    ))
                })?;
            DeltaLight::Spot(spot)
        }
        _ => {
            let direction = match to_world(p, "direction")? {
                Some(m) => m.transform_vector3(DVec3::Z),
                None => match given(p, "direction") {
                    true => p.point("direction", DVec3::ZERO)?,
                    false => return Err(p.error("needs a `direction` or a `to_world`")),
                },
            };
            let length = direction.length();
            if !(length.is_finite() && length > 1e-12) {
                return Err(p.error(format!("the direction {direction} is zero or not finite")));
            }
            DeltaLight::Directional {
                direction: (direction / length).as_vec3(),
                irradiance: emission(p, "irradiance", warnings)?.as_vec3(),
            }
        }
    };
    p.finish()?;
    Ok(light)
}

/// Mitsuba's `envmap`: the equirectangular image `filename` (EXR through the `exr` crate;
/// with feature `oiio` also every format OpenImageIO reads, such as Radiance `.hdr`; PNG
/// sRGB-decoded), `scale` and a rigid `to_world`. The file is added to `files`.
pub fn envmap(
    p: &Props,
    files: &mut Vec<PathBuf>,
    warnings: &mut Vec<String>,
) -> Result<Environment, SceneError> {
    let name = p
        .string("filename")?
        .ok_or_else(|| p.error("needs a `filename`"))?;
    let path = p.doc.resolve(p.loc(), name);
    if !path.is_file() {
        return Err(p.error(format!("file `{}` not found", path.display())));
    }
    let scale = p.float("scale", 1.0)?;
    if !(0.0..=1e30).contains(&scale) {
        return Err(p.error(format!(
            "`scale` {scale} is negative, not a number or beyond 1e30"
        )));
    }
    let to_world = DMat3::from_mat4(p.transform("to_world")?);
    p.ignore(
        &["mis_compensation"],
        "it changes Mitsuba's sampling, not the image",
        warnings,
    );
    p.finish()?;
    let image = crate::image::read(&path).map_err(|e| p.error(e.to_string()))?;
    files.push(path.clone());
    let texels = image.pixels.iter().map(|&c| Vec3::from(c)).collect();
    let map = EnvMap::new(
        image.width as usize,
        image.height as usize,
        texels,
        to_world,
    )
    .map_err(|e| p.error(format!("`{}`: {e}", path.display())))?;
    Ok(Environment::map(map, scale as f32))
}

/// Mitsuba's `constant` emitter: its `radiance` (given explicitly).
fn constant_emitter(p: &Props, warnings: &mut Vec<String>) -> Result<Environment, SceneError> {
    let radiance = p
        .color("radiance", ColorUse::Emission, warnings)?
        .ok_or_else(|| p.error("needs a `radiance` (genpath does not assume Mitsuba's default)"))?;
    if radiance.min_element() < 0.0 || radiance.as_vec3().max_element() > 1e30 {
        return Err(p.error(format!("`radiance` {radiance} is negative or beyond 1e30")));
    }
    p.finish()?;
    Ok(Environment::new(radiance.as_vec3()))
}
