//! Reading one object's properties with their types, Mitsuba's defaults and a record of
//! what was read: [`Props::finish`] refuses every property that genpath did not read, so
//! that nothing that would change the image is silently dropped.

use super::parse::{Doc, Loc, Object, Prop, Value};
use super::spectrum::ColorUse;
use crate::scene::SceneError;
use glam::{DMat4, DVec3};

/// One object's properties, as the scene builder reads them.
pub struct Props<'d> {
    pub doc: &'d Doc,
    pub index: usize,
}

impl<'d> Props<'d> {
    pub fn new(doc: &'d Doc, index: usize) -> Self {
        Self { doc, index }
    }

    pub fn object(&self) -> &'d Object {
        &self.doc.objects[self.index]
    }

    pub fn loc(&self) -> Loc {
        self.object().loc
    }

    /// `<shape type="obj">`, for messages.
    pub fn what(&self) -> String {
        let o = self.object();
        format!("<{} type=\"{}\">", o.tag, o.plugin)
    }

    /// An error at this object.
    pub fn error(&self, message: impl Into<String>) -> SceneError {
        self.doc
            .error(self.loc(), format!("{}: {}", self.what(), message.into()))
    }

    /// An error at property `prop`.
    pub fn prop_error(&self, prop: &Prop, message: impl Into<String>) -> SceneError {
        self.doc.error(
            prop.loc,
            format!("{} `{}`: {}", self.what(), prop.name, message.into()),
        )
    }

    /// The property `name`, marked as read.
    pub fn get(&self, name: &str) -> Option<&'d Prop> {
        let prop = self.object().props.iter().find(|p| p.name == name)?;
        prop.used.set(true);
        Some(prop)
    }

    fn wrong_type(&self, prop: &Prop, expected: &str) -> SceneError {
        self.prop_error(
            prop,
            format!("expected {expected}, got {}", prop.value.kind()),
        )
    }

    pub fn float(&self, name: &str, default: f64) -> Result<f64, SceneError> {
        match self.get(name) {
            None => Ok(default),
            Some(p) => match p.value {
                Value::Float(v) => Ok(v),
                Value::Int(v) => Ok(v as f64),
                _ => Err(self.wrong_type(p, "a float")),
            },
        }
    }

    pub fn int(&self, name: &str, default: i64) -> Result<i64, SceneError> {
        match self.get(name) {
            None => Ok(default),
            Some(p) => match p.value {
                Value::Int(v) => Ok(v),
                _ => Err(self.wrong_type(p, "an integer")),
            },
        }
    }

    pub fn bool(&self, name: &str, default: bool) -> Result<bool, SceneError> {
        match self.get(name) {
            None => Ok(default),
            Some(p) => match p.value {
                Value::Bool(v) => Ok(v),
                _ => Err(self.wrong_type(p, "a boolean")),
            },
        }
    }

    pub fn string(&self, name: &str) -> Result<Option<&'d str>, SceneError> {
        match self.get(name) {
            None => Ok(None),
            Some(p) => match &p.value {
                Value::Str(v) => Ok(Some(v)),
                _ => Err(self.wrong_type(p, "a string")),
            },
        }
    }

    /// A `<point>` or `<vector>`.
    pub fn point(&self, name: &str, default: DVec3) -> Result<DVec3, SceneError> {
        match self.get(name) {
            None => Ok(default),
            Some(p) => match p.value {
                Value::Vector(v) => Ok(v),
                _ => Err(self.wrong_type(p, "a <point>")),
            },
        }
    }

    pub fn transform(&self, name: &str) -> Result<DMat4, SceneError> {
        match self.get(name) {
            None => Ok(DMat4::IDENTITY),
            Some(p) => match p.value {
                Value::Transform(m) => Ok(m),
                _ => Err(self.wrong_type(p, "a <transform>")),
            },
        }
    }

    /// A colour: `<rgb>`, `<spectrum>` (converted for `usage` as Mitsuba's RGB variants
    /// do), or a `<float>` for all channels; `None` when absent. Textures are refused.
    pub fn color(
        &self,
        name: &str,
        usage: ColorUse,
        warnings: &mut Vec<String>,
    ) -> Result<Option<DVec3>, SceneError> {
        let Some(p) = self.get(name) else {
            return Ok(None);
        };
        match &p.value {
            Value::Rgb(c) => Ok(Some(*c)),
            Value::Float(v) => Ok(Some(DVec3::splat(*v))),
            Value::Int(v) => Ok(Some(DVec3::splat(*v as f64))),
            Value::Spectrum(s) => {
                let (rgb, clamped) = s.to_rgb(usage);
                if clamped {
                    warnings.push(format!(
                        "{}: {} `{name}`: the spectrum's colour is out of gamut and was clamped, as Mitsuba clamps it",
                        self.doc.at(p.loc),
                        self.what()
                    ));
                }
                Ok(Some(rgb))
            }
            Value::Object(i) => {
                let o = &self.doc.objects[*i];
                Err(self.prop_error(
                    p,
                    format!(
                        "textures (<{} type=\"{}\">) are not supported yet; give an <rgb> or <spectrum>",
                        o.tag, o.plugin
                    ),
                ))
            }
            _ => Err(self.wrong_type(p, "an <rgb>, <spectrum> or <float>")),
        }
    }

    /// The nested or referenced objects, in order, each marked as read.
    pub fn children(&self) -> Vec<(&'d Prop, usize)> {
        self.object()
            .props
            .iter()
            .filter_map(|p| match p.value {
                Value::Object(i) => Some((p, i)),
                _ => None,
            })
            .collect()
    }

    /// The nested objects of element `tag` (`bsdf`, `emitter`, …), marked as read.
    pub fn children_of(&self, tag: &str) -> Vec<usize> {
        self.children()
            .into_iter()
            .filter(|&(_, i)| self.doc.objects[i].tag == tag)
            .map(|(p, i)| {
                p.used.set(true);
                i
            })
            .collect()
    }

    /// Marks properties that Mitsuba accepts and that do not change the image, with a
    /// warning for each one given.
    pub fn ignore(&self, names: &[&str], why: &str, warnings: &mut Vec<String>) {
        for name in names {
            if let Some(p) = self.get(name) {
                warnings.push(format!(
                    "{}: {} `{name}` is ignored ({why})",
                    self.doc.at(p.loc),
                    self.what()
                ));
            }
        }
    }

    /// Refuses every property nobody read: genpath does not implement it.
    pub fn finish(&self) -> Result<(), SceneError> {
        match self.object().props.iter().find(|p| !p.used.get()) {
            None => Ok(()),
            Some(p) => Err(match p.value {
                Value::Object(i) => {
                    let o = &self.doc.objects[i];
                    self.prop_error(
                        p,
                        format!(
                            "a nested <{} type=\"{}\"> is not supported here",
                            o.tag, o.plugin
                        ),
                    )
                }
                _ => self.prop_error(p, "genpath does not implement this parameter"),
            }),
        }
    }
}
