//! Mitsuba 3 XML scenes (`genpath render scene.xml`), mapped onto genpath's scene model:
//! [`parse`] reads the document as Mitsuba's parser does, [`build`] turns its sensor,
//! shapes, BSDFs and emitters into a [`Scene`], refusing with file and line whatever genpath
//! does not implement. docs/scenes.md lists what is supported and the conventions.

mod build;
mod emitters;
mod ior;
mod maps;
mod mask;
mod mesh;
mod numbers;
mod parse;
mod ply;
mod props;
mod rough;
mod serialized;
mod shapes;
mod spectrum;
mod tables;
mod textures;
mod transform;
mod values;

use super::{Scene, SceneError};
use std::path::Path;

pub use parse::MAX_INCLUDE_DEPTH;

/// Whether `path` names a Mitsuba XML scene (by its extension).
pub fn is_xml(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("xml"))
}

/// Loads a Mitsuba XML scene with the `-D` parameters `defines`.
pub fn load(path: &Path, defines: &[(String, String)]) -> Result<Scene, SceneError> {
    let doc = parse::parse(path, defines)?;
    build::build(&doc, path)
}
