//! A plan's GA pixels evolved outside one process: the waves (`Waves`:
//! the pilot's scouting, the pilot going on, the cold first wave, the warm-started second)
//! kept in a [`LearnStore`] as they finish (and, beyond the GA, the spatial guide's training
//! after each pass: `integrators::pg`), so that learning stopped by a signal goes on
//! where it stopped, and so that the GA splits over jobs (`genpath learn --shard K/N`):
//! each job evolves its share of the first wave not yet complete, the waves being barriers
//! between the steps of a job array, and a last job builds the plan from every share.
//!
//! Every GA pixel's result depends on the seed, its position and how it starts (its
//! neighbours' best individuals, which come from earlier waves) alone, so a wave's results
//! are the same whichever job evolved them, and a plan built from stored waves equals the
//! plan built in one process (docs/shards.md).

use super::super::individual::Individual;
use super::types::GaPixel;
use crate::genetic::GaConfigError;
use crate::path::RayCounts;

/// One GA pixel's result in a wave: what the plan keeps of it, and the best individual
/// that warm-starts its neighbours (which the plan itself does not keep).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct WaveEntry {
    /// The job's index in its wave.
    pub job: u32,
    pub pixel: GaPixel,
    pub best: Option<Individual>,
    pub counts: RayCounts,
}

/// Where learning keeps what it finished between processes (`genpath learn`): the waves of
/// a plan's GA pixels, and the spatial guide's training after its last finished pass.
pub trait LearnStore: Send + Sync + std::fmt::Debug {
    /// Every result of wave `wave` saved so far, by this job or any other.
    fn load(&self, wave: usize) -> Result<Vec<WaveEntry>, StoreError>;
    /// Keeps `entries`, new results of wave `wave` (of `jobs` jobs) this job evolved.
    fn save(&self, wave: usize, jobs: usize, entries: &[WaveEntry]) -> Result<(), StoreError>;
    /// Whether this job evolves job `job` of a wave (every job, unless the GA is split).
    fn mine(&self, job: usize) -> bool;
    /// Whether the GA is split over jobs: this one stops once its share of a wave is done.
    fn split(&self) -> bool;
    /// The signal that asked the learning to stop, if one did.
    fn stop_requested(&self) -> Option<usize>;
    /// The spatial guide's training as [`Self::save_training`] last kept it, if it did.
    fn load_training(&self) -> Result<Option<Vec<u8>>, StoreError>;
    /// Keeps the spatial guide's training after a finished pass (`pass`, counted from 1),
    /// encoded as `state`.
    fn save_training(&self, pass: u32, state: &[u8]) -> Result<(), StoreError>;
}

/// Why a [`LearnStore`] could not keep or give back what learning finished: its files,
/// named in the message.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct StoreError(pub String);

impl From<String> for StoreError {
    fn from(message: String) -> Self {
        Self(message)
    }
}

/// Why a plan is not built.
#[derive(Debug, thiserror::Error)]
pub enum PlanError {
    #[error(transparent)]
    Config(#[from] GaConfigError),
    /// A signal stopped the learning; the GA pixels evolved so far are in the store.
    #[error(
        "stopped by signal {signal} in wave {wave} of the GA, with {done} of its {jobs} GA \
         pixels evolved and kept: run the same command to go on"
    )]
    Stopped {
        signal: usize,
        wave: usize,
        done: usize,
        jobs: usize,
    },
    /// A job of a split GA did its share of `wave` (`None`: every wave was complete); the
    /// rest of the wave is other jobs'.
    #[error("{}", share_done(*.wave, *.evolved, *.missing))]
    ShareDone {
        wave: Option<usize>,
        evolved: usize,
        missing: usize,
    },
    #[error("the GA's waves: {0}")]
    Store(StoreError),
}

fn share_done(wave: Option<usize>, evolved: usize, missing: usize) -> String {
    match wave {
        Some(w) => format!(
            "this job's share of wave {w} of the GA is done ({evolved} GA pixels evolved \
             now); {missing} of its GA pixels are other jobs'"
        ),
        None => "every wave of the GA is complete: learn without --shard builds the plan \
                 from them"
            .to_string(),
    }
}
