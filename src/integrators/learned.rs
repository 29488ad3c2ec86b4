//! What a method that learns learned while it was prepared ([`Learned`]): the samples its
//! training took (which the image keeps) and the method's own state, which only the method
//! reads. Saved in a plan file (`genpath learn`, the `shard` module's `plan_file`) it prepares
//! the method again without training ([`prepare_learned`], through the method's
//! [`super::MethodInfo::prepare_learned`]): the render is the one that trained in-process,
//! bit for bit, and shards of it render with one learned state.

use super::{Context, Integrator, Method, PrepareError, RenderSettings, Settings};
use crate::film::PixelSums;
use crate::path::SceneView;

/// The learned state of a prepared method.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Learned {
    /// The `--method` name of the method that learned it.
    pub method: String,
    /// The per-pixel sums of the samples its training took, which the image of a render
    /// that trained keeps.
    pub samples: Option<PixelSums>,
    /// The method's own state, encoded by [`Learned::new`] (`bincode`: every float as its
    /// bits, so that it round-trips exactly).
    pub state: Vec<u8>,
    /// What was learned, in brief, as JSON text: for the plan file's header.
    pub summary: String,
}

impl Learned {
    /// `method`'s learned `state`, beside the samples its training took and a summary.
    pub fn new<T: serde::Serialize>(
        method: Method,
        samples: Option<PixelSums>,
        state: &T,
        summary: &serde_json::Value,
    ) -> Self {
        Self {
            method: method.name(),
            samples,
            state: bincode::serialize(state).expect("a learned state serialises"),
            summary: summary.to_string(),
        }
    }

    /// The method's state, as [`Learned::new`] was given it.
    pub fn state<T: serde::de::DeserializeOwned>(&self) -> Result<T, PrepareError> {
        bincode::deserialize(&self.state).map_err(|e| PrepareError::Learned {
            method: self.method.clone(),
            what: format!("its state does not decode: {e}"),
        })
    }

    /// The per-pixel sums of the samples preparing took, which the image of a render that
    /// trained keeps, if it took any.
    pub fn samples(&self) -> Option<&PixelSums> {
        self.samples.as_ref().filter(|s| s.spp > 0)
    }

    /// Samples per pixel the training took (in the image of a render that trained).
    pub fn training_spp(&self) -> u32 {
        self.samples().map_or(0, |s| s.spp)
    }

    /// The summary as JSON.
    pub fn summary(&self) -> serde_json::Value {
        serde_json::from_str(&self.summary).unwrap_or(serde_json::Value::Null)
    }
}

/// Prepares `settings.method` with `learned` instead of training. A render of the whole
/// image (`settings.shard` whole) starts from the training's samples, as the render that
/// trained does; a shard renders only its share of the samples after them (the learn job's
/// training shard holds those). Refuses a state of another method or image size.
pub fn prepare_learned(
    view: &SceneView,
    config: &Settings,
    settings: &RenderSettings,
    learned: Learned,
) -> Result<Box<dyn Integrator>, PrepareError> {
    let method = settings.method;
    let mismatch = |what: String| PrepareError::Learned {
        method: method.name(),
        what,
    };
    if learned.method != method.name() {
        return Err(mismatch(format!("it is --method {}'s", learned.method)));
    }
    let camera = &view.scene.camera;
    let pixels = (camera.width * camera.height) as usize;
    if let Some(s) = learned.samples() {
        if s.sum.len() != pixels || s.sum_sq.len() != pixels || s.spp > settings.spp {
            return Err(mismatch(format!(
                "training sums of {} pixels and {} spp for {pixels} pixels at {} spp",
                s.sum.len(),
                s.spp,
                settings.spp
            )));
        }
    }
    let Some(prepare) = method.info().prepare_learned else {
        return Err(mismatch("the method learns nothing".into()));
    };
    super::lit(view, config, |view| {
        prepare(
            &Context {
                view,
                config,
                settings,
            },
            learned,
        )
    })
}
