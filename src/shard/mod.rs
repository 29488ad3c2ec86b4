//! Shards of one render (docs/shards.md): `render --shard K/N` takes sample `s` of every
//! pixel when `s mod N = K`, from the same random stream `(seed, pixel, s)` as a render on
//! one machine, and keeps its per-pixel sums in a shard file ([`file`]); [`merge`] adds
//! shards' sums. A shard records what makes it part of one render, its [`Identity`]: the
//! genpath binary, the scene's files, the settings and the seeds, and a merge refuses
//! shards whose identities differ.
//!
//! A method that learns (`ga`, `ga-pt`, `pg`) is sharded with its learned state trained
//! once, by `genpath learn`, and saved in a plan file ([`plan_file`]) that every shard
//! renders with; the learn job's training samples, which the image keeps, are a shard file
//! of their own ([`Part::Training`]).

pub mod file;
mod frame;
pub mod merge;
pub mod plan_file;

pub use crate::film::LayerSums;
use crate::film::Shard;
use crate::integrators::{RenderSettings, Settings};
use std::hash::Hasher;
use std::path::{Path, PathBuf};

/// What makes shards parts of one render: two shards merge only if these are equal.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Identity {
    /// The command that rendered it: `render` (one layer) or `reference` (two halves).
    pub command: String,
    pub genpath_version: String,
    /// Hash of the bytes of the genpath binary that rendered it.
    pub build: String,
    /// Hash of the bytes of every file the scene was read from and its `-D` parameters.
    pub scene: String,
    /// Hash of the bytes of `--generators FILE` (`--method mixture`).
    pub generators: Option<String>,
    pub width: u32,
    pub height: u32,
    /// The ray-tracing back-end.
    pub accel: String,
    pub method: String,
    /// Samples per pixel of each layer in the whole render.
    pub spp: u32,
    pub max_bounces: u32,
    /// `--seed`.
    pub seed: u64,
    /// The seed of each layer's random streams (a reference's two halves have their own).
    pub layer_seeds: Vec<u64>,
    /// Every method setting, as `--config` writes them.
    pub settings: serde_json::Value,
    /// The half of a reference (1 or 2) that a file of `genpath learn --for-reference`'s
    /// learning folder was learned for (its waves, its training): none elsewhere.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub half: Option<u32>,
    /// The plan file (`render --plan`, `reference --plan`) whose learned state the render
    /// used, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plan: Option<PlanRef>,
}

/// The learned state a render used, as its shards' identity records it: shards merge only
/// if they rendered with the same plan file.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlanRef {
    /// Hash of the plan file's learned state ([`hash_bytes`] of its payload).
    pub hash: String,
    /// Samples per pixel its training took, which are in the learn job's training shard
    /// (0: none, as for `ga`); of a reference's plan, the most either half's took.
    pub training_spp: u32,
}

impl Identity {
    /// The identity of a render with `settings` (whose `seed` and `spp` are those of its
    /// first layer; `layer_seeds` the seeds of all) of the scene read from `files` with
    /// `defines`, traced with `accel`.
    pub fn new(
        command: &str,
        user_seed: u64,
        settings: &RenderSettings,
        layer_seeds: Vec<u64>,
        config: &Settings,
        scene: &SceneInputs,
        accel: &str,
    ) -> Result<Self, ShardError> {
        let generators = match &config.mixture.generators {
            Some(path) => Some(hex(hash_files(std::slice::from_ref(path), &[])?)),
            None => None,
        };
        Ok(Self {
            command: command.to_string(),
            genpath_version: env!("CARGO_PKG_VERSION").to_string(),
            build: hex(build_hash()?),
            scene: hex(hash_files(&scene.files, &scene.defines)?),
            generators,
            width: scene.width,
            height: scene.height,
            accel: accel.to_string(),
            method: settings.method.name(),
            spp: settings.spp,
            max_bounces: settings.max_bounces,
            seed: user_seed,
            layer_seeds,
            settings: serde_json::to_value(config).map_err(|e| ShardError::Header {
                path: PathBuf::new(),
                message: e.to_string(),
            })?,
            half: None,
            plan: None,
        })
    }

    /// The first difference from `other`, as `(what, this one's value, other's value)`,
    /// the fields compared in the order they are declared.
    pub fn difference(&self, other: &Identity) -> Option<(String, String, String)> {
        let (a, b) = (self.fields(), other.fields());
        a.iter()
            .zip(&b)
            .find_map(|((name, u), (_, v))| first_difference(u, v, name.to_string()))
    }

    fn fields(&self) -> [(&'static str, serde_json::Value); 16] {
        use serde_json::json;
        [
            ("command", json!(self.command)),
            ("genpath_version", json!(self.genpath_version)),
            ("build", json!(self.build)),
            ("scene", json!(self.scene)),
            ("generators", json!(self.generators)),
            ("width", json!(self.width)),
            ("height", json!(self.height)),
            ("accel", json!(self.accel)),
            ("method", json!(self.method)),
            ("spp", json!(self.spp)),
            ("max_bounces", json!(self.max_bounces)),
            ("seed", json!(self.seed)),
            ("layer_seeds", json!(self.layer_seeds)),
            ("settings", self.settings.clone()),
            ("half", json!(self.half)),
            ("plan", json!(self.plan)),
        ]
    }
}

/// The scene a shard renders, as its identity records it.
pub struct SceneInputs {
    /// Every file the scene was read from.
    pub files: Vec<PathBuf>,
    /// Its `-D NAME=VALUE` parameters.
    pub defines: Vec<(String, String)>,
    /// The image's size, after `--width` and `--height`.
    pub width: u32,
    pub height: u32,
}

/// What a shard file holds besides its sums.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Header {
    /// Which samples of every pixel it holds.
    pub shard: Shard,
    pub identity: Identity,
    /// For the record, not compared: where the scene was and the command line.
    pub scene_path: PathBuf,
    pub command_line: Vec<String>,
    /// Which of the render's samples it holds besides `shard`'s.
    #[serde(default, skip_serializing_if = "Part::is_samples")]
    pub part: Part,
    /// Whether each layer is followed by its splat layer (a method whose samples splat onto
    /// other pixels); [`file::encode`] sets it from the layers.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub splats: bool,
}

/// What a shard file holds, of a render whose identity has a [`PlanRef`] with training
/// samples (a render without one has only [`Part::Samples`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Part {
    /// Shard `K/N`'s samples of those the render takes after the training (all of them
    /// without a plan).
    #[default]
    Samples,
    /// The learn job's training samples alone (`genpath learn`; its `shard` is `0/1` and
    /// means nothing).
    Training,
    /// The training samples and every later sample: a render with `--plan` and no
    /// `--shard` that keeps a shard file (`--checkpoint`, `--resume`).
    WithTraining,
}

impl Part {
    pub fn is_samples(&self) -> bool {
        *self == Part::Samples
    }

    /// Whether the file holds the training samples.
    pub fn has_training(&self) -> bool {
        *self != Part::Samples
    }
}

impl Header {
    /// Pixels per layer.
    pub fn pixels(&self) -> u64 {
        u64::from(self.identity.width) * u64::from(self.identity.height)
    }

    pub fn layers(&self) -> usize {
        self.identity.layer_seeds.len()
    }
}

/// Why a shard cannot be written, read or merged.
#[derive(Debug, thiserror::Error)]
pub enum ShardError {
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}: not a genpath shard file (it does not start with the shard format's mark)", path.display())]
    NotShard { path: PathBuf },
    #[error("{}: shard format version {found}; this genpath reads version {}", path.display(), file::VERSION)]
    Version { path: PathBuf, found: u32 },
    #[error("{}: bad shard header: {message}", path.display())]
    Header { path: PathBuf, message: String },
    #[error("{}: truncated or padded: {found} bytes where the header promises {expected}", path.display())]
    Length {
        path: PathBuf,
        found: u64,
        expected: u64,
    },
    #[error("{}: corrupted: its checksum does not match its contents", path.display())]
    Checksum { path: PathBuf },
    #[error("{}: inconsistent: {message}", path.display())]
    Inconsistent { path: PathBuf, message: String },
    #[error(
        "{} and {} are not shards of one render: {what} differs ({a_value} in the first, {b_value} in the second)",
        a.display(), b.display()
    )]
    Mismatch {
        a: PathBuf,
        b: PathBuf,
        what: String,
        a_value: String,
        b_value: String,
    },
    #[error("{} and {} are both shard {shard}", a.display(), b.display())]
    Duplicate {
        a: PathBuf,
        b: PathBuf,
        shard: Shard,
    },
    #[error(
        "{} (shard {a_shard}) and {} (shard {b_shard}) overlap: both hold the samples s with s mod {modulus} = {residue}",
        a.display(), b.display()
    )]
    Overlap {
        a: PathBuf,
        b: PathBuf,
        a_shard: Shard,
        b_shard: Shard,
        modulus: u64,
        residue: u64,
    },
    #[error("{} and {} both hold the learn job's training samples", a.display(), b.display())]
    TwoTrainings { a: PathBuf, b: PathBuf },
    #[error("no shard files to merge")]
    Empty,
}

/// The first leaf where `a` and `b` differ, with its path (`settings.ga.test_paths`).
pub fn first_difference(
    a: &serde_json::Value,
    b: &serde_json::Value,
    path: String,
) -> Option<(String, String, String)> {
    use serde_json::Value;
    match (a, b) {
        (Value::Object(x), Value::Object(y)) => {
            let keys: std::collections::BTreeSet<_> = x.keys().chain(y.keys()).collect();
            keys.into_iter().find_map(|k| {
                let (u, v) = (x.get(k), y.get(k));
                let at = if path.is_empty() {
                    k.clone()
                } else {
                    format!("{path}.{k}")
                };
                match (u, v) {
                    (Some(u), Some(v)) => first_difference(u, v, at),
                    _ => Some((at, json_text(u), json_text(v))),
                }
            })
        }
        _ if a == b => None,
        _ => Some((path, a.to_string(), b.to_string())),
    }
}

fn json_text(v: Option<&serde_json::Value>) -> String {
    v.map_or_else(|| "nothing".to_string(), |v| v.to_string())
}

/// A 64-bit hash (std's SipHash with its fixed keys: the same in one binary, which every
/// identity pins) of `files`' bytes, each with its length, and `defines`.
pub fn hash_files(files: &[PathBuf], defines: &[(String, String)]) -> Result<u64, ShardError> {
    let mut hasher = std::hash::DefaultHasher::new();
    for path in files {
        let bytes = read_all(path)?;
        hasher.write_u64(bytes.len() as u64);
        hasher.write(&bytes);
    }
    for (name, value) in defines {
        for text in [name, value] {
            hasher.write_u64(text.len() as u64);
            hasher.write(text.as_bytes());
        }
    }
    Ok(hasher.finish())
}

/// A 64-bit hash of `bytes` (as [`hash_files`] hashes a file), in hexadecimal.
pub fn hash_bytes(bytes: &[u8]) -> String {
    let mut hasher = std::hash::DefaultHasher::new();
    hasher.write_u64(bytes.len() as u64);
    hasher.write(bytes);
    hex(hasher.finish())
}

/// The hash of the running genpath binary's bytes ([`hash_files`]).
pub fn build_hash() -> Result<u64, ShardError> {
    let exe = std::env::current_exe().map_err(|source| ShardError::Io {
        path: PathBuf::from("the genpath binary"),
        source,
    })?;
    hash_files(&[exe], &[])
}

fn read_all(path: &Path) -> Result<Vec<u8>, ShardError> {
    std::fs::read(path).map_err(|source| ShardError::Io {
        path: path.to_path_buf(),
        source,
    })
}

fn hex(hash: u64) -> String {
    format!("{hash:016x}")
}
