//! How a render may be stopped, saved while it runs and resumed.

use super::LayerSums;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::Duration;

/// A request to stop a render early, shared with whoever makes it (a signal handler): `0`
/// while the render should go on, else the number of the signal that stopped it. Each
/// pixel checks it before each sample, so a render stops within one sample per thread and
/// keeps every sample it took.
#[derive(Clone, Debug, Default)]
pub struct Stop(Option<Arc<AtomicUsize>>);

impl Stop {
    /// A stop requested by storing a non-zero value (a signal number) in `flag`.
    pub fn on(flag: Arc<AtomicUsize>) -> Self {
        Self(Some(flag))
    }

    /// The signal number that requested the stop, if one did.
    pub fn requested(&self) -> Option<usize> {
        self.0
            .as_ref()
            .map(|f| f.load(Ordering::Relaxed))
            .filter(|&s| s != 0)
    }
}

/// Periodic snapshots of a render's sums while it runs (`render --checkpoint SECONDS`):
/// after each tile, when `every` has passed since the last, `write` is given every pixel's
/// sums so far (the finished tiles', and for the others what the render started from).
#[derive(Clone)]
pub struct Checkpoint {
    pub every: Duration,
    pub write: Arc<dyn Fn(&LayerSums) + Send + Sync>,
}

impl std::fmt::Debug for Checkpoint {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Checkpoint(every {:?})", self.every)
    }
}

/// How a render may be stopped, continued and saved while it runs; by default it starts
/// from nothing and runs to the end.
#[derive(Clone, Debug, Default)]
pub struct Control {
    pub stop: Stop,
    /// Sums of this render (this shard of it) taken before, in a shard file it wrote when
    /// it was stopped or at a checkpoint: pixel `p` holds the first `counts[p]` of its
    /// samples, and the render takes the rest onto those sums (`render --resume FILE`).
    pub resume: Option<Arc<LayerSums>>,
    pub checkpoint: Option<Checkpoint>,
}
