//! Mitsuba's shapes: as triangles `obj`, `ply`, `serialized`, `rectangle`, `cube`, placed
//! by `to_world` the way Mitsuba 3.9.1 places a mesh (the winding is kept where the
//! transform mirrors, so that the faces' normals turn over while given vertex normals,
//! through the inverse transpose, do not; `flip_normals` turns both over), with their
//! vertex normals (shading normals) and texture coordinates; analytic `sphere` (`center`,
//! `radius`, `to_world`, `flip_normals`) and `disk` (`to_world`, `flip_normals`),
//! intersected exactly ([`crate::accel::Analytic`]). `cylinder` is refused: tessellating it
//! would change the image.

use super::mesh::RawMesh;
use super::parse::Loc;
use super::props::Props;
use super::{ply, serialized};
use crate::accel::Analytic;
use crate::scene::validate::MAX_COORDINATE;
use crate::scene::SceneError;
use glam::{DMat3, DMat4, DVec3, Vec2, Vec3};
use std::collections::HashMap;
use std::path::Path;

/// The triangles of shape `p` in object space; the file it reads them from is added to
/// `files`.
pub fn load(p: &Props, files: &mut Vec<std::path::PathBuf>) -> Result<RawMesh, SceneError> {
    let plugin = p.object().plugin.as_str();
    let mut file = |p: &Props| -> Result<std::path::PathBuf, SceneError> {
        let name = p
            .string("filename")?
            .ok_or_else(|| p.error("needs a `filename`"))?;
        let path = p.doc.resolve(p.loc(), name);
        if !path.is_file() {
            return Err(p.error(format!("file `{}` not found", path.display())));
        }
        files.push(path.clone());
        Ok(path)
    };
    let mesh = match plugin {
        "rectangle" => rectangle(),
        "cube" => cube(),
        "obj" => {
            let path = file(p)?;
            obj(&path, p.bool("flip_tex_coords", true)?)?
        }
        "ply" => {
            let path = file(p)?;
            let flip = p.bool("flip_tex_coords", false)?;
            ply::load(&path, flip).map_err(|e| mesh_error(&path, e.to_string()))?
        }
        "serialized" => {
            let path = file(p)?;
            let index = p.int("shape_index", 0)?;
            let index = u32::try_from(index)
                .map_err(|_| p.error(format!("`shape_index` {index} is negative")))?;
            serialized::load(&path, index).map_err(|e| mesh_error(&path, e.to_string()))?
        }
        "cylinder" => {
            return Err(p.error(
                "analytic cylinders are not supported yet, and genpath does not tessellate them silently (that would change the image); give the shape as a mesh (obj, ply or serialized)",
            ))
        }
        other => {
            return Err(p.error(format!(
                "genpath does not implement the `{other}` shape (supported: obj, ply, serialized, rectangle, cube, sphere, disk)"
            )))
        }
    };
    if mesh.triangles.is_empty() {
        return Err(p.error("the shape has no triangles"));
    }
    Ok(mesh)
}

/// Shape `p` as an analytic shape in world space, `None` for a shape given as triangles.
/// A sphere is placed as Mitsuba places it: `to_world · translate(center) · scale(radius)`,
/// its radius the length of the image of the x axis (Mitsuba warns, as genpath does, where
/// `to_world` scales unevenly or shears, and uses that length); a negative or zero radius,
/// and a mirroring `to_world` (which Mitsuba turns into flipped normals), are refused.
pub fn analytic(p: &Props, warnings: &mut Vec<String>) -> Result<Option<Analytic>, SceneError> {
    let plugin = p.object().plugin.as_str();
    if plugin != "sphere" && plugin != "disk" {
        return Ok(None);
    }
    let to_world = p.transform("to_world")?;
    let flip = p.bool("flip_normals", false)?;
    if !to_world.is_finite() {
        return Err(p.error("`to_world` is not finite"));
    }
    let linear = DMat3::from_mat4(to_world);
    let shape = if plugin == "sphere" {
        let center = p.point("center", DVec3::ZERO)?;
        let radius = p.float("radius", 1.0)?;
        if !(radius.is_finite() && radius > 0.0) {
            return Err(p.error(format!(
                "`radius` {radius} is not a positive finite number"
            )));
        }
        if !center.is_finite() {
            return Err(p.error(format!("`center` {center} is not finite")));
        }
        if linear.determinant() <= 0.0 {
            return Err(p.error(
                "`to_world` mirrors or collapses the sphere (Mitsuba would flip its normals instead; give `flip_normals`)",
            ));
        }
        let axes = [linear.x_axis, linear.y_axis, linear.z_axis].map(|a| a.length());
        let similar = axes.iter().all(|&l| (l - axes[0]).abs() <= 1e-5 * axes[0])
            && linear.x_axis.dot(linear.y_axis).abs() <= 1e-5 * axes[0] * axes[1]
            && linear.y_axis.dot(linear.z_axis).abs() <= 1e-5 * axes[1] * axes[2]
            && linear.z_axis.dot(linear.x_axis).abs() <= 1e-5 * axes[2] * axes[0];
        if !similar {
            warnings.push(format!(
                "{}: {}: `to_world` scales unevenly or shears; the sphere's radius is the length of its x axis, as in Mitsuba",
                p.doc.at(p.loc()),
                p.what()
            ));
        }
        let world_center = to_world.transform_point3(center);
        let world_radius = radius * axes[0];
        Analytic::sphere(world_center, world_radius, flip).and_then(|s| s.turned(linear))
    } else {
        let affine = glam::DAffine3::from_mat4(to_world);
        Analytic::disk(affine, flip)
    }
    .map_err(|e| p.error(e.to_string()))?;
    let (lo, hi) = shape.bounds();
    if !(lo.is_finite() && hi.is_finite()) || lo.abs().max(hi.abs()).max_element() > MAX_COORDINATE
    {
        return Err(p.error(format!(
            "the {plugin} reaches beyond ±{MAX_COORDINATE:e} (or is not finite)"
        )));
    }
    Ok(Some(shape))
}

fn mesh_error(path: &Path, message: String) -> SceneError {
    SceneError::Mesh {
        path: path.to_path_buf(),
        message,
    }
}

/// Mitsuba's rectangle: [-1, 1]² in the z = 0 plane, normal +z.
pub fn rectangle() -> RawMesh {
    let positions = [(-1., -1.), (1., -1.), (1., 1.), (-1., 1.)]
        .map(|(x, y)| DVec3::new(x, y, 0.0))
        .to_vec();
    let uvs = [(0., 0.), (1., 0.), (1., 1.), (0., 1.)].map(|(u, v)| Some(Vec2::new(u, v)));
    RawMesh {
        positions,
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        normals: Some(vec![DVec3::Z; 4]),
        uvs: Some(uvs.to_vec()),
    }
}

/// A cube face: its normal, its four corners and their texture coordinates (u, v pairs).
type CubeFace = ([f64; 3], [[f64; 3]; 4], [f32; 8]);

/// Mitsuba 3.9.1's cube, face by face (normal), its four corners (position) with their
/// texture coordinates.
const MITSUBA_CUBE: [CubeFace; 6] = [
    (
        [0., -1., 0.],
        [
            [1., -1., -1.],
            [1., -1., 1.],
            [-1., -1., 1.],
            [-1., -1., -1.],
        ],
        [0., 1., 1., 1., 1., 0., 0., 0.],
    ),
    (
        [0., 1., 0.],
        [[1., 1., -1.], [-1., 1., -1.], [-1., 1., 1.], [1., 1., 1.]],
        [0., 1., 1., 1., 1., 0., 0., 0.],
    ),
    (
        [1., 0., 0.],
        [[1., -1., -1.], [1., 1., -1.], [1., 1., 1.], [1., -1., 1.]],
        [0., 1., 1., 1., 1., 0., 0., 0.],
    ),
    (
        [0., 0., 1.],
        [[1., -1., 1.], [1., 1., 1.], [-1., 1., 1.], [-1., -1., 1.]],
        [0., 1., 1., 1., 1., 0., 0., 0.],
    ),
    (
        [-1., 0., 0.],
        [
            [-1., -1., 1.],
            [-1., 1., 1.],
            [-1., 1., -1.],
            [-1., -1., -1.],
        ],
        [0., 1., 1., 1., 1., 0., 0., 0.],
    ),
    (
        [0., 0., -1.],
        [
            [1., 1., -1.],
            [1., -1., -1.],
            [-1., -1., -1.],
            [-1., 1., -1.],
        ],
        [0., 1., 1., 1., 1., 0., 0., 0.],
    ),
];

/// The texture coordinates of Mitsuba's cube at corner `p` of the face of normal `n`.
fn cube_uv(n: DVec3, p: DVec3) -> Vec2 {
    let (_, corners, uvs) = MITSUBA_CUBE
        .iter()
        .find(|(m, _, _)| DVec3::from(*m) == n)
        .expect("a cube face");
    let k = corners
        .iter()
        .position(|c| DVec3::from(*c) == p)
        .expect("a corner of the face");
    Vec2::new(uvs[2 * k], uvs[2 * k + 1])
}

/// Mitsuba's cube: [-1, 1]³, four vertices per face with the face's outward normal and
/// Mitsuba's texture coordinates (genpath's vertices come in another order, which the
/// image does not see: the coordinates are affine over each face).
pub fn cube() -> RawMesh {
    let mut mesh = RawMesh {
        normals: Some(Vec::new()),
        uvs: Some(Vec::new()),
        ..RawMesh::default()
    };
    for axis in 0..3 {
        for sign in [-1.0, 1.0] {
            let mut n = DVec3::ZERO;
            n[axis] = sign;
            let (u, v) = (DVec3::new(n.y, n.z, n.x), DVec3::new(n.z, n.x, n.y));
            let base = mesh.positions.len() as u32;
            for (a, b) in [(-1., -1.), (1., -1.), (1., 1.), (-1., 1.)] {
                let p = n + u * a + v * b;
                mesh.positions.push(p);
                if let Some(uvs) = &mut mesh.uvs {
                    uvs.push(Some(cube_uv(n, p)));
                }
            }
            // (u × v) is ±n: wind each face so that its normal points outward.
            let t = if u.cross(v).dot(n) > 0.0 {
                [[0, 1, 2], [0, 2, 3]]
            } else {
                [[0, 2, 1], [0, 3, 2]]
            };
            mesh.triangles.extend(t.map(|f| f.map(|i| base + i)));
            if let Some(normals) = &mut mesh.normals {
                normals.extend([n; 4]);
            }
        }
    }
    mesh
}

/// A Wavefront OBJ as Mitsuba reads it: `v`, `vn`, `vt` (its `v` turned into `1 − v` with
/// `flip_tex_coords`), `f` (polygons as fans, negative indices relative; a vertex for each
/// distinct position, texture coordinate and normal triple); materials, groups and
/// everything else ignored.
pub fn obj(path: &Path, flip_tex_coords: bool) -> Result<RawMesh, SceneError> {
    let text = std::fs::read_to_string(path).map_err(|reason| SceneError::Io {
        path: path.to_path_buf(),
        reason,
    })?;
    let err = |line: usize, message: String| SceneError::Syntax {
        path: path.to_path_buf(),
        line,
        message,
    };
    let (mut v, mut vn, mut vt) = (Vec::new(), Vec::new(), Vec::new());
    let mut mesh = RawMesh::default();
    let (mut normals, mut uvs) = (Vec::new(), Vec::new());
    let (mut any_normal, mut any_uv) = (false, false);
    let mut vertex_of: HashMap<(usize, Option<usize>, Option<usize>), u32> = HashMap::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let mut words = raw.split('#').next().unwrap_or("").split_whitespace();
        match words.next() {
            Some(kind @ ("v" | "vn" | "vt")) => {
                let numbers: Vec<f64> = words
                    .take(if kind == "vt" { 2 } else { 3 })
                    .map(|w| super::numbers::parse_f64(w).ok_or(w))
                    .collect::<Result<_, _>>()
                    .map_err(|w| err(line, format!("`{kind}`: `{w}` is not a finite number")))?;
                match (kind, &numbers[..]) {
                    ("vt", &[s]) => vt.push(Vec2::new(s as f32, 0.0)),
                    ("vt", &[s, t]) => vt.push(Vec2::new(s as f32, t as f32)),
                    ("vt", _) => return Err(err(line, "`vt` needs 1 or 2 numbers".into())),
                    (_, &[x, y, z]) => {
                        if kind == "v" { &mut v } else { &mut vn }.push(DVec3::new(x, y, z))
                    }
                    _ => return Err(err(line, format!("`{kind}` needs 3 numbers"))),
                }
            }
            Some("f") => {
                let mut corners = Vec::new();
                for w in words {
                    let mut parts = w.split('/');
                    let index = |part: Option<&str>, count: usize, what: &str| {
                        obj_index(part, count).map_err(|m| err(line, format!("`f`: {what} {m}")))
                    };
                    let p = index(parts.next(), v.len(), "vertex")?
                        .ok_or_else(|| err(line, format!("`f`: `{w}` has no vertex index")))?;
                    let t = index(parts.next(), vt.len(), "texture coordinate")?;
                    let n = index(parts.next(), vn.len(), "normal")?;
                    any_normal |= n.is_some();
                    any_uv |= t.is_some();
                    let next = mesh.positions.len() as u32;
                    let id = *vertex_of.entry((p, t, n)).or_insert_with(|| {
                        mesh.positions.push(v[p]);
                        normals.push(n.map(|n| vn[n]));
                        uvs.push(t.map(|t| {
                            let uv: Vec2 = vt[t];
                            if flip_tex_coords {
                                Vec2::new(uv.x, 1.0 - uv.y)
                            } else {
                                uv
                            }
                        }));
                        next
                    });
                    corners.push(id);
                }
                if corners.len() < 3 {
                    return Err(err(line, "`f` needs at least 3 vertices".into()));
                }
                for k in 1..corners.len() - 1 {
                    mesh.triangles
                        .push([corners[0], corners[k], corners[k + 1]]);
                }
            }
            _ => {}
        }
    }
    if any_normal {
        let normals: Option<Vec<DVec3>> = normals.into_iter().collect();
        mesh.normals = Some(normals.ok_or_else(|| {
            mesh_error(
                path,
                "some faces give vertex normals and some do not".into(),
            )
        })?);
    }
    if any_uv {
        mesh.uvs = Some(uvs);
    }
    Ok(mesh)
}

/// Why a part of an OBJ face is no index into the items defined before it.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
enum ObjIndexError {
    #[error("`{0}` is not an index")]
    NotAnIndex(String),
    #[error("index {index} is out of range ({count} defined so far)")]
    OutOfRange { index: i64, count: usize },
}

/// A 1-based (or negative, relative) OBJ index into `count` items; `None` for an empty one.
fn obj_index(part: Option<&str>, count: usize) -> Result<Option<usize>, ObjIndexError> {
    let Some(text) = part.filter(|t| !t.is_empty()) else {
        return Ok(None);
    };
    let k: i64 = text
        .parse()
        .map_err(|_| ObjIndexError::NotAnIndex(text.to_string()))?;
    let i = if k > 0 { k - 1 } else { count as i64 + k };
    if k == 0 || i < 0 || i >= count as i64 {
        return Err(ObjIndexError::OutOfRange { index: k, count });
    }
    Ok(Some(i as usize))
}

/// Shape options that decide how a mesh is placed.
pub struct Placement {
    pub to_world: DMat4,
    pub flip_normals: bool,
    pub face_normals: bool,
}

/// A shape in world space, as the scene keeps it.
#[derive(Debug)]
pub struct PlacedMesh {
    pub positions: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
    /// Unit shading normal of each vertex, where Mitsuba shades with vertex normals that
    /// differ from the faces' (given ones, or the angle-weighted ones it computes for a mesh
    /// without any); `None` where the shape shades with its faces' normals (`face_normals`,
    /// or vertex normals equal to them). Zero for a vertex without a usable normal (a zero
    /// one in the file, or one around degenerate faces only): its triangles shade flat.
    pub normals: Option<Vec<Vec3>>,
    /// Vertices whose normal is zero.
    pub zero_normals: usize,
    /// Texture coordinates of each vertex, as the mesh gives them.
    pub uvs: Option<Vec<Option<Vec2>>>,
}

/// The mesh in world space, wound so that its geometric normals are Mitsuba's, with
/// Mitsuba's shading normals.
pub fn place(
    mesh: RawMesh,
    how: &Placement,
    loc: Loc,
    p: &Props,
) -> Result<PlacedMesh, SceneError> {
    let linear = DMat3::from_mat4(how.to_world);
    let normal_matrix = linear.inverse().transpose();
    let positions: Vec<DVec3> = mesh
        .positions
        .iter()
        .map(|&x| how.to_world.transform_point3(x))
        .collect();
    if let Some(x) = positions
        .iter()
        .find(|x| !x.is_finite() || x.abs().max_element() > MAX_COORDINATE)
    {
        return Err(p.doc.error(
            loc,
            format!(
                "{}: vertex {x} is not finite or beyond ±{MAX_COORDINATE:e}",
                p.what()
            ),
        ));
    }
    let mut triangles = mesh.triangles;
    // Mitsuba 3.9.1 negates both normals at each hit for `flip_normals`: the same as the
    // other winding (and the angle-weighted normals of that winding) and negated given ones.
    if how.flip_normals {
        for t in &mut triangles {
            t.swap(1, 2);
        }
    }
    let mut normals = None;
    if !how.face_normals {
        let sign = if how.flip_normals { -1.0 } else { 1.0 };
        let n = match &mesh.normals {
            Some(n) => n
                .iter()
                .map(|&n| (normal_matrix * n).normalize_or_zero() * sign)
                .collect(),
            None => angle_weighted_normals(&positions, &triangles),
        };
        if !is_flat(&positions, &triangles, &n) {
            normals = Some(n);
        }
    }
    Ok(PlacedMesh {
        positions: positions.iter().map(|x| x.as_vec3()).collect(),
        triangles,
        zero_normals: normals
            .iter()
            .flatten()
            .filter(|n| **n == DVec3::ZERO)
            .count(),
        normals: normals.map(|n| n.iter().map(|n| n.as_vec3()).collect()),
        uvs: mesh.uvs,
    })
}

/// Mitsuba's `recompute_vertex_normals`: each face's normal weighted by its angle at the
/// vertex.
fn angle_weighted_normals(positions: &[DVec3], triangles: &[[u32; 3]]) -> Vec<DVec3> {
    let mut normals = vec![DVec3::ZERO; positions.len()];
    for t in triangles {
        let v = t.map(|i| positions[i as usize]);
        let n = (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero();
        for i in 0..3 {
            let d0 = (v[(i + 1) % 3] - v[i]).normalize_or_zero();
            let d1 = (v[(i + 2) % 3] - v[i]).normalize_or_zero();
            let angle = d0.dot(d1).clamp(-1.0, 1.0).acos();
            normals[t[i] as usize] += n * angle;
        }
    }
    normals.iter().map(|n| n.normalize_or_zero()).collect()
}

/// Smallest cosine between a vertex normal and its face's normal that still shades as the
/// flat face: 1e-5 rad, far below what an f32 shading normal resolves.
const FLAT_COS: f64 = 1.0 - 5e-11;

/// Whether every vertex normal equals the normals of its (non-degenerate) faces: the shape
/// then shades flat, as fast and with the same numbers as a mesh without vertex normals.
fn is_flat(positions: &[DVec3], triangles: &[[u32; 3]], normals: &[DVec3]) -> bool {
    triangles.iter().all(|t| {
        let v = t.map(|i| positions[i as usize]);
        let ng = (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero();
        ng == DVec3::ZERO || t.iter().all(|&i| normals[i as usize].dot(ng) >= FLAT_COS)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cube_faces_point_outward() {
        let m = cube();
        assert_eq!(m.triangles.len(), 12);
        for t in &m.triangles {
            let v = t.map(|i| m.positions[i as usize]);
            let n = (v[1] - v[0]).cross(v[2] - v[0]);
            let centre = (v[0] + v[1] + v[2]) / 3.0;
            assert!(n.dot(centre) > 0.0, "{t:?}");
        }
    }

    #[test]
    fn obj_indices_are_checked() {
        assert_eq!(obj_index(Some("2"), 3), Ok(Some(1)));
        assert_eq!(obj_index(Some("-1"), 3), Ok(Some(2)));
        assert_eq!(obj_index(Some(""), 3), Ok(None));
        assert!(obj_index(Some("4"), 3).is_err());
        assert!(obj_index(Some("0"), 3).is_err());
        assert!(obj_index(Some("x"), 3).is_err());
    }
}
