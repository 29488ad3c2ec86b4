//! Mitsuba 3 XML documents as objects with typed properties, the way Mitsuba's parser reads
//! them (`src/core/parser.cpp`): `<default>` and `$name` substitution (with `-D` values
//! first), `<include>` to a bounded depth, `<alias>`, `<path>`, `<ref>`, the typed property
//! tags, `<transform>`, and the upgrade of version 0.x/1.x files (camelCase names become
//! snake_case, `diffuse`'s `diffuse_reflectance` becomes `reflectance`). What the objects
//! mean is [`super::build`]'s business.

use super::spectrum::Spectrum;
use crate::scene::SceneError;
use glam::{DMat4, DVec3};
use std::cell::Cell;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// `<include>` nesting limit (Mitsuba's `max_include_depth`).
pub const MAX_INCLUDE_DEPTH: usize = 15;

/// Where something was written: a file of [`Doc::files`] and a line (1-based).
#[derive(Clone, Copy, Debug)]
pub struct Loc {
    pub file: usize,
    pub line: u32,
}

/// A property's value.
#[derive(Clone, Debug)]
pub enum Value {
    Int(i64),
    Float(f64),
    Bool(bool),
    Str(String),
    /// `<point>` or `<vector>` (a sphere's `center`).
    Vector(DVec3),
    Rgb(DVec3),
    Spectrum(Spectrum),
    Transform(DMat4),
    /// A nested object or a resolved `<ref>`: an index into [`Doc::objects`].
    Object(usize),
    /// An unresolved `<ref id>` (only while parsing).
    Ref(String),
}

impl Value {
    pub fn kind(&self) -> &'static str {
        match self {
            Value::Int(_) => "integer",
            Value::Float(_) => "float",
            Value::Bool(_) => "boolean",
            Value::Str(_) => "string",
            Value::Vector(_) => "point/vector",
            Value::Rgb(_) => "rgb",
            Value::Spectrum(_) => "spectrum",
            Value::Transform(_) => "transform",
            Value::Object(_) | Value::Ref(_) => "object",
        }
    }
}

/// A named property of an object; `used` is set when the scene builder reads it.
#[derive(Debug)]
pub struct Prop {
    pub name: String,
    pub value: Value,
    pub loc: Loc,
    pub used: Cell<bool>,
}

/// One plugin instance: `<bsdf type="diffuse" id="white">…</bsdf>`.
#[derive(Debug)]
pub struct Object {
    /// The element: `bsdf`, `shape`, `emitter`, `sensor`, `film`, … (`scene` for the root).
    pub tag: String,
    /// The `type` attribute (the plugin), `scene` for the root.
    pub plugin: String,
    pub id: Option<String>,
    pub loc: Loc,
    pub props: Vec<Prop>,
}

/// A parsed document: the root object is `objects[0]`.
#[derive(Debug)]
pub struct Doc {
    pub files: Vec<PathBuf>,
    pub objects: Vec<Object>,
    /// `<path>` folders, most recent first, searched before the referring file's folder.
    pub search: Vec<PathBuf>,
    pub warnings: Vec<String>,
}

impl Doc {
    /// An error at `loc`, naming file and line.
    pub fn error(&self, loc: Loc, message: impl Into<String>) -> SceneError {
        SceneError::Syntax {
            path: self.files[loc.file].clone(),
            line: loc.line as usize,
            message: message.into(),
        }
    }

    /// `file:line` of `loc`, for warnings.
    pub fn at(&self, loc: Loc) -> String {
        format!("{}:{}", self.files[loc.file].display(), loc.line)
    }

    /// The file a scene refers to by `name` from the file of `loc`: an absolute path as
    /// it is, else the first of the `<path>` folders and the referring file's folder that
    /// holds it (Mitsuba's file resolver).
    pub fn resolve(&self, loc: Loc, name: &str) -> PathBuf {
        let path = Path::new(name);
        if path.is_absolute() {
            return path.to_path_buf();
        }
        let own = self.files[loc.file].parent().unwrap_or(Path::new("."));
        self.search
            .iter()
            .map(|dir| dir.join(path))
            .find(|p| p.exists())
            .unwrap_or_else(|| own.join(path))
    }
}

/// Parses `path` with the `-D` values `defines` (`name=value`).
pub fn parse(path: &Path, defines: &[(String, String)]) -> Result<Doc, SceneError> {
    let mut parser = Parser {
        doc: Doc {
            files: Vec::new(),
            objects: Vec::new(),
            search: Vec::new(),
            warnings: Vec::new(),
        },
        params: defines
            .iter()
            .map(|(k, v)| (format!("${k}"), v.clone()))
            .collect(),
        ids: HashMap::new(),
        args: 0,
    };
    parser.sort_params();
    parser.file(path, None, 0)?;
    parser.resolve_refs()?;
    check_cycles(&parser.doc)?;
    Ok(parser.doc)
}

pub(super) struct Parser {
    doc: Doc,
    /// Substitutions `$name` → value, longest key first.
    params: Vec<(String, String)>,
    ids: HashMap<String, usize>,
    /// Counter for unnamed nested objects (`_arg_N`).
    args: usize,
}

/// The element being read: its substituted attributes and where it is.
pub(super) struct Element<'a, 'input> {
    pub(super) node: roxmltree::Node<'a, 'input>,
    attrs: Vec<(String, String)>,
    pub(super) loc: Loc,
    /// The file's `version` is below 2.0: names get Mitsuba's upgrade.
    old: bool,
}

impl Element<'_, '_> {
    pub(super) fn get(&self, name: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(k, _)| k == name)
            .map(|(_, v)| v.as_str())
    }
}

const OBJECT_TAGS: &[&str] = &[
    "bsdf",
    "shape",
    "emitter",
    "sensor",
    "film",
    "sampler",
    "integrator",
    "rfilter",
    "texture",
    "medium",
    "phase",
    "volume",
];

impl Parser {
    fn sort_params(&mut self) {
        self.params.sort_by_key(|(k, _)| std::cmp::Reverse(k.len()));
    }

    pub(super) fn err(&self, loc: Loc, message: impl Into<String>) -> SceneError {
        self.doc.error(loc, message)
    }

    /// Parses one file; with `parent`, its content goes into that object (an include).
    fn file(
        &mut self,
        path: &Path,
        parent: Option<(usize, Option<String>)>,
        depth: usize,
    ) -> Result<(), SceneError> {
        let text = std::fs::read_to_string(path).map_err(|reason| SceneError::Io {
            path: path.to_path_buf(),
            reason,
        })?;
        let file = self.doc.files.len();
        self.doc.files.push(path.to_path_buf());
        let xml = roxmltree::Document::parse(&text).map_err(|e| SceneError::Syntax {
            path: path.to_path_buf(),
            line: e.pos().row as usize,
            message: format!("malformed XML: {e}"),
        })?;
        let root = xml.root_element();
        let loc = Loc {
            file,
            line: xml.text_pos_at(root.range().start).row,
        };
        let version = root.attribute("version");
        let old = match version {
            Some(v) => {
                parse_version(v).ok_or_else(|| {
                    self.err(loc, format!("`version` \"{v}\" is not a version number"))
                })? < (2, 0)
            }
            None if parent.is_none() => {
                return Err(self.err(loc, "the root element needs a `version` attribute"))
            }
            None => false,
        };
        if let Some(major) = version.and_then(parse_version).map(|v| v.0) {
            if major > 3 {
                return Err(self.err(loc, format!("scene version {major}.x is newer than 3.x")));
            }
        }
        let ctx = Ctx {
            xml: &xml,
            file,
            old,
            depth,
        };
        match parent {
            None => {
                if root.tag_name().name() != "scene" {
                    return Err(self.err(loc, "the root element must be <scene>"));
                }
                self.doc.objects.push(Object {
                    tag: "scene".into(),
                    plugin: "scene".into(),
                    id: None,
                    loc,
                    props: Vec::new(),
                });
                self.children(&ctx, root, 0)
            }
            Some((parent, _)) if root.tag_name().name() == "scene" => {
                self.children(&ctx, root, parent)
            }
            Some((parent, name)) => {
                let el = self.element(&ctx, root)?;
                self.object(&ctx, &el, parent, name)
            }
        }
    }

    fn children(
        &mut self,
        ctx: &Ctx,
        node: roxmltree::Node,
        parent: usize,
    ) -> Result<(), SceneError> {
        for child in node.children().filter(|c| c.is_element()) {
            let el = self.element(ctx, child)?;
            self.tag(ctx, &el, parent)?;
        }
        Ok(())
    }

    /// Reads an element's attributes with `$name` substituted.
    pub(super) fn element<'a, 'input>(
        &self,
        ctx: &Ctx,
        node: roxmltree::Node<'a, 'input>,
    ) -> Result<Element<'a, 'input>, SceneError> {
        let loc = Loc {
            file: ctx.file,
            line: ctx.xml.text_pos_at(node.range().start).row,
        };
        let mut attrs = Vec::new();
        for a in node.attributes() {
            attrs.push((a.name().to_string(), self.substitute(a.value(), loc)?));
        }
        Ok(Element {
            node,
            attrs,
            loc,
            old: ctx.old,
        })
    }

    /// `$name` replaced by its value (longest names first); `\$` stays a dollar sign.
    fn substitute(&self, value: &str, loc: Loc) -> Result<String, SceneError> {
        if !value.contains('$') {
            return Ok(value.to_string());
        }
        let mut out = value.to_string();
        for (key, v) in &self.params {
            let mut pos = 0;
            while let Some(found) = out[pos..].find(key.as_str()) {
                let at = pos + found;
                if at > 0 && out.as_bytes()[at - 1] == b'\\' {
                    pos = at + key.len();
                } else {
                    out.replace_range(at..at + key.len(), v);
                    pos = at + v.len();
                }
            }
        }
        let bytes = out.as_bytes();
        for (i, &b) in bytes.iter().enumerate() {
            if b == b'$' && (i == 0 || bytes[i - 1] != b'\\') {
                let name: String = out[i + 1..]
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                return Err(self.err(
                    loc,
                    format!("undefined parameter `${name}` (give it with -D {name}=VALUE or a <default>)"),
                ));
            }
        }
        Ok(out.replace("\\$", "$"))
    }

    pub(super) fn check_attrs(&self, el: &Element, allowed: &[&str]) -> Result<(), SceneError> {
        for (name, _) in &el.attrs {
            if !allowed.contains(&name.as_str()) {
                return Err(self.err(
                    el.loc,
                    format!(
                        "unexpected attribute `{name}` on <{}>",
                        el.node.tag_name().name()
                    ),
                ));
            }
        }
        Ok(())
    }

    pub(super) fn required<'e>(&self, el: &'e Element, name: &str) -> Result<&'e str, SceneError> {
        el.get(name).ok_or_else(|| {
            self.err(
                el.loc,
                format!("<{}> needs a `{name}` attribute", el.node.tag_name().name()),
            )
        })
    }

    /// One child element of object `parent`.
    fn tag(&mut self, ctx: &Ctx, el: &Element, parent: usize) -> Result<(), SceneError> {
        let tag = el.node.tag_name().name();
        if OBJECT_TAGS.contains(&tag) || (tag == "spectrum" && el.get("type").is_some()) {
            let name = el.get("name").map(str::to_string);
            return self.object(ctx, el, parent, name);
        }
        match tag {
            "default" => {
                self.check_attrs(el, &["name", "value"])?;
                let name = self.required(el, "name")?;
                let value = self.required(el, "value")?;
                if name.is_empty() {
                    return Err(self.err(el.loc, "<default>: name must be non-empty"));
                }
                let key = format!("${name}");
                if !self.params.iter().any(|(k, _)| *k == key) {
                    self.params.push((key, value.to_string()));
                    self.sort_params();
                }
                Ok(())
            }
            "include" => self.include(ctx, el, parent),
            "alias" => {
                self.check_attrs(el, &["id", "as"])?;
                let (id, alias) = (self.required(el, "id")?, self.required(el, "as")?);
                if self.ids.contains_key(alias) {
                    return Err(self.err(el.loc, format!("alias id `{alias}` already exists")));
                }
                let Some(&target) = self.ids.get(id) else {
                    return Err(self.err(el.loc, format!("alias source id `{id}` not found")));
                };
                self.ids.insert(alias.to_string(), target);
                Ok(())
            }
            "path" => {
                self.check_attrs(el, &["value"])?;
                if parent != 0 {
                    return Err(self.err(el.loc, "<path> may only be a child of <scene>"));
                }
                let value = self.required(el, "value")?;
                let own = self.doc.files[el.loc.file]
                    .parent()
                    .unwrap_or(Path::new("."));
                let dir = own.join(value);
                if !dir.is_dir() {
                    return Err(self.err(
                        el.loc,
                        format!("<path>: folder `{}` not found", dir.display()),
                    ));
                }
                self.doc.search.insert(0, dir);
                Ok(())
            }
            "ref" => {
                self.check_attrs(el, &["id", "name"])?;
                let id = self.required(el, "id")?.to_string();
                let name = self.arg_name(el);
                self.push_prop(parent, name, Value::Ref(id), el.loc, el.old)
            }
            _ => {
                let value = self.property(el)?;
                self.check_attrs(el, &["name", "value", "x", "y", "z", "filename"])?;
                let name = self.required(el, "name")?.to_string();
                self.push_prop(parent, name, value, el.loc, el.old)
            }
        }
    }

    fn arg_name(&mut self, el: &Element) -> String {
        match el.get("name") {
            Some(n) => n.to_string(),
            None => {
                self.args += 1;
                format!("_arg_{}", self.args)
            }
        }
    }

    fn push_prop(
        &mut self,
        parent: usize,
        name: String,
        value: Value,
        loc: Loc,
        old: bool,
    ) -> Result<(), SceneError> {
        let name = if old { camel_to_snake(&name) } else { name };
        let object = &mut self.doc.objects[parent];
        if object.props.iter().any(|p| p.name == name) {
            return Err(self.err(
                loc,
                format!(
                    "property `{name}` of <{} type=\"{}\"> is given twice",
                    self.doc.objects[parent].tag, self.doc.objects[parent].plugin
                ),
            ));
        }
        object.props.push(Prop {
            name,
            value,
            loc,
            used: Cell::new(false),
        });
        Ok(())
    }

    /// An object element (`<bsdf type=…>`), its properties and nested objects.
    fn object(
        &mut self,
        ctx: &Ctx,
        el: &Element,
        parent: usize,
        name: Option<String>,
    ) -> Result<(), SceneError> {
        self.check_attrs(el, &["type", "id", "name"])?;
        let plugin = self.required(el, "type")?.to_string();
        let tag = el.node.tag_name().name().to_string();
        let index = self.doc.objects.len();
        let id = el.get("id").map(str::to_string);
        if let Some(id) = &id {
            if self.ids.insert(id.clone(), index).is_some() {
                return Err(self.err(el.loc, format!("duplicate id `{id}`")));
            }
        }
        self.doc.objects.push(Object {
            tag,
            plugin,
            id,
            loc: el.loc,
            props: Vec::new(),
        });
        let name = name.unwrap_or_else(|| {
            self.args += 1;
            format!("_arg_{}", self.args)
        });
        self.children(ctx, el.node, index)?;
        if ctx.old {
            let object = &mut self.doc.objects[index];
            if object.plugin == "diffuse" {
                if let Some(p) = object
                    .props
                    .iter_mut()
                    .find(|p| p.name == "diffuse_reflectance")
                {
                    p.name = "reflectance".into();
                }
            }
        }
        // Top-level objects with an id are only reachable by reference. A nested object's
        // `name` is upgraded as a property's is (Mitsuba upgrades every `name` but
        // `<default>`'s).
        self.push_prop(parent, name, Value::Object(index), el.loc, ctx.old)
    }

    fn include(&mut self, ctx: &Ctx, el: &Element, parent: usize) -> Result<(), SceneError> {
        self.check_attrs(el, &["filename", "name"])?;
        let filename = self.required(el, "filename")?;
        if ctx.depth + 1 >= MAX_INCLUDE_DEPTH {
            return Err(self.err(
                el.loc,
                format!(
                    "<include> nested deeper than {MAX_INCLUDE_DEPTH} files (a recursive include?)"
                ),
            ));
        }
        let path = self.doc.resolve(el.loc, filename);
        if !path.exists() {
            return Err(self.err(
                el.loc,
                format!("included file `{}` not found", path.display()),
            ));
        }
        let name = el.get("name").map(str::to_string);
        self.file(&path, Some((parent, name)), ctx.depth + 1)
    }

    /// Replaces every `<ref>` by the object it names.
    fn resolve_refs(&mut self) -> Result<(), SceneError> {
        for i in 0..self.doc.objects.len() {
            for j in 0..self.doc.objects[i].props.len() {
                let prop = &self.doc.objects[i].props[j];
                if let Value::Ref(id) = &prop.value {
                    let Some(&target) = self.ids.get(id) else {
                        return Err(self.err(
                            prop.loc,
                            format!("<ref id=\"{id}\">: no object has this id"),
                        ));
                    };
                    self.doc.objects[i].props[j].value = Value::Object(target);
                }
            }
        }
        Ok(())
    }
}

/// What every element of one file shares.
pub(super) struct Ctx<'a, 'input> {
    xml: &'a roxmltree::Document<'input>,
    file: usize,
    old: bool,
    depth: usize,
}

impl Ctx<'_, '_> {
    /// A context for the children of `el` (transform operations), same file.
    pub(super) fn at<'a, 'input>(el: &Element<'a, 'input>) -> Ctx<'a, 'input> {
        Ctx {
            xml: el.node.document(),
            file: el.loc.file,
            old: el.old,
            depth: 0,
        }
    }
}

/// A reference cycle (an object that contains itself) would recurse forever.
fn check_cycles(doc: &Doc) -> Result<(), SceneError> {
    // 0 unvisited, 1 on the current path, 2 done.
    let mut state = vec![0u8; doc.objects.len()];
    fn visit(doc: &Doc, i: usize, state: &mut [u8]) -> Result<(), SceneError> {
        state[i] = 1;
        for prop in &doc.objects[i].props {
            if let Value::Object(j) = prop.value {
                match state[j] {
                    1 => {
                        return Err(
                            doc.error(prop.loc, "this reference makes an object contain itself")
                        )
                    }
                    0 => visit(doc, j, state)?,
                    _ => {}
                }
            }
        }
        state[i] = 2;
        Ok(())
    }
    visit(doc, 0, &mut state)
}

/// `major.minor[.patch]`.
fn parse_version(text: &str) -> Option<(u32, u32)> {
    let mut parts = text.trim().split('.');
    let major = parts.next()?.parse().ok()?;
    let minor = parts.next().map_or(Some(0), |p| p.parse().ok())?;
    if let Some(patch) = parts.next() {
        patch.parse::<u32>().ok()?;
    }
    Some((major, minor))
}

/// Mitsuba's upgrade of 0.x names: `diffuseReflectance` → `diffuse_reflectance`,
/// `intIOR` → `int_ior` (a capital after a lower-case letter starts a new word, and the
/// capitals that follow it stay in that word).
pub fn camel_to_snake(name: &str) -> String {
    let chars: Vec<char> = name.chars().collect();
    let mut out = String::with_capacity(name.len() + 4);
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        if i > 0 && chars[i - 1].is_ascii_lowercase() && c.is_ascii_uppercase() {
            out.push('_');
            out.push(c.to_ascii_lowercase());
            while i + 1 < chars.len() && chars[i + 1].is_ascii_uppercase() {
                i += 1;
                out.push(chars[i].to_ascii_lowercase());
            }
        } else {
            out.push(c);
        }
        i += 1;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn camel_case_upgrades_as_mitsuba() {
        assert_eq!(camel_to_snake("diffuseReflectance"), "diffuse_reflectance");
        assert_eq!(camel_to_snake("intIOR"), "int_ior");
        assert_eq!(camel_to_snake("toWorld"), "to_world");
        assert_eq!(camel_to_snake("sampleCount"), "sample_count");
        assert_eq!(camel_to_snake("max_depth"), "max_depth");
        assert_eq!(camel_to_snake("fovAxis"), "fov_axis");
    }

    /// In a 0.x file a nested object's `name` is upgraded too: a `diffuse`'s
    /// `<texture name="diffuseReflectance">` becomes its `reflectance` (which the builder
    /// then refuses as a texture, instead of as an unknown parameter).
    #[test]
    fn old_files_upgrade_nested_objects_names() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("old.xml");
        let text = r#"<scene version="0.5.0"><bsdf type="diffuse" id="d">
            <texture type="bitmap" name="diffuseReflectance"/>
            <ref name="someThing" id="d2"/></bsdf>
            <bsdf type="diffuse" id="d2"><float name="fooBar" value="1"/></bsdf></scene>"#;
        std::fs::write(&path, text).unwrap();
        let doc = parse(&path, &[]).unwrap();
        let names = |i: usize| -> Vec<&str> {
            doc.objects[i]
                .props
                .iter()
                .map(|p| p.name.as_str())
                .collect()
        };
        let diffuse = doc
            .objects
            .iter()
            .position(|o| o.id.as_deref() == Some("d"))
            .unwrap();
        assert_eq!(names(diffuse), ["reflectance", "some_thing"]);
        let other = doc
            .objects
            .iter()
            .position(|o| o.id.as_deref() == Some("d2"))
            .unwrap();
        assert_eq!(names(other), ["foo_bar"]);
    }
}
