//! PLY meshes (ASCII and binary, through `ply-rs-bw`) as Mitsuba's `ply` shape reads them:
//! the `vertex` element's `x y z` (and `nx ny nz`, when all three are there; texture
//! coordinates `u v`, else `texture_u texture_v`, else `s t`), the `face` element's
//! `vertex_indices` (or `vertex_index`) lists as fans; other elements skipped.

use super::mesh::RawMesh;
use glam::{DVec3, Vec2};
use ply_rs_bw::parser::Parser;
use ply_rs_bw::ply::{Property, PropertyAccess};
use std::io::BufReader;
use std::path::Path;

#[derive(Default)]
struct Vertex {
    p: [f64; 3],
    n: [f64; 3],
    /// `u v`, `texture_u texture_v`, `s t`: the first pair the file has is used.
    uv: [[f64; 2]; 3],
}

/// The names of a PLY vertex's texture coordinates, in Mitsuba's order of preference.
const UV_NAMES: [[&str; 2]; 3] = [["u", "v"], ["texture_u", "texture_v"], ["s", "t"]];

#[derive(Default)]
struct Face {
    indices: Vec<i64>,
}

/// An element genpath does not read.
struct Skipped;

fn scalar(p: &Property) -> Option<f64> {
    Some(match *p {
        Property::Char(v) => v.into(),
        Property::UChar(v) => v.into(),
        Property::Short(v) => v.into(),
        Property::UShort(v) => v.into(),
        Property::Int(v) => v.into(),
        Property::UInt(v) => v.into(),
        Property::Float(v) => v.into(),
        Property::Double(v) => v,
        _ => return None,
    })
}

impl PropertyAccess for Vertex {
    fn new() -> Self {
        Self::default()
    }
    fn set_property(&mut self, name: &str, property: Property) {
        let slot = match name {
            "x" => &mut self.p[0],
            "y" => &mut self.p[1],
            "z" => &mut self.p[2],
            "nx" => &mut self.n[0],
            "ny" => &mut self.n[1],
            "nz" => &mut self.n[2],
            "u" => &mut self.uv[0][0],
            "v" => &mut self.uv[0][1],
            "texture_u" => &mut self.uv[1][0],
            "texture_v" => &mut self.uv[1][1],
            "s" => &mut self.uv[2][0],
            "t" => &mut self.uv[2][1],
            _ => return,
        };
        *slot = scalar(&property).unwrap_or(f64::NAN);
    }
}

impl PropertyAccess for Face {
    fn new() -> Self {
        Self::default()
    }
    fn set_property(&mut self, name: &str, property: Property) {
        if name != "vertex_indices" && name != "vertex_index" {
            return;
        }
        self.indices = match property {
            Property::ListChar(v) => v.into_iter().map(i64::from).collect(),
            Property::ListUChar(v) => v.into_iter().map(i64::from).collect(),
            Property::ListShort(v) => v.into_iter().map(i64::from).collect(),
            Property::ListUShort(v) => v.into_iter().map(i64::from).collect(),
            Property::ListInt(v) => v.into_iter().map(i64::from).collect(),
            Property::ListUInt(v) => v.into_iter().map(i64::from).collect(),
            _ => vec![-1],
        };
    }
}

impl PropertyAccess for Skipped {
    fn new() -> Self {
        Skipped
    }
}

/// Why a PLY file is no mesh; the caller names the file.
#[derive(Debug, thiserror::Error)]
pub enum PlyError {
    #[error("cannot read: {0}")]
    Read(std::io::Error),
    #[error("malformed PLY header: {0}")]
    Header(std::io::Error),
    #[error("element `{name}` claims {count} entries, more than the file's {size} bytes")]
    Count {
        name: String,
        count: usize,
        size: u64,
    },
    #[error("element `{name}`: {source} (truncated or malformed)")]
    Truncated {
        name: String,
        source: std::io::Error,
    },
    #[error("vertex {0} is not finite")]
    VertexNotFinite(usize),
    #[error("face {0} has fewer than 3 vertex indices")]
    FewIndices(usize),
    #[error("face {face}: vertex index {index} is out of range ({vertices} vertices)")]
    IndexOutOfRange {
        face: usize,
        index: i64,
        vertices: i64,
    },
    #[error("no `vertex` element")]
    NoVertices,
}

/// Reads a PLY file (its `v` turned into `1 − v` with `flip_tex_coords`).
pub fn load(path: &Path, flip_tex_coords: bool) -> Result<RawMesh, PlyError> {
    let file = std::fs::File::open(path).map_err(PlyError::Read)?;
    let size = file.metadata().map(|m| m.len()).unwrap_or(0);
    let mut reader = BufReader::new(file);
    let header = Parser::<Skipped>::new()
        .read_header(&mut reader)
        .map_err(PlyError::Header)?;
    let mut mesh = RawMesh::default();
    let mut normals = Vec::new();
    let mut has_normals = false;
    let mut uvs = None;
    for (name, def) in &header.elements {
        // Every element takes at least one byte: a count beyond the file is a lie.
        if def.count as u64 > size {
            return Err(PlyError::Count {
                name: name.clone(),
                count: def.count,
                size,
            });
        }
        let truncated = |source: std::io::Error| PlyError::Truncated {
            name: name.clone(),
            source,
        };
        match name.as_str() {
            "vertex" => {
                has_normals = ["nx", "ny", "nz"]
                    .iter()
                    .all(|n| def.properties.contains_key(*n));
                let uv_names = UV_NAMES
                    .iter()
                    .position(|pair| pair.iter().all(|n| def.properties.contains_key(*n)));
                let vertices = Parser::<Vertex>::new()
                    .read_payload_for_element(&mut reader, def, &header)
                    .map_err(truncated)?;
                for (i, v) in vertices.iter().enumerate() {
                    let p = DVec3::from(v.p);
                    if !p.is_finite() || (has_normals && !DVec3::from(v.n).is_finite()) {
                        return Err(PlyError::VertexNotFinite(i));
                    }
                    mesh.positions.push(p);
                    normals.push(DVec3::from(v.n));
                }
                uvs = uv_names.map(|k| {
                    vertices
                        .iter()
                        .map(|v| {
                            let [s, t] = v.uv[k].map(|x| x as f32);
                            let t = if flip_tex_coords { 1.0 - t } else { t };
                            // A non-finite coordinate is no texture coordinate.
                            Some(Vec2::new(s, t)).filter(|uv| uv.is_finite())
                        })
                        .collect()
                });
            }
            "face" => {
                let faces = Parser::<Face>::new()
                    .read_payload_for_element(&mut reader, def, &header)
                    .map_err(truncated)?;
                let n = mesh.positions.len() as i64;
                for (i, f) in faces.iter().enumerate() {
                    if f.indices.len() < 3 {
                        return Err(PlyError::FewIndices(i));
                    }
                    if let Some(&index) = f.indices.iter().find(|&&k| k < 0 || k >= n) {
                        return Err(PlyError::IndexOutOfRange {
                            face: i,
                            index,
                            vertices: n,
                        });
                    }
                    let k = |j: usize| f.indices[j] as u32;
                    for j in 1..f.indices.len() - 1 {
                        mesh.triangles.push([k(0), k(j), k(j + 1)]);
                    }
                }
            }
            _ => {
                Parser::<Skipped>::new()
                    .read_payload_for_element(&mut reader, def, &header)
                    .map_err(truncated)?;
            }
        }
    }
    if mesh.positions.is_empty() {
        return Err(PlyError::NoVertices);
    }
    if has_normals {
        mesh.normals = Some(normals);
    }
    mesh.uvs = uvs;
    Ok(mesh)
}
