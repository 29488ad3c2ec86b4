//! The values of Mitsuba's typed property tags (`<float>`, `<rgb>`, `<spectrum>`, …) and of
//! `<transform>` with its operations, for [`super::parse`].

use super::numbers::{parse_f64, tokens};
use super::parse::{Ctx, Element, Parser, Value};
use super::spectrum::Spectrum;
use super::transform;
use crate::scene::SceneError;
use glam::{DMat4, DVec3};

impl Parser {
    /// A typed property tag's value (`<float>`, `<rgb>`, `<transform>`, …).
    pub(super) fn property(&self, el: &Element) -> Result<Value, SceneError> {
        let tag = el.node.tag_name().name();
        let number = |text: &str| parse_f64(text).ok_or_else(|| self.not_a_number(el, text));
        let value = || self.required(el, "value");
        Ok(match tag {
            "float" => Value::Float(number(value()?)?),
            "integer" => {
                let text = value()?;
                Value::Int(text.trim().parse().map_err(|_| {
                    self.err(el.loc, format!("could not parse integer value \"{text}\""))
                })?)
            }
            "boolean" => Value::Bool(match value()?.to_ascii_lowercase().as_str() {
                "true" => true,
                "false" => false,
                other => {
                    return Err(self.err(
                        el.loc,
                        format!("could not parse boolean value \"{other}\" (true or false)"),
                    ))
                }
            }),
            "string" => Value::Str(value()?.to_string()),
            "point" | "vector" => Value::Vector(self.xyz(el, 0.0)?),
            "rgb" => {
                let numbers = tokens(value()?)
                    .map(number)
                    .collect::<Result<Vec<_>, _>>()?;
                match numbers[..] {
                    [v] => Value::Rgb(DVec3::splat(v)),
                    [r, g, b] => Value::Rgb(DVec3::new(r, g, b)),
                    _ => {
                        return Err(self.err(
                            el.loc,
                            format!("<rgb> needs one or three values, got {}", numbers.len()),
                        ))
                    }
                }
            }
            "spectrum" => {
                if el.get("filename").is_some() {
                    return Err(self.err(
                        el.loc,
                        "<spectrum filename=…> (spectra from files) is not supported; give wavelength:value pairs",
                    ));
                }
                Value::Spectrum(
                    Spectrum::parse(value()?).map_err(|e| self.err(el.loc, e.to_string()))?,
                )
            }
            "transform" => Value::Transform(self.transform(el)?),
            _ => {
                return Err(self.err(el.loc, format!("unsupported XML element <{tag}>")));
            }
        })
    }

    fn not_a_number(&self, el: &Element, text: &str) -> SceneError {
        self.err(
            el.loc,
            format!(
                "<{}>: could not parse \"{text}\" as a finite number",
                el.node.tag_name().name()
            ),
        )
    }

    /// `value="x, y, z"` (or one value for all three) or `x=`/`y=`/`z=` with `default` for
    /// the missing ones.
    pub(super) fn xyz(&self, el: &Element, default: f64) -> Result<DVec3, SceneError> {
        let number = |text: &str| parse_f64(text).ok_or_else(|| self.not_a_number(el, text));
        if let Some(value) = el.get("value") {
            if el.get("x").is_some() || el.get("y").is_some() || el.get("z").is_some() {
                return Err(self.err(el.loc, "cannot mix `value` and `x`/`y`/`z`"));
            }
            let v = tokens(value).map(number).collect::<Result<Vec<_>, _>>()?;
            return match v[..] {
                [a] => Ok(DVec3::splat(a)),
                [a, b, c] => Ok(DVec3::new(a, b, c)),
                _ => Err(self.err(el.loc, "`value` must have exactly 1 or 3 numbers")),
            };
        }
        let mut out = DVec3::splat(default);
        for (i, axis) in ["x", "y", "z"].into_iter().enumerate() {
            if let Some(text) = el.get(axis) {
                out[i] = number(text)?;
            }
        }
        Ok(out)
    }

    /// A `<transform>`: its operations in order, the first applied first.
    fn transform(&self, el: &Element) -> Result<DMat4, SceneError> {
        let mut m = DMat4::IDENTITY;
        for child in el.node.children().filter(|c| c.is_element()) {
            let op = self.element(&Ctx::at(el), child)?;
            let op_m = self.transform_op(&op)?;
            m = op_m * m;
        }
        if !m.is_finite() {
            return Err(self.err(el.loc, "the transform is not finite"));
        }
        Ok(m)
    }

    fn transform_op(&self, op: &Element) -> Result<DMat4, SceneError> {
        let tag = op.node.tag_name().name();
        let number = |text: &str| parse_f64(text).ok_or_else(|| self.not_a_number(op, text));
        let vector = |name: &str| -> Result<DVec3, SceneError> {
            let v = tokens(self.required(op, name)?)
                .map(number)
                .collect::<Result<Vec<_>, _>>()?;
            match v[..] {
                [a, b, c] => Ok(DVec3::new(a, b, c)),
                _ => Err(self.err(op.loc, format!("`{name}` needs 3 numbers, got {}", v.len()))),
            }
        };
        match tag {
            "translate" => {
                self.check_attrs(op, &["value", "x", "y", "z"])?;
                Ok(DMat4::from_translation(self.xyz(op, 0.0)?))
            }
            "scale" => {
                self.check_attrs(op, &["value", "x", "y", "z"])?;
                Ok(DMat4::from_scale(self.xyz(op, 1.0)?))
            }
            "rotate" => {
                self.check_attrs(op, &["value", "x", "y", "z", "angle"])?;
                let axis = self.xyz(op, 0.0)?;
                let angle = number(self.required(op, "angle")?)?;
                transform::rotate(axis, angle)
                    .ok_or_else(|| self.err(op.loc, "rotation axis cannot be zero"))
            }
            "matrix" => {
                self.check_attrs(op, &["value"])?;
                let v = tokens(self.required(op, "value")?)
                    .map(number)
                    .collect::<Result<Vec<_>, _>>()?;
                transform::matrix(&v).ok_or_else(|| {
                    self.err(
                        op.loc,
                        format!("<matrix> needs 9 or 16 values, got {}", v.len()),
                    )
                })
            }
            "lookat" => {
                self.check_attrs(op, &["origin", "target", "up"])?;
                let origin = vector("origin")?;
                let target = vector("target")?;
                let up = if op.get("up").is_some() {
                    vector("up")?
                } else {
                    DVec3::ZERO
                };
                transform::look_at(origin, target, up)
                    .ok_or_else(|| self.err(op.loc, "invalid lookat transformation"))
            }
            _ => Err(self.err(op.loc, format!("unexpected <{tag}> inside <transform>"))),
        }
    }
}
