//! Adding shards' sums: the shards must be of one render ([`Identity`]) and hold no sample
//! twice; any set of them is a render with the samples they hold.
//!
//! The sums are added in the order of the shards' `(N, K)`, whatever the order of the files,
//! starting from the first shard's own sums: pixel `p`'s merged sum of 4 shards is
//! `((S₀ + S₁) + S₂) + S₃` with `S_K = Σ_{s mod 4 = K} x_s` added in increasing `s`. A
//! render on one machine adds `x₀ + x₁ + x₂ + …` in increasing `s`, so the two `f64` sums
//! may differ in their last bits (a relative difference below `spp · 2⁻⁵³`); the image's
//! `f32` pixels are equal unless a mean falls that close to the midpoint between two `f32`s.
//!
//! A render with a plan file (`render --plan`) whose training took samples has them in the
//! learn job's training shard ([`Part::Training`]): its sums come first, then the shards'.

use super::{file, Header, Identity, LayerSums, Part, ShardError};
use crate::film::{Shard, SplatLayer};
use std::path::{Path, PathBuf};

/// The most missing shards a [`Coverage::Missing`] lists.
pub const LISTED: usize = 32;

/// Shards added together.
#[derive(Debug)]
pub struct Merged {
    /// The first shard's header (its identity is every shard's).
    pub header: Header,
    /// The learn job's training shard, if merged: its sums were added first.
    pub training: Option<PathBuf>,
    /// The shards merged, in the order their sums were added (after the training shard's).
    pub shards: Vec<(PathBuf, Shard)>,
    /// The summed layers.
    pub layers: Vec<LayerSums>,
    pub coverage: Coverage,
}

/// How many of the render's samples the merged shards hold.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Coverage {
    /// Every sample: the merge is the whole render.
    Complete,
    /// Of `n` shards, `missing` are not there; `first` lists the first of them (at most
    /// [`LISTED`]).
    Missing {
        n: u32,
        missing: u32,
        first: Vec<u32>,
    },
    /// Shards of different `N`, or shards of a stopped render: the samples per pixel of
    /// the pixel that holds fewest, of the render's.
    Partial { spp: u32, of: u32 },
    /// No file holds the learn job's `training` samples per pixel (the render used a plan
    /// file whose training took them): the merge holds `spp` of the render's `of`.
    NoTraining { training: u32, spp: u32, of: u32 },
}

impl Merged {
    pub fn identity(&self) -> &Identity {
        &self.header.identity
    }
}

/// Reads the shard files at `paths` and adds their sums; refuses files that are not
/// complete, uncorrupted shards of one render, and shards that share samples.
pub fn merge(paths: &[PathBuf]) -> Result<Merged, ShardError> {
    let mut headers = paths
        .iter()
        .map(|p| Ok((p.clone(), file::read_header(p)?)))
        .collect::<Result<Vec<_>, ShardError>>()?;
    let Some((first_path, first)) = headers.first().cloned() else {
        return Err(ShardError::Empty);
    };
    for (path, header) in &headers[1..] {
        if let Some((what, a_value, b_value)) = first.identity.difference(&header.identity) {
            return Err(ShardError::Mismatch {
                a: first_path.clone(),
                b: path.clone(),
                what,
                a_value,
                b_value,
            });
        }
    }
    check_training(&headers, &first)?;
    // The training shard first, then the others in increasing (N, K).
    headers.sort_by_key(|(_, h)| (h.part != Part::Training, h.shard.count, h.shard.index));
    let split = usize::from(
        headers
            .first()
            .is_some_and(|(_, h)| h.part == Part::Training),
    );
    check_disjoint(&headers[split..])?;

    let pixels = first.pixels() as usize;
    let mut layers = vec![LayerSums::zero(pixels); first.layers()];
    for (path, header) in &headers {
        let (read, sums) = file::read(path)?;
        if read.shard != header.shard || read.identity != first.identity {
            return Err(ShardError::Inconsistent {
                path: path.clone(),
                message: "the file changed while it was merged".into(),
            });
        }
        for (total, layer) in layers.iter_mut().zip(&sums) {
            add(total, layer, path)?;
        }
    }
    let training_spp = first.identity.plan.as_ref().map_or(0, |p| p.training_spp);
    let coverage = if training_spp > 0 && !headers.iter().any(|(_, h)| h.part.has_training()) {
        Coverage::NoTraining {
            training: training_spp,
            spp: layers.iter().map(LayerSums::fewest).min().unwrap_or(0),
            of: first.identity.spp,
        }
    } else {
        coverage(&headers[split..], &layers, first.identity.spp)
    };
    let training = headers[..split].first().map(|(p, _)| p.clone());
    Ok(Merged {
        header: first,
        training,
        shards: headers
            .into_iter()
            .skip(split)
            .map(|(p, h)| (p, h.shard))
            .collect(),
        layers,
        coverage,
    })
}

/// Refuses two files that both hold the learn job's training samples, and training samples
/// in a render that used no plan file.
fn check_training(headers: &[(PathBuf, Header)], first: &Header) -> Result<(), ShardError> {
    let mut holders = headers.iter().filter(|(_, h)| h.part.has_training());
    if let Some((a, _)) = holders.next() {
        if let Some((b, _)) = holders.next() {
            return Err(ShardError::TwoTrainings {
                a: a.clone(),
                b: b.clone(),
            });
        }
        if first.identity.plan.is_none() {
            return Err(ShardError::Inconsistent {
                path: a.clone(),
                message: "it holds training samples of a render that used no plan file".into(),
            });
        }
    }
    Ok(())
}

/// Refuses two shards that hold a common sample: `s mod N = K` and `s mod M = L` share
/// samples exactly when `K ≡ L (mod gcd(N, M))`.
fn check_disjoint(headers: &[(PathBuf, Header)]) -> Result<(), ShardError> {
    for (i, (a, ha)) in headers.iter().enumerate() {
        for (b, hb) in &headers[i + 1..] {
            let (x, y) = (ha.shard, hb.shard);
            if x == y {
                return Err(ShardError::Duplicate {
                    a: a.clone(),
                    b: b.clone(),
                    shard: x,
                });
            }
            let g = gcd(x.count, y.count);
            if x.index % g == y.index % g {
                let modulus = u64::from(x.count) / u64::from(g) * u64::from(y.count);
                // The common residue (Chinese remainder theorem), found by stepping through x's.
                let residue = (0..u64::from(y.count / g))
                    .map(|t| u64::from(x.index) + t * u64::from(x.count))
                    .find(|s| s % u64::from(y.count) == u64::from(y.index))
                    .unwrap_or(u64::from(x.index));
                return Err(ShardError::Overlap {
                    a: a.clone(),
                    b: b.clone(),
                    a_shard: x,
                    b_shard: y,
                    modulus,
                    residue,
                });
            }
        }
    }
    Ok(())
}

/// Adds `layer`'s sums to `total`'s, pixel by pixel.
fn add(total: &mut LayerSums, layer: &LayerSums, path: &Path) -> Result<(), ShardError> {
    for i in 0..total.counts.len() {
        total.counts[i] = total.counts[i]
            .checked_add(layer.counts[i])
            .ok_or_else(|| ShardError::Inconsistent {
                path: path.to_path_buf(),
                message: format!("pixel {i}'s sample count overflows"),
            })?;
        total.sum[i] += layer.sum[i];
        total.sum_sq[i] += layer.sum_sq[i];
    }
    if let Some(splats) = &layer.splats {
        let pixels = total.counts.len();
        (total.splats.get_or_insert_with(|| SplatLayer::zero(pixels))).add_layer(splats);
    }
    Ok(())
}

fn coverage(headers: &[(PathBuf, Header)], layers: &[LayerSums], spp: u32) -> Coverage {
    let Some((_, first)) = headers.first() else {
        return Coverage::Partial {
            spp: layers.iter().map(LayerSums::fewest).min().unwrap_or(0),
            of: spp,
        };
    };
    let held = layers
        .iter()
        .flat_map(|l| l.counts.iter().copied())
        .min()
        .unwrap_or(0);
    if held == spp {
        return Coverage::Complete;
    }
    let n = first.shard.count;
    let every_shard = headers.len() == n as usize;
    if !every_shard && headers.iter().all(|(_, h)| h.shard.count == n) {
        // The headers are sorted by index.
        let mut present = headers.iter().map(|(_, h)| h.shard.index).peekable();
        let absent = (0..n).filter(|&k| {
            if present.peek() == Some(&k) {
                present.next();
                false
            } else {
                true
            }
        });
        let first = absent.take(LISTED).collect();
        Coverage::Missing {
            n,
            missing: n - headers.len() as u32,
            first,
        }
    } else {
        Coverage::Partial { spp: held, of: spp }
    }
}

fn gcd(a: u32, b: u32) -> u32 {
    if b == 0 {
        a
    } else {
        gcd(b, a % b)
    }
}
