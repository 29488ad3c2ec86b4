//! The mesh every shape reader returns (`obj` in `shapes`, `ply`, `serialized`, and the
//! built-in shapes), apart from the readers so that they and the shape builder that calls
//! them all import it from here.

use glam::{DVec3, Vec2};

/// A mesh in object space, as a file or a built-in shape gives it.
#[derive(Debug, Default)]
pub struct RawMesh {
    pub positions: Vec<DVec3>,
    pub triangles: Vec<[u32; 3]>,
    /// Per-vertex normals, when the mesh has them.
    pub normals: Option<Vec<DVec3>>,
    /// Per-vertex texture coordinates, when the mesh has them (`None` for a vertex that has
    /// none in a mesh whose other vertices do).
    pub uvs: Option<Vec<Option<Vec2>>>,
}

/// A face index of a mesh (`what`) that names no vertex.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{what}: face index {index} is out of range ({vertices} vertices)")]
pub struct FaceIndexError {
    pub what: String,
    pub index: u32,
    pub vertices: u64,
}

impl RawMesh {
    /// Checks that every index names a vertex.
    pub fn check_indices(&self, what: &str) -> Result<(), FaceIndexError> {
        let n = self.positions.len() as u64;
        match self
            .triangles
            .iter()
            .flatten()
            .find(|&&i| u64::from(i) >= n)
        {
            Some(&index) => Err(FaceIndexError {
                what: what.to_string(),
                index,
                vertices: n,
            }),
            None => Ok(()),
        }
    }
}
