//! Indices of refraction by name, as Mitsuba 3's dielectrics read `int_ior` and `ext_ior`:
//! a number, or a name from Mitsuba's table (`include/mitsuba/render/ior.h`, Hecht's
//! *Optics*, 0–20 °C at ~589 nm), looked up case-insensitively; and a conductor's complex
//! index ([`complex_ior`]), given or from Mitsuba's presets.

use super::parse::Value;
use super::props::Props;
use super::spectrum::ColorUse;
use super::tables::CONDUCTORS;
use crate::scene::SceneError;
use glam::DVec3;

/// Mitsuba 3's named indices of refraction (`ior_data` of `ior.h`), in its order.
pub const IORS: &[(&str, f32)] = &[
    ("vacuum", 1.0),
    ("helium", 1.000036),
    ("hydrogen", 1.000132),
    ("air", 1.000277),
    ("carbon dioxide", 1.00045),
    ("water", 1.3330),
    ("acetone", 1.36),
    ("ethanol", 1.361),
    ("carbon tetrachloride", 1.461),
    ("glycerol", 1.4729),
    ("benzene", 1.501),
    ("silicone oil", 1.52045),
    ("bromine", 1.661),
    ("water ice", 1.31),
    ("fused quartz", 1.458),
    ("pyrex", 1.470),
    ("acrylic glass", 1.49),
    ("polypropylene", 1.49),
    ("bk7", 1.5046),
    ("sodium chloride", 1.544),
    ("amber", 1.55),
    ("pet", 1.5750),
    ("diamond", 2.419),
];

/// The named index of refraction `name` (any case).
pub fn lookup(name: &str) -> Option<f32> {
    let lower = name.to_lowercase();
    IORS.iter().find(|(n, _)| *n == lower).map(|&(_, v)| v)
}

/// The index of refraction `name` of `p` (Mitsuba's `lookup_ior`): a `<float>` (or an
/// `<integer>`), or a `<string>` naming one of [`IORS`]; the name `default` when absent.
/// Refused: other types, unknown names, and values that are not positive and finite.
pub fn read(p: &Props, name: &str, default: &str) -> Result<f32, SceneError> {
    let value = match p.get(name) {
        None => lookup(default),
        Some(prop) => match &prop.value {
            Value::Float(v) => Some(*v as f32),
            Value::Int(v) => Some(*v as f32),
            Value::Str(s) => Some(lookup(s).ok_or_else(|| {
                let names: Vec<&str> = IORS.iter().map(|i| i.0).collect();
                p.prop_error(
                    prop,
                    format!(
                        "unknown index of refraction \"{s}\" (known: {})",
                        names.join(", ")
                    ),
                )
            })?),
            other => {
                return Err(p.prop_error(
                    prop,
                    format!("expected a <float> or a <string>, got {}", other.kind()),
                ))
            }
        },
    };
    match value {
        Some(v) if v.is_finite() && v > 0.0 => Ok(v),
        Some(v) => Err(p.error(format!(
            "`{name}` {v} is not a positive, finite index of refraction"
        ))),
        None => Err(p.error(format!("`{name}`: no index of refraction"))),
    }
}

/// A conductor's complex index of refraction (η, k) as Mitsuba's conductors read it: given
/// (`eta` 0 and `k` 1 by default) or a `material` preset.
pub(super) fn complex_ior(
    p: &Props,
    warnings: &mut Vec<String>,
) -> Result<(DVec3, DVec3), SceneError> {
    let preset = p.string("material")?.unwrap_or("none");
    let given_eta = p.color("eta", ColorUse::Unbounded, warnings)?;
    let given_k = p.color("k", ColorUse::Unbounded, warnings)?;
    if given_eta.is_some() || preset == "none" {
        if preset != "none" {
            return Err(p.error("give either (`eta`, `k`) or `material`, not both"));
        }
        return Ok((
            given_eta.unwrap_or(DVec3::ZERO),
            given_k.unwrap_or(DVec3::ONE),
        ));
    }
    if given_k.is_some() {
        return Err(p.error("give either (`eta`, `k`) or `material`, not both"));
    }
    let Some((_, eta, k)) = CONDUCTORS.iter().find(|(n, _, _)| *n == preset) else {
        let names: Vec<&str> = CONDUCTORS.iter().map(|c| c.0).collect();
        return Err(p.error(format!(
            "unknown conductor `material` \"{preset}\" (known: none, {})",
            names.join(", ")
        )));
    };
    Ok((DVec3::from(*eta), DVec3::from(*k)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_case_insensitive_and_unknown_ones_are_none() {
        assert_eq!(lookup("BK7"), Some(1.5046));
        assert_eq!(lookup("Water Ice"), Some(1.31));
        assert_eq!(lookup("air"), Some(1.000277));
        assert_eq!(lookup("glass"), None);
    }
}
