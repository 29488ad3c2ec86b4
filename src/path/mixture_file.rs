//! Mixtures of path generators described in a file (`--method mixture --generators FILE`),
//! TOML or JSON by extension, so hand-made generators can be rendered before any GA runs.
//!
//! ```toml
//! srt_weight = 0.2          # weight of the defensive srt component (≥ W_MIN)
//! [[generators]]
//! weight = 0.4              # relative weights of the other components
//! light = { region = { prim = 8, level = 0, cell = 0 }, beta = 0.5 }
//! steps = [
//!   { absorption = 0.2, sampler = { type = "brdf" } },
//!   { absorption = 0.9, sampler = { type = "anchor", anchor = [-1.0, 1.9, 0.0], theta_c = 0.3, alpha = 0.8 } },
//! ]
//! ```

use super::generator::{
    DirectionSampler, PathGenerator, SrtAbsorption, Step, ABSORPTION_MAX, ABSORPTION_MIN,
};
use super::mixture::Mixture;
use crate::sampling::anchor::{AnchorError, AnchorSampler};
use crate::sampling::light_point::{LightPointError, LightPointSampler};
use crate::sampling::patch::{PatchError, PatchSampler};
use crate::scene::Scene;
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// Smallest weight of the defensive `srt` component.
pub const W_MIN: f64 = 0.01;

#[derive(Debug, thiserror::Error)]
#[error("{path}: {message}")]
pub struct MixtureFileError {
    pub path: PathBuf,
    pub message: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MixtureFile {
    #[serde(default = "default_srt_weight")]
    srt_weight: f64,
    generators: Vec<GeneratorFile>,
}

fn default_srt_weight() -> f64 {
    0.1
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct GeneratorFile {
    weight: f64,
    steps: Vec<Step>,
    /// Defaults to uniform light sampling by area.
    light: Option<LightPointSampler>,
}

/// Uniform light sampling by area (a light-point sampler with β = 0; in a scene lit only by
/// its environment, one that is never sampled).
pub fn uniform_light(scene: &Scene) -> LightPointSampler {
    LightPointSampler::uniform(scene.emitters.prims.first().copied().unwrap_or(0))
}

/// The `srt` method as a mixture: the one `srt` generator with uniform light sampling.
pub fn srt(scene: &Scene, max_bounces: u32, absorption: impl Into<SrtAbsorption>) -> Mixture {
    Mixture::new(
        vec![PathGenerator::srt(
            max_bounces,
            absorption,
            uniform_light(scene),
        )],
        vec![1.0],
    )
}

/// Which invariant of the estimator a generator breaks.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum GeneratorError {
    #[error("step {step}: absorption {absorption} is not in [{ABSORPTION_MIN}, {ABSORPTION_MAX}]")]
    Absorption { step: usize, absorption: f64 },
    #[error("step {step}: {source}")]
    Anchor { step: usize, source: AnchorError },
    #[error("step {step}: {source}")]
    Patch { step: usize, source: PatchError },
    #[error("light: the scene has no area emitter to sample light points on")]
    NoAreaEmitter,
    #[error("light: {0}")]
    Light(LightPointError),
}

/// Checks a generator against the invariants that keep the estimator unbiased and finite.
pub fn check_generator(g: &PathGenerator, scene: &Scene) -> Result<(), GeneratorError> {
    for (k, step) in g.steps.iter().enumerate() {
        let a = step.absorption;
        if !(ABSORPTION_MIN..=ABSORPTION_MAX).contains(&a) {
            return Err(GeneratorError::Absorption {
                step: k,
                absorption: a,
            });
        }
        match &step.sampler {
            DirectionSampler::Brdf => {}
            DirectionSampler::Anchor(a) => {
                AnchorSampler::new(a.anchor, a.theta_c, a.alpha)
                    .map_err(|source| GeneratorError::Anchor { step: k, source })?;
            }
            DirectionSampler::Patch(p) => {
                PatchSampler::new(p.center, p.half_u, p.half_v, p.alpha)
                    .map_err(|source| GeneratorError::Patch { step: k, source })?;
            }
        }
    }
    if scene.emitters.prims.is_empty() {
        // Lit by its environment alone: no light point is ever sampled.
        if g.light != uniform_light(scene) {
            return Err(GeneratorError::NoAreaEmitter);
        }
        return Ok(());
    }
    LightPointSampler::new(g.light.region, g.light.beta, &scene.emitters)
        .map_err(GeneratorError::Light)?;
    if g.light.region.is_invalid_on(&scene.mesh) {
        return Err(GeneratorError::Light(LightPointError::AnalyticLevel(
            g.light.region.prim,
        )));
    }
    Ok(())
}

/// Reads a mixture file; the defensive `srt` generator (absorption `srt_absorption`) is
/// added as component 0.
pub fn load(
    path: &Path,
    scene: &Scene,
    max_bounces: u32,
    srt_absorption: impl Into<SrtAbsorption>,
) -> Result<Mixture, MixtureFileError> {
    let error = |message: String| MixtureFileError {
        path: path.to_path_buf(),
        message,
    };
    let text = std::fs::read_to_string(path).map_err(|e| error(format!("cannot read: {e}")))?;
    let file: MixtureFile = match path.extension().and_then(|e| e.to_str()) {
        Some("json") => serde_json::from_str(&text).map_err(|e| error(e.to_string()))?,
        Some("toml") => {
            toml::from_str(&text).map_err(|e| error(e.to_string().trim_end().to_string()))?
        }
        _ => {
            return Err(error(
                "the generators file must end in .toml or .json".into(),
            ))
        }
    };
    if !(file.srt_weight.is_finite() && (W_MIN..=1.0).contains(&file.srt_weight)) {
        return Err(error(format!(
            "srt_weight {} is not in [{W_MIN}, 1]",
            file.srt_weight
        )));
    }
    let uniform_light = uniform_light(scene);
    let mut generators = vec![PathGenerator::srt(
        max_bounces,
        srt_absorption,
        uniform_light,
    )];
    let mut weights = vec![file.srt_weight];
    let total: f64 = file.generators.iter().map(|g| g.weight).sum();
    for (i, g) in file.generators.into_iter().enumerate() {
        if !(g.weight.is_finite() && g.weight > 0.0) {
            return Err(error(format!(
                "generators[{i}]: weight {} must be positive",
                g.weight
            )));
        }
        let generator = PathGenerator {
            steps: g.steps,
            light: g.light.unwrap_or(uniform_light),
        };
        check_generator(&generator, scene).map_err(|e| error(format!("generators[{i}]: {e}")))?;
        generators.push(generator);
        weights.push((1.0 - file.srt_weight) * g.weight / total);
    }
    Ok(Mixture::new(generators, weights))
}
