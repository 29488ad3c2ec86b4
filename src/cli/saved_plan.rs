//! A plan file read for a render (`render --plan FILE`) or a reference (`reference --plan
//! FILE`), and the training samples a render that learned starts from: the renders' side of
//! `genpath learn`.

use anyhow::{bail, Context, Result};
use genpath::film::{LayerSums, Shard};
use genpath::integrators::Learned;
use genpath::shard::plan_file;
use genpath::shard::{Identity, PlanRef};
use std::path::{Path, PathBuf};

/// The per-pixel sums of the samples `learned`'s training took (an image of `pixels` pixels;
/// zero where it took none): what the image of a render that learned starts from.
pub fn training_layer(learned: &Learned, pixels: usize) -> LayerSums {
    match learned.samples() {
        Some(samples) => LayerSums::from(samples),
        None => LayerSums::zero(pixels),
    }
}

/// A plan file read for a render (`render --plan FILE`) or a reference (`reference --plan
/// FILE`).
pub struct SavedPlan {
    pub path: PathBuf,
    pub hash: String,
    pub training_spp: u32,
    pub summary: serde_json::Value,
    /// A render's learned state, or a reference's two halves' in order; taken when the
    /// render prepares its method.
    pub learned: Vec<Learned>,
}

impl SavedPlan {
    /// What the render's shards record of it.
    pub fn reference(&self) -> PlanRef {
        PlanRef {
            hash: self.hash.clone(),
            training_spp: self.training_spp,
        }
    }

    /// What the render's JSON records of it.
    pub fn json(&self) -> serde_json::Value {
        serde_json::json!({
            "file": self.path,
            "hash": self.hash,
            "training_spp": self.training_spp,
            "summary": self.summary,
            "note": "the plan's and the spatial guide's times are the learn job's",
        })
    }
}

/// Reads the plan file at `path` for a render (or reference) with `identity` (without a
/// plan), shard `shard`: refuses a file that is damaged, or learned for another render
/// (naming the first field that differs: a reference's plan for a render, another seed…),
/// or a split into more shards than there are samples (per half) after the training's.
pub fn read_plan(path: &Path, identity: &Identity, shard: Shard) -> Result<SavedPlan> {
    let file = plan_file::read(path).with_context(|| format!("--plan {}", path.display()))?;
    if let Some((what, theirs, ours)) = file.header.identity.difference(identity) {
        let learn = match identity.command.as_str() {
            "reference" => "learn --for-reference",
            _ => "learn",
        };
        bail!(
            "--plan {}: it was learned for another render: {what} is {theirs} there and {ours} \
             here ({learn} with the same build, scene, size, seed, --spp and settings)",
            path.display()
        );
    }
    let training_spp = file.header.training_spp;
    let learned_spp = file.learned.iter().map(Learned::training_spp).max();
    if file.learned.len() != identity.layer_seeds.len() || Some(training_spp) != learned_spp {
        bail!(
            "--plan {}: inconsistent: its header says {training_spp} training samples per \
             pixel of {} layers, its learned states {learned_spp:?} of {}",
            path.display(),
            identity.layer_seeds.len(),
            file.learned.len()
        );
    }
    let after = identity.spp.saturating_sub(training_spp);
    if !shard.is_whole() && shard.count > after {
        bail!(
            "--shard {shard}: {} shards of the {after} samples per pixel left after the plan's \
             {training_spp} training samples leave some shards without a sample",
            shard.count
        );
    }
    Ok(SavedPlan {
        path: path.to_path_buf(),
        hash: file.hash,
        training_spp,
        summary: file.header.summary,
        learned: file.learned,
    })
}
