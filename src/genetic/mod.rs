//! The genetic algorithm of the paper (§4–5, design §6): per pixel, a population of
//! individuals — weighted sets of path generators — evolves towards the set whose mixture
//! density (eq. 7) gives the estimator of eq. 8 the smallest variance, measured by eq. 10 on
//! a fixed set of test paths.
//!
//! * [`test_paths`]: the `M` test paths of one pixel, sampled once from a defensive density.
//! * [`fitness`]: eq. 10–11, with every generator's densities cached on the test paths.
//! * [`individual`]: individuals and their random initialisation.
//! * [`operators`]: crossover and mutations (paper §5.5).
//! * [`population`]: selection, elitism and the generation loop.

pub mod fitness;
pub mod individual;
pub mod operators;
pub mod population;
pub mod test_paths;

use glam::DVec3;

/// Every parameter of the genetic algorithm; defaults in [`GaConfig::default`] only.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GaConfig {
    /// Individuals per generation (the paper used 150).
    pub population: usize,
    /// Generations, the random first one included (the paper used 200).
    pub generations: usize,
    /// Evolved generators per individual (`S`), besides the defensive `srt` component.
    pub generators: usize,
    /// Test paths per pixel (`M` of eq. 10), zero-contribution paths included.
    pub test_paths: usize,
    /// Best individuals copied unchanged into the next generation (`E`).
    pub elitism: usize,
    /// Probability that two parents exchange their first `R ≥ 1` generators.
    pub p_cross: f64,
    /// Probability, per sampler (directional or light point), of a mutation.
    pub p_sampler_mutate: f64,
    /// Probability, per individual, that two generators switch positions.
    pub p_switch: f64,
    /// Probability, per individual, that the component weights change.
    pub p_weight: f64,
    /// Probability, per generator, that one of its absorptions changes.
    pub p_absorb: f64,
    /// Smallest weight of the defensive `srt` component (at least `mixture_file::W_MIN`).
    pub defensive_weight: f64,
    /// Absorption of the defensive `srt` generator (Russian roulette at every vertex).
    pub srt_absorption: f64,
    /// Standard deviation of an anchor shift along its triangle, relative to the scene size.
    pub anchor_shift: f64,
}

impl Default for GaConfig {
    /// Smaller than the paper's 150 × 200: eq. 10 on a fixed set of test paths converges
    /// within a few tens of generations on the paper's scene (tests/genetic.rs), and the
    /// run time is per GA pixel. Mutation rates follow the usual "about one change per
    /// offspring" rule: an individual of S = 4 generators with 4 steps each holds ~20 samplers.
    fn default() -> Self {
        Self {
            population: 40,
            generations: 30,
            generators: 4,
            test_paths: 2000,
            elitism: 2,
            p_cross: 0.7,
            p_sampler_mutate: 0.05,
            p_switch: 0.1,
            p_weight: 0.3,
            p_absorb: 0.1,
            defensive_weight: 0.05,
            srt_absorption: 0.5,
            anchor_shift: 0.05,
        }
    }
}

/// Luminance of linear Rec. 709 RGB: the scalar the fitness measures variance of.
pub fn luminance(c: DVec3) -> f64 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}
