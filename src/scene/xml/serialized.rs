//! Mitsuba's `serialized` meshes, format versions 3 and 4 (the format of published scenes):
//! a `0x041C` magic and version, then a zlib stream of flags, (v4) a name, vertex and
//! triangle counts, positions, optional normals, UVs and colours, and `u32` triangles;
//! files with several meshes end with a table of their offsets (`shape_index`).

use super::mesh::{FaceIndexError, RawMesh};
use flate2::read::ZlibDecoder;
use glam::{DVec3, Vec2};
use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

const MAGIC: u16 = 0x041C;
const HAS_NORMALS: u32 = 0x0001;
const HAS_TEXCOORDS: u32 = 0x0002;
const HAS_COLORS: u32 = 0x0008;
const DOUBLE_PRECISION: u32 = 0x2000;

fn read_u16(r: &mut impl Read) -> std::io::Result<u16> {
    let mut b = [0; 2];
    r.read_exact(&mut b)?;
    Ok(u16::from_le_bytes(b))
}
fn read_u32(r: &mut impl Read) -> std::io::Result<u32> {
    let mut b = [0; 4];
    r.read_exact(&mut b)?;
    Ok(u32::from_le_bytes(b))
}
fn read_u64(r: &mut impl Read) -> std::io::Result<u64> {
    let mut b = [0; 8];
    r.read_exact(&mut b)?;
    Ok(u64::from_le_bytes(b))
}

/// `count` vectors of `dim` floats (f32 or f64).
fn read_floats(
    r: &mut impl Read,
    count: u64,
    dim: usize,
    double: bool,
) -> std::io::Result<Vec<f64>> {
    let width = if double { 8 } else { 4 };
    let mut bytes = vec![0u8; count as usize * dim * width];
    r.read_exact(&mut bytes)?;
    Ok(if double {
        bytes
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().unwrap_or_default()))
            .collect()
    } else {
        bytes
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes(c.try_into().unwrap_or_default()).into())
            .collect()
    })
}

/// Why a Mitsuba serialized file gives no mesh; the caller names the file.
#[derive(Debug, thiserror::Error)]
pub enum SerializedError {
    #[error("cannot read: {0}")]
    Read(std::io::Error),
    #[error("truncated or malformed serialized mesh: {0}")]
    Malformed(std::io::Error),
    #[error("not a Mitsuba serialized mesh (bad magic number)")]
    BadMagic,
    #[error("version 5 serialized meshes are not supported yet (convert the mesh to PLY)")]
    Version5,
    #[error("serialized format version {0} is not 3 or 4")]
    Version(u16),
    #[error("shape_index {index} is out of range (the file has {count} meshes)")]
    IndexOutOfRange { index: u32, count: u32 },
    #[error("mesh {index}'s offset {offset} is beyond the file")]
    OffsetBeyondFile { index: u32, offset: u64 },
    #[error("implausible counts ({vertices} vertices, {faces} triangles) for a {size}-byte file")]
    Counts {
        vertices: u64,
        faces: u64,
        size: u64,
    },
    #[error("vertex {0} is not finite")]
    VertexNotFinite(usize),
    #[error(transparent)]
    FaceIndex(#[from] FaceIndexError),
}

/// Mesh `index` of the file.
pub fn load(path: &Path, index: u32) -> Result<RawMesh, SerializedError> {
    let io = SerializedError::Malformed;
    let mut file = std::fs::File::open(path).map_err(SerializedError::Read)?;
    let size = file.metadata().map_err(io)?.len();
    if read_u16(&mut file).map_err(io)? != MAGIC {
        return Err(SerializedError::BadMagic);
    }
    let version = read_u16(&mut file).map_err(io)?;
    if version == 5 {
        return Err(SerializedError::Version5);
    }
    if version != 3 && version != 4 {
        return Err(SerializedError::Version(version));
    }
    if index > 0 {
        file.seek(SeekFrom::End(-4)).map_err(io)?;
        let count = read_u32(&mut file).map_err(io)?;
        if index >= count {
            return Err(SerializedError::IndexOutOfRange { index, count });
        }
        let entry = if version == 4 { 8 } else { 4 };
        let back = 4 + entry * i64::from(count - index);
        file.seek(SeekFrom::End(-back)).map_err(io)?;
        let offset = if version == 4 {
            read_u64(&mut file).map_err(io)?
        } else {
            read_u32(&mut file).map_err(io)?.into()
        };
        if offset >= size {
            return Err(SerializedError::OffsetBeyondFile { index, offset });
        }
        file.seek(SeekFrom::Start(offset + 4)).map_err(io)?;
    }
    let mut z = ZlibDecoder::new(std::io::BufReader::new(file));
    let flags = read_u32(&mut z).map_err(io)?;
    if version == 4 {
        // The null-terminated shape name.
        let mut b = [0u8; 1];
        loop {
            z.read_exact(&mut b).map_err(io)?;
            if b[0] == 0 {
                break;
            }
        }
    }
    let vertices = read_u64(&mut z).map_err(io)?;
    let faces = read_u64(&mut z).map_err(io)?;
    // A compressed stream can expand ~1000×; counts far beyond that are corrupt.
    let limit = size.saturating_mul(1100);
    if vertices.saturating_mul(12) > limit
        || faces.saturating_mul(12) > limit
        || vertices > u64::from(u32::MAX)
    {
        return Err(SerializedError::Counts {
            vertices,
            faces,
            size,
        });
    }
    let double = flags & DOUBLE_PRECISION != 0;
    let p = read_floats(&mut z, vertices, 3, double).map_err(io)?;
    let normals = if flags & HAS_NORMALS != 0 {
        Some(read_floats(&mut z, vertices, 3, double).map_err(io)?)
    } else {
        None
    };
    let uvs = if flags & HAS_TEXCOORDS != 0 {
        Some(read_floats(&mut z, vertices, 2, double).map_err(io)?)
    } else {
        None
    };
    if flags & HAS_COLORS != 0 {
        read_floats(&mut z, vertices, 3, double).map_err(io)?;
    }
    let mut bytes = vec![0u8; faces as usize * 12];
    z.read_exact(&mut bytes).map_err(io)?;
    let vec3 = |v: &[f64]| {
        v.chunks_exact(3)
            .map(|c| DVec3::new(c[0], c[1], c[2]))
            .collect::<Vec<_>>()
    };
    let positions = vec3(&p);
    if let Some(i) = positions.iter().position(|x| !x.is_finite()) {
        return Err(SerializedError::VertexNotFinite(i));
    }
    let triangles: Vec<[u32; 3]> = bytes
        .chunks_exact(12)
        .map(|c| [0, 4, 8].map(|o| u32::from_le_bytes([c[o], c[o + 1], c[o + 2], c[o + 3]])))
        .collect();
    let mesh = RawMesh {
        positions,
        triangles,
        normals: normals.as_deref().map(vec3),
        uvs: uvs.map(|uv| {
            uv.chunks_exact(2)
                .map(|c| Some(Vec2::new(c[0] as f32, c[1] as f32)).filter(|uv| uv.is_finite()))
                .collect()
        }),
    };
    mesh.check_indices("serialized mesh")?;
    Ok(mesh)
}
