//! The plan file (`genpath learn … -o plan.bin`, read by `render --plan plan.bin`, and of
//! `learn --for-reference`, by `reference --plan`): the
//! learned state of a method that learns ([`Learned`]: the GA plan, the spatial guide with
//! its training's per-pixel sums and decisions), trained once and shared by every shard of
//! a render. Little-endian throughout:
//!
//! | bytes | what |
//! | --- | --- |
//! | 8 | the mark `GPPLAN\0\0` |
//! | 4 | format version, `u32` ([`VERSION`]) |
//! | 4 | header length `H`, `u32` (at most [`MAX_HEADER`]) |
//! | H | the [`PlanHeader`] as JSON (UTF-8): the render's identity, the training's samples per pixel, a summary |
//! | 8 | payload length `L`, `u64` |
//! | L | the payload: [`Learned`] in `bincode` 1 (fixed-width integers, `f32`/`f64` as their bits): the method's name, its training's per-pixel sums, its own state (itself `bincode`) and a summary; for a reference (`learn --for-reference`), its two halves' one after the other |
//! | 4 | CRC-32 (IEEE) of every byte before it |
//!
//! The payload round-trips exactly (every float as its bits); caches (a plan's lookup
//! index) are not in it and are rebuilt on first use.

use super::Identity;
use crate::genetic::plan::WaveEntry;
use crate::integrators::Learned;
use bincode::Options;
use std::path::{Path, PathBuf};

/// The format version this genpath writes and reads.
pub const VERSION: u32 = 4;
/// The mark every plan file starts with.
pub const MAGIC: &[u8; 8] = b"GPPLAN\0\0";
/// The longest header read.
pub const MAX_HEADER: u32 = 1 << 24;

/// What a plan file says about its learned state.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlanHeader {
    /// The identity of the render it was learned for (command `render` or `reference`, no
    /// plan): a render or reference with `--plan` must have this identity.
    pub identity: Identity,
    /// Samples per pixel the training took (pg's and ga-pt's spatial training passes, and
    /// a GA plan's baseline), which the learn job wrote to its training shard.
    pub training_spp: u32,
    /// What was learned, in brief (GA pixels, spatial passes, the trials' decisions).
    pub summary: serde_json::Value,
    /// For the record, not compared: where the scene was and the command line.
    pub scene_path: PathBuf,
    pub command_line: Vec<String>,
}

/// Why a plan file cannot be written or read.
#[derive(Debug, thiserror::Error)]
pub enum PlanFileError {
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}: not a genpath {kind} file (it does not start with the {kind} format's mark)", path.display())]
    NotPlan { path: PathBuf, kind: &'static str },
    #[error("{}: {kind} format version {found}; this genpath reads version {VERSION}", path.display())]
    Version {
        path: PathBuf,
        kind: &'static str,
        found: u32,
    },
    #[error("{}: bad header: {message}", path.display())]
    Header { path: PathBuf, message: String },
    #[error("{}: truncated or padded: {found} bytes where the header promises {expected}", path.display())]
    Length {
        path: PathBuf,
        found: u64,
        expected: u64,
    },
    #[error("{}: corrupted: its checksum does not match its contents", path.display())]
    Checksum { path: PathBuf },
    #[error("{}: bad contents: {message}", path.display())]
    Payload { path: PathBuf, message: String },
}

/// Why a plan file's bytes were not encoded: its payload's `bincode` error or its
/// header's JSON error.
#[derive(Debug, thiserror::Error)]
pub enum EncodeError {
    #[error(transparent)]
    Payload(#[from] bincode::Error),
    #[error(transparent)]
    Header(#[from] serde_json::Error),
}

/// The payload's encoding: `bincode` with fixed-width little-endian integers, nothing after.
fn codec() -> impl Options {
    bincode::options()
        .with_fixint_encoding()
        .with_little_endian()
        .reject_trailing_bytes()
}

/// The payload's bytes: what a render's identity hashes ([`super::hash_bytes`]).
pub fn payload(learned: &Learned) -> Result<Vec<u8>, EncodeError> {
    Ok(codec().serialize(learned)?)
}

/// The payload's bytes of a reference's plan: its two halves' learned states, one after
/// the other.
pub fn payload_halves(first: &Learned, second: &Learned) -> Result<Vec<u8>, EncodeError> {
    Ok(codec().serialize(&(first, second))?)
}

/// The file's bytes, from its header and payload.
pub fn encode(header: &PlanHeader, payload: &[u8]) -> Result<Vec<u8>, EncodeError> {
    encode_framed(&PLAN, header, payload)
}

/// Writes a plan file atomically (temporary file, then rename).
pub fn write(path: &Path, header: &PlanHeader, payload: &[u8]) -> Result<(), PlanFileError> {
    write_framed(&PLAN, path, header, payload)
}

/// A file of this module's layout (a JSON header, then a `bincode` payload): its mark,
/// version and name.
struct Kind {
    magic: &'static [u8; 8],
    version: u32,
    name: &'static str,
}

const PLAN: Kind = Kind {
    magic: MAGIC,
    version: VERSION,
    name: "plan",
};

fn encode_framed(
    kind: &Kind,
    header: &impl serde::Serialize,
    payload: &[u8],
) -> Result<Vec<u8>, EncodeError> {
    let json = serde_json::to_vec(header)?;
    let body = |out: &mut Vec<u8>| {
        out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
        out.extend_from_slice(payload);
    };
    Ok(super::frame::encode(
        kind.magic,
        kind.version,
        &json,
        8 + payload.len(),
        body,
    ))
}

/// [`write_framed`] of `value` encoded as the payload.
fn write_serialized(
    kind: &Kind,
    path: &Path,
    header: &impl serde::Serialize,
    value: &(impl serde::Serialize + ?Sized),
) -> Result<(), PlanFileError> {
    let payload = codec()
        .serialize(value)
        .map_err(|e| PlanFileError::Payload {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
    write_framed(kind, path, header, &payload)
}

fn write_framed(
    kind: &Kind,
    path: &Path,
    header: &impl serde::Serialize,
    payload: &[u8],
) -> Result<(), PlanFileError> {
    let io = |message: String| PlanFileError::Io {
        path: path.to_path_buf(),
        source: std::io::Error::other(message),
    };
    let bytes = encode_framed(kind, header, payload).map_err(|e| io(e.to_string()))?;
    crate::image::write_bytes_atomic(path, &bytes).map_err(|e| io(e.to_string()))
}

/// A plan file read and checked: its header, its learned states (a render's one, a
/// reference's two halves in order), and the hash of its payload.
pub struct PlanFile {
    pub header: PlanHeader,
    pub learned: Vec<Learned>,
    pub hash: String,
}

/// Reads and checks the plan file at `path`: its mark, version, length and checksum, then
/// its header and payload (a reference's two halves where the header's identity is a
/// reference's).
pub fn read(path: &Path) -> Result<PlanFile, PlanFileError> {
    let (header, payload): (PlanHeader, _) = read_bytes(&PLAN, path)?;
    let decoded = if header.identity.command == "reference" {
        decode::<(Learned, Learned)>(path, &payload).map(|(a, b)| vec![a, b])
    } else {
        decode::<Learned>(path, &payload).map(|l| vec![l])
    };
    Ok(PlanFile {
        header,
        learned: decoded?,
        hash: super::hash_bytes(&payload),
    })
}

/// Decodes the payload `bytes` of the file at `path`.
fn decode<P: serde::de::DeserializeOwned>(path: &Path, bytes: &[u8]) -> Result<P, PlanFileError> {
    codec()
        .deserialize(bytes)
        .map_err(|e| PlanFileError::Payload {
            path: path.to_path_buf(),
            message: e.to_string(),
        })
}

/// Reads and checks a file of `kind` at `path`: its header, its payload, and the payload's
/// hash.
fn read_framed<H: serde::de::DeserializeOwned, P: serde::de::DeserializeOwned>(
    kind: &Kind,
    path: &Path,
) -> Result<(H, P, String), PlanFileError> {
    let (header, payload) = read_bytes(kind, path)?;
    let contents = decode(path, &payload)?;
    Ok((header, contents, super::hash_bytes(&payload)))
}

/// Reads and checks a file of `kind` at `path`: its header and its payload's bytes.
fn read_bytes<H: serde::de::DeserializeOwned>(
    kind: &Kind,
    path: &Path,
) -> Result<(H, Vec<u8>), PlanFileError> {
    let bytes = std::fs::read(path).map_err(|source| PlanFileError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let length = |found: usize, expected: usize| PlanFileError::Length {
        path: path.to_path_buf(),
        found: found as u64,
        expected: expected as u64,
    };
    if bytes.len() < 8 || &bytes[..8] != kind.magic {
        return Err(PlanFileError::NotPlan {
            path: path.to_path_buf(),
            kind: kind.name,
        });
    }
    let word = |i: usize| -> Result<[u8; 4], PlanFileError> {
        bytes
            .get(i..i + 4)
            .and_then(|b| b.try_into().ok())
            .ok_or_else(|| length(bytes.len(), i + 4))
    };
    let version = u32::from_le_bytes(word(8)?);
    if version != kind.version {
        return Err(PlanFileError::Version {
            path: path.to_path_buf(),
            kind: kind.name,
            found: version,
        });
    }
    let h = u32::from_le_bytes(word(12)?);
    let bad_header = |message: String| PlanFileError::Header {
        path: path.to_path_buf(),
        message,
    };
    if h > MAX_HEADER {
        return Err(bad_header(format!(
            "header length {h} is more than {MAX_HEADER} bytes"
        )));
    }
    let at = 16 + h as usize;
    let l = bytes
        .get(at..at + 8)
        .and_then(|b| b.try_into().ok())
        .map(u64::from_le_bytes)
        .ok_or_else(|| length(bytes.len(), at + 8))?;
    let expected = (at as u64 + 8).saturating_add(l).saturating_add(4);
    if bytes.len() as u64 != expected {
        return Err(PlanFileError::Length {
            path: path.to_path_buf(),
            found: bytes.len() as u64,
            expected,
        });
    }
    let (body, crc) = bytes.split_at(bytes.len() - 4);
    if crc32fast::hash(body) != u32::from_le_bytes(word(bytes.len() - 4)?) || crc.len() != 4 {
        return Err(PlanFileError::Checksum {
            path: path.to_path_buf(),
        });
    }
    let header: H = serde_json::from_slice(&body[16..at]).map_err(|e| bad_header(e.to_string()))?;
    Ok((header, body[at + 8..].to_vec()))
}

/// The mark every wave file starts with.
pub const WAVES_MAGIC: &[u8; 8] = b"GPWAVES\0";

const WAVES: Kind = Kind {
    magic: WAVES_MAGIC,
    version: 1,
    name: "GA wave",
};

/// What a wave file (`genpath learn`'s GA pixels of one wave, evolved by one job) says
/// about its results.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WaveHeader {
    /// The identity of the render the plan is learned for (as a plan file's).
    pub identity: Identity,
    /// The wave's number, and how many GA pixels it has.
    pub wave: usize,
    pub jobs: usize,
    /// The job that evolved them: `K/N` of `learn --shard K/N` (`0/1` unsplit).
    pub shard: String,
}

/// Writes a wave file atomically.
pub fn write_waves(
    path: &Path,
    header: &WaveHeader,
    entries: &[WaveEntry],
) -> Result<(), PlanFileError> {
    write_serialized(&WAVES, path, header, entries)
}

/// Reads and checks the wave file at `path`.
pub fn read_waves(path: &Path) -> Result<(WaveHeader, Vec<WaveEntry>), PlanFileError> {
    let (header, entries, _) = read_framed(&WAVES, path)?;
    Ok((header, entries))
}

const TRAINING: Kind = Kind {
    magic: b"GPTRAIN\0",
    version: 1,
    name: "spatial training",
};

/// What a training file (`genpath learn`'s spatial guide after its last finished pass) says
/// about it.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrainingHeader {
    /// The identity of the render the plan is learned for (as a plan file's).
    pub identity: Identity,
    /// Passes finished.
    pub passes: u32,
}

/// Writes a training file atomically: `state` is the training as the spatial guide encodes
/// it.
pub fn write_training(
    path: &Path,
    header: &TrainingHeader,
    state: &[u8],
) -> Result<(), PlanFileError> {
    write_serialized(&TRAINING, path, header, state)
}

/// Reads and checks the training file at `path`.
pub fn read_training(path: &Path) -> Result<(TrainingHeader, Vec<u8>), PlanFileError> {
    let (header, state, _) = read_framed(&TRAINING, path)?;
    Ok((header, state))
}
