//! The shard file, little-endian throughout:
//!
//! | bytes | what |
//! | --- | --- |
//! | 8 | the mark `GPSHARD\0` |
//! | 4 | format version, `u32` ([`VERSION`]) |
//! | 4 | header length `H`, `u32` (at most [`MAX_HEADER`]) |
//! | H | the [`Header`] as JSON (UTF-8) |
//! | per layer | `P` sample counts `u32`, then `3P` sums `f64` (r, g, b per pixel), then `3P` sums of squares `f64` |
//! | after each layer, if the header's `splats` | the splat layer: its light paths `u64`, its passes `u64`, then `3P` sums `f64`, then `3P` sums of squares `f64` (per pass) |
//! | 4 | CRC-32 (IEEE) of every byte before it |
//!
//! with `P` = width × height pixels, pixels row by row. The length follows from the header,
//! so a truncated file is refused before its checksum is even read.

use super::{Header, LayerSums, ShardError};
use crate::film::SplatLayer;
use glam::DVec3;
use std::io::Read;
use std::path::Path;

/// The format version this genpath writes and reads.
pub const VERSION: u32 = 2;
/// The mark every shard file starts with.
pub const MAGIC: &[u8; 8] = b"GPSHARD\0";
/// The longest header read, so that a corrupted length does not allocate gigabytes.
pub const MAX_HEADER: u32 = 1 << 24;
/// Bytes per pixel and layer: a count and six `f64`s.
const PIXEL_BYTES: u64 = 4 + 6 * 8;

/// The file's bytes.
pub fn encode(header: &Header, layers: &[LayerSums]) -> Vec<u8> {
    let header = Header {
        splats: layers.iter().any(|l| l.splats.is_some()),
        ..header.clone()
    };
    let json = serde_json::to_vec(&header).expect("a header serialises");
    let body_len = layers.len() * layer_bytes(&header) as usize;
    super::frame::encode(MAGIC, VERSION, &json, body_len, |out| {
        for layer in layers {
            for c in &layer.counts {
                out.extend_from_slice(&c.to_le_bytes());
            }
            put_vectors(out, &layer.sum);
            put_vectors(out, &layer.sum_sq);
            if header.splats {
                let zero = SplatLayer::zero(layer.counts.len());
                let splats = layer.splats.as_ref().unwrap_or(&zero);
                out.extend_from_slice(&splats.light_paths.to_le_bytes());
                out.extend_from_slice(&splats.passes.to_le_bytes());
                put_vectors(out, &splats.sum);
                put_vectors(out, &splats.sum_sq);
            }
        }
    })
}

/// Appends `values`' components, r, g, b per pixel.
fn put_vectors(out: &mut Vec<u8>, values: &[DVec3]) {
    for v in values.iter().flat_map(|v| v.to_array()) {
        out.extend_from_slice(&v.to_le_bytes());
    }
}

/// Bytes of one layer (with its splat layer, if the header has them).
fn layer_bytes(header: &Header) -> u64 {
    let pixels = header.pixels();
    let splats = if header.splats { 16 + 48 * pixels } else { 0 };
    pixels * PIXEL_BYTES + splats
}

/// Writes a shard file atomically (temporary file, then rename).
pub fn write(path: &Path, header: &Header, layers: &[LayerSums]) -> Result<(), ShardError> {
    crate::image::write_bytes_atomic(path, &encode(header, layers)).map_err(|e| ShardError::Io {
        path: path.to_path_buf(),
        source: std::io::Error::other(e.to_string()),
    })
}

/// Reads only the header of the shard file at `path`, checked as far as it goes.
pub fn read_header(path: &Path) -> Result<Header, ShardError> {
    let mut file = std::fs::File::open(path).map_err(|source| io(path, source))?;
    let mut prefix = [0u8; 16];
    let got = read_up_to(&mut file, &mut prefix).map_err(|source| io(path, source))?;
    let length = header_length(path, &prefix[..got])?;
    let mut json = vec![0u8; length as usize];
    let got = read_up_to(&mut file, &mut json).map_err(|source| io(path, source))?;
    if got < json.len() {
        let found = file.metadata().map_or(0, |m| m.len());
        return Err(ShardError::Length {
            path: path.to_path_buf(),
            found,
            expected: 16 + u64::from(length),
        });
    }
    parse_header(path, &json)
}

/// Reads and checks the whole shard file at `path`: its length, checksum and header, and
/// that no pixel holds more samples than its shard has.
pub fn read(path: &Path) -> Result<(Header, Vec<LayerSums>), ShardError> {
    let bytes = std::fs::read(path).map_err(|source| io(path, source))?;
    let length = header_length(path, &bytes[..bytes.len().min(16)])? as usize;
    let too_short = || ShardError::Length {
        path: path.to_path_buf(),
        found: bytes.len() as u64,
        expected: (16 + length) as u64,
    };
    let json = bytes.get(16..16 + length).ok_or_else(too_short)?;
    let header = parse_header(path, json)?;
    let pixels = header.pixels();
    let expected = 16 + length as u64 + header.layers() as u64 * layer_bytes(&header) + 4;
    if bytes.len() as u64 != expected {
        return Err(ShardError::Length {
            path: path.to_path_buf(),
            found: bytes.len() as u64,
            expected,
        });
    }
    let (body, crc) = bytes.split_at(bytes.len() - 4);
    if crc32fast::hash(body) != u32::from_le_bytes(crc.try_into().expect("4 bytes")) {
        return Err(ShardError::Checksum {
            path: path.to_path_buf(),
        });
    }
    let pixels = pixels as usize;
    let most = header.shard.samples_of(header.identity.spp);
    let mut at = 16 + length;
    let mut layers = Vec::with_capacity(header.layers());
    for _ in 0..header.layers() {
        let counts: Vec<u32> = body[at..at + 4 * pixels]
            .chunks_exact(4)
            .map(|b| u32::from_le_bytes(b.try_into().expect("4 bytes")))
            .collect();
        at += 4 * pixels;
        let sum = take_vectors(body, &mut at, pixels);
        let sum_sq = take_vectors(body, &mut at, pixels);
        let splats = if header.splats {
            let count =
                |at: usize| u64::from_le_bytes(body[at..at + 8].try_into().expect("8 bytes"));
            let (light_paths, passes) = (count(at), count(at + 8));
            at += 16;
            Some(SplatLayer {
                light_paths,
                passes,
                sum: take_vectors(body, &mut at, pixels),
                sum_sq: take_vectors(body, &mut at, pixels),
            })
        } else {
            None
        };
        if header.splats && counts.iter().any(|&c| c != counts[0]) {
            // A render that splats stops only between passes of one sample per pixel.
            return Err(ShardError::Inconsistent {
                path: path.to_path_buf(),
                message: "its pixels hold different sample counts beside a splat layer".into(),
            });
        }
        if let Some(i) = counts.iter().position(|&c| c > most) {
            return Err(ShardError::Inconsistent {
                path: path.to_path_buf(),
                message: format!(
                    "pixel {i} holds {} samples, more than the {most} of shard {} at {} spp",
                    counts[i], header.shard, header.identity.spp
                ),
            });
        }
        layers.push(LayerSums {
            counts,
            sum,
            sum_sq,
            splats,
        });
    }
    Ok((header, layers))
}

/// The `pixels` vectors at `body[*at..]`, r, g, b per pixel; moves `at` past them.
fn take_vectors(body: &[u8], at: &mut usize, pixels: usize) -> Vec<DVec3> {
    let v = body[*at..*at + 24 * pixels]
        .chunks_exact(24)
        .map(|b| {
            DVec3::from_array(std::array::from_fn(|c| {
                f64::from_le_bytes(b[8 * c..8 * c + 8].try_into().expect("8 bytes"))
            }))
        })
        .collect();
    *at += 24 * pixels;
    v
}

/// The header's length from the file's first 16 bytes (`prefix`, fewer if the file is
/// shorter), after its mark and version.
fn header_length(path: &Path, prefix: &[u8]) -> Result<u32, ShardError> {
    if prefix.len() < 8 || &prefix[..8] != MAGIC {
        return Err(ShardError::NotShard {
            path: path.to_path_buf(),
        });
    }
    if prefix.len() < 16 {
        return Err(ShardError::Length {
            path: path.to_path_buf(),
            found: prefix.len() as u64,
            expected: 16,
        });
    }
    let word = |i: usize| u32::from_le_bytes(prefix[i..i + 4].try_into().expect("4 bytes"));
    let version = word(8);
    if version != VERSION {
        return Err(ShardError::Version {
            path: path.to_path_buf(),
            found: version,
        });
    }
    let length = word(12);
    if length > MAX_HEADER {
        return Err(ShardError::Header {
            path: path.to_path_buf(),
            message: format!("header length {length} is more than {MAX_HEADER} bytes"),
        });
    }
    Ok(length)
}

/// The header from its JSON, with its shard and sizes checked.
fn parse_header(path: &Path, json: &[u8]) -> Result<Header, ShardError> {
    let bad = |message: String| ShardError::Header {
        path: path.to_path_buf(),
        message,
    };
    let header: Header = serde_json::from_slice(json).map_err(|e| bad(e.to_string()))?;
    let id = &header.identity;
    let shard = header.shard;
    if shard.count == 0 || shard.index >= shard.count {
        return Err(bad(format!("shard {shard} is not K/N with K < N")));
    }
    let side = 1..=crate::scene::MAX_IMAGE_SIDE;
    if !side.contains(&id.width) || !side.contains(&id.height) {
        return Err(bad(format!("image size {}×{}", id.width, id.height)));
    }
    if !(1..=2).contains(&header.layers()) {
        return Err(bad(format!("{} layers (1 or 2)", header.layers())));
    }
    Ok(header)
}

/// Reads into `buf` until it is full or the file ends; the bytes read.
fn read_up_to(file: &mut std::fs::File, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut got = 0;
    while got < buf.len() {
        match file.read(&mut buf[got..])? {
            0 => break,
            n => got += n,
        }
    }
    Ok(got)
}

fn io(path: &Path, source: std::io::Error) -> ShardError {
    ShardError::Io {
        path: path.to_path_buf(),
        source,
    }
}
