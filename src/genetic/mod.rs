//! The genetic algorithm of the paper (§4–5; docs/methods/ga.md): per pixel, a population of
//! individuals — weighted sets of path generators — evolves towards the set whose mixture
//! density (eq. 7) gives the estimator of eq. 8 the smallest variance, measured by eq. 10
//! on a fixed set of test paths.
//!
//! * [`test_paths`]: the `M` test paths of one pixel, sampled once from a defensive density.
//! * [`fitness`]: eq. 10–11, with every generator's densities cached on the test paths.
//! * [`individual`]: individuals and their random initialisation.
//! * [`operators`]: crossover and mutations (paper §5.5).
//! * [`population`]: selection, elitism and the generation loop.
//! * [`explain`]: an image of what was learned (`--explain`).
//! * [`plan`]: which pixels run the GA, and the mixture every pixel renders with.

pub mod explain;
pub mod fitness;
pub mod individual;
pub mod nearest;
pub mod operators;
pub mod plan;
pub mod population;
pub mod test_paths;

use glam::DVec3;

crate::settings_table! {
    /// Every parameter of the genetic algorithm, table `[ga]`: its settings declared once,
    /// with their defaults, ranges and help ([`crate::settings_table`]). The defaults are
    /// chosen for error at equal time, every phase counted, and the mutation rates for about
    /// one change per offspring (the measurements are in reports/README.md).
    #[derive(Clone, Debug, PartialEq)]
    pub struct GaConfig {
        table: "ga",
        heading: "Genetic algorithm (--method ga, ga-pt)",
        settings: {
            /// Individuals per generation (the paper: 150).
            #[range = 1..=100_000]
            pub population: usize = 30,
            /// Generations, the random first one included (the paper: 200).
            #[range = 1..=100_000]
            pub generations: usize = 20,
            /// Evolved generators per individual (S), besides the defensive srt one.
            #[key = "ga_generators"]
            #[value_name = "S"]
            #[range = 1..=64]
            pub generators: usize = 4,
            /// Test paths per GA pixel (M of eq. 10), zero-contribution paths included.
            #[value_name = "M"]
            #[range = 1..=100_000_000]
            pub test_paths: usize = 10_000,
            /// Best individuals copied unchanged into the next generation (E); at most the
            /// population.
            #[value_name = "E"]
            #[range = 0..=100_000]
            pub elitism: usize = 2,
            /// Crossover probability per pair of parents (they exchange their first R ≥ 1
            /// generators).
            #[range = 0.0..=1.0]
            pub p_cross: f64 = 0.7,
            /// Mutation probability per sampler (directional or light point).
            #[key = "p_mutate"]
            #[range = 0.0..=1.0]
            pub p_sampler_mutate: f64 = 0.1,
            /// Probability per individual that two generators switch positions.
            #[range = 0.0..=1.0]
            pub p_switch: f64 = 0.1,
            /// Probability per individual of a weight mutation.
            #[range = 0.0..=1.0]
            pub p_weight: f64 = 0.3,
            /// Probability per generator of an absorption mutation.
            #[range = 0.0..=1.0]
            pub p_absorb: f64 = 0.1,
            /// Smallest weight of the defensive srt component of every evolved mixture.
            #[range = crate::path::mixture_file::W_MIN..1.0]
            pub defensive_weight: f64 = 0.05,
            /// Standard deviation of an anchor shift along its triangle, relative to the
            /// scene's size.
            #[range = 0.0..]
            pub anchor_shift: f64 = 0.05,
            /// After evolution, set each GA pixel's mixture weights to the optimum of eq. 10
            /// for its evolved generators (convex optimisation, beyond the paper).
            pub convex_weights: bool = true,
            /// Share of random anchor points drawn where light-carrying test paths went (0:
            /// the paper's, uniform by area on all surfaces).
            #[range = 0.0..=1.0]
            pub data_anchors: f64 = 0.5,
            /// Share of data-driven directional samplers that are patches (parallelograms
            /// where the light-carrying test paths' directions arrived on one plane) rather
            /// than cones (0: the paper's cones only).
            #[range = 0.0..=1.0]
            pub patches: f64 = 0.5,
            // One set for both lets the GA shrink the terms of the few paths that dominate
            // eq. 10 and keep mixtures whose `V` on the test paths is far below their
            // variance; for `ga-pt` a second set costs as much as the first for no better
            // image (reports/README.md).
            /// Place the data-driven anchors and patches from a second, independent set of
            /// test paths, so that the set eq. 10 is measured on never placed them (`false`:
            /// one set for both, which lets the GA fit its samplers to the few paths that
            /// dominate eq. 10). Default: on for ga, off for ga-pt (whose end-only test paths
            /// seldom carry light, so that a second set costs as much as the first)
            pub held_out: Option<bool> = None,
            // The GA's cost grows with the light-carrying paths, its information much less.
            /// Stop sampling a pixel's test paths once this many carry light.
            #[value_name = "L"]
            #[range = 1..=100_000_000]
            pub max_light_paths: usize = 1_000,
        },
        internal: {
            /// Absorption of the defensive `srt` generator (Russian roulette at its vertices).
            pub srt_absorption: crate::path::generator::SrtAbsorption =
                crate::path::generator::Nee::default().default_srt_absorption(),
            /// The estimator whose test paths, fitness and mixtures the GA works with
            /// (`srt.nee`).
            pub nee: crate::path::generator::Nee = crate::path::generator::Nee::default(),
            /// Steps per evolved generator; `None`: one per vertex that can scatter before
            /// `max_bounces`. The pixel plan sets it to the depth the test paths need
            /// (pruning).
            pub max_steps: Option<usize> = None,
            /// Evolve directional samplers only: every generator keeps `srt`'s absorption and
            /// light sampler, so that `V` measures exactly what a guide for path tracing takes
            /// from the mixture (`ga-pt` sets it).
            pub directions_only: bool = false,
        },
    }
}

/// An invalid [`GaConfig`].
#[derive(Debug, thiserror::Error)]
#[error("invalid genetic-algorithm setting: {0}")]
pub struct GaConfigError(String);

impl GaConfig {
    /// Checks the ranges that [`population::evolve`] relies on: each setting's declared
    /// range, and what ties settings together or the code sets.
    pub fn validate(&self) -> Result<(), GaConfigError> {
        let fail = |m: String| Err(GaConfigError(m));
        if let Err(e) = crate::settings_table::Table::check(self) {
            return fail(e.to_string());
        }
        if self.elitism > self.population {
            return fail(format!(
                "elitism {} exceeds the population {}",
                self.elitism, self.population
            ));
        }
        let (lo, hi) = (
            crate::path::generator::ABSORPTION_MIN,
            crate::path::generator::ABSORPTION_MAX,
        );
        if !(lo..=hi).contains(&self.srt_absorption.per_vertex) {
            return fail(format!(
                "srt_absorption {} is not in [{lo}, {hi}]",
                self.srt_absorption.per_vertex
            ));
        }
        if self.max_steps == Some(0) {
            return fail("max_steps must be at least 1".into());
        }
        Ok(())
    }
}

/// How the genetic algorithm and the gate measure the variance of a pixel's estimator:
/// `Σ_c w_c Var[v_c]` over the RGB channels of its samples `v`.
///
/// The weights are [`ChannelWeights::relative`] to the pixel's value `I`, so that this is,
/// up to a constant factor, the pixel's share of the relMSE that `genpath compare` reports,
/// `mean_c (x_c − ref_c)² / (ref_c² + 0.01)`. The luminance the paper's fitness could take
/// instead weights blue by 0.07: the mixture then neglects mostly blue light, and the
/// image's blue channel stays noisier than its red one (reports/README.md, "Measurements
/// formerly in code comments (2026-12-07)").
///
/// Eq. 10's second moment becomes `Σ_c w_c E[(f_c/p)²] = E[F²/p²]` with
/// `F² = Σ_c w_c f_c²`, still convex in the mixture weights.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChannelWeights(DVec3);

impl ChannelWeights {
    /// Equal weights, summing to 1.
    pub const EQUAL: Self = Self(DVec3::splat(1.0 / 3.0));

    /// `w_c ∝ 1 / (I_c² + 0.01)` for the pixel value `I` (negative or non-finite channels
    /// count as 0), normalised to sum 1.
    pub fn relative(value: DVec3) -> Self {
        let i = DVec3::select(value.cmpgt(DVec3::ZERO), value, DVec3::ZERO);
        let i = DVec3::select(i.is_finite_mask(), i, DVec3::ZERO);
        let w = (i * i + 0.01).recip();
        Self(w / w.element_sum())
    }

    /// `Σ_c w_c s_c` for per-channel squares (or variances) `s`.
    pub fn weigh(&self, s: DVec3) -> f64 {
        self.0.dot(s)
    }
}

/// Luminance of linear Rec. 709 RGB: what the baseline measures relative variance of.
pub fn luminance(c: DVec3) -> f64 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}
