//! What every GA pixel of a plan shares ([`PixelContext`]), and how the GA starts at one
//! ([`GaRun`]).

use super::super::individual::Individual;
use super::super::GaConfig;
use super::config::PlanConfig;
use super::stages::LearnStore;
use super::types::PlanFor;
use crate::path::mixture::Mixture;
use crate::path::SceneView;

/// What every GA pixel of a plan shares: the scene, the defensive `srt` mixture, the
/// settings, the estimator the plan is for and the user's seed, from which each pixel's
/// random streams are derived.
pub(super) struct PixelContext<'a> {
    pub(super) view: &'a SceneView<'a>,
    pub(super) srt: &'a Mixture,
    pub(super) ga: &'a GaConfig,
    pub(super) config: &'a PlanConfig,
    pub(super) max_bounces: u32,
    pub(super) plan_for: PlanFor,
    /// Whether the gate runs (`GateConfig::gate`).
    pub(super) gate: bool,
    pub(super) seed: u64,
    /// Where the waves are kept between processes, if they are.
    pub(super) store: Option<&'a dyn LearnStore>,
}

/// How the GA starts at a pixel, and whether the pixel then runs the gate's trial.
#[derive(Debug)]
pub(super) struct GaRun {
    /// The first generation's evolved individuals (none: a cold start).
    pub(super) seeds: Vec<Individual>,
    pub(super) generations: usize,
    /// The pixel's GA random stream (a pilot pixel that goes on takes a fresh one: its
    /// scouting run's would replay the same random individuals and breeding).
    pub(super) stream: u64,
    /// Whether the pixel runs the gate's trial (with the gate, where the GA did not keep
    /// `srt`).
    pub(super) trial: bool,
}
