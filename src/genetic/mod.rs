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

/// Every parameter of the genetic algorithm; defaults in [`GaConfig::default`] only.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GaConfig {
    /// Individuals per generation (the paper used 150).
    pub population: usize,
    /// Generations, the random first one included (the paper used 200).
    pub generations: usize,
    /// Evolved generators per individual (`S`), besides the defensive `srt` component.
    #[serde(rename = "ga_generators")]
    pub generators: usize,
    /// Test paths per pixel (`M` of eq. 10), zero-contribution paths included.
    pub test_paths: usize,
    /// Best individuals copied unchanged into the next generation (`E`).
    pub elitism: usize,
    /// Probability that two parents exchange their first `R ≥ 1` generators.
    pub p_cross: f64,
    /// Probability, per sampler (directional or light point), of a mutation.
    #[serde(rename = "p_mutate")]
    pub p_sampler_mutate: f64,
    /// Probability, per individual, that two generators switch positions.
    pub p_switch: f64,
    /// Probability, per individual, that the component weights change.
    pub p_weight: f64,
    /// Probability, per generator, that one of its absorptions changes.
    pub p_absorb: f64,
    /// Smallest weight of the defensive `srt` component (at least `mixture_file::W_MIN`).
    pub defensive_weight: f64,
    /// Absorption of the defensive `srt` generator (Russian roulette at its vertices).
    #[serde(skip)]
    pub srt_absorption: crate::path::generator::SrtAbsorption,
    /// The estimator whose test paths, fitness and mixtures the GA works with (`srt.nee`).
    #[serde(skip)]
    pub nee: crate::path::generator::Nee,
    /// Standard deviation of an anchor shift along its triangle, relative to the scene size.
    pub anchor_shift: f64,
    /// Steps per evolved generator; `None`: one per vertex that can scatter before
    /// `max_bounces`. The pixel plan sets it to the depth the test paths need (pruning).
    #[serde(skip)]
    pub max_steps: Option<usize>,
    /// After evolution, replace the best individual's weights by the ones that minimise
    /// eq. 10 for its generators ([`fitness::optimise_weights`], beyond the paper).
    pub convex_weights: bool,
    /// Test-path sampling stops once this many carry light (fewer than `test_paths` are
    /// then sampled): the GA's cost grows with them, its information much less.
    pub max_light_paths: usize,
    /// Share of random anchor points drawn where light-carrying test paths went (beyond
    /// the paper, which draws them uniformly by area on all surfaces: 0).
    pub data_anchors: f64,
    /// Share of data-driven directional samplers that are patches ([`PatchSampler`]: the
    /// region where light-carrying test paths' directions arrived on one plane) rather than
    /// cones (beyond the paper, whose samplers are cones: 0).
    ///
    /// [`PatchSampler`]: crate::sampling::patch::PatchSampler
    pub patches: f64,
    /// Place the data-driven anchors and patches from a second, independent set of test
    /// paths, and measure every `V` on the first (beyond the paper). With one set for both,
    /// a sampler placed at the few paths that dominate eq. 10 shrinks their terms, and the
    /// GA keeps mixtures whose `V` on the test paths is far below their variance (glossy,
    /// `ga --no-gate`, 64 spp: `V` 7 × below `srt`'s, the render no better than `srt`).
    /// `None`: on for `ga` (its test paths do next-event estimation at every vertex, most
    /// carry light, and the second set costs a few hundred paths), off for `ga-pt` (its
    /// end-only test paths seldom carry light: on fig5 the second set doubled the plan's
    /// CPU time for no better image at 64 spp, and a smaller one made it worse).
    pub held_out: Option<bool>,
    /// Evolve directional samplers only: every generator keeps `srt`'s absorption and light
    /// sampler, so that `V` measures exactly what a guide for path tracing takes from the
    /// mixture (`ga-pt` sets it).
    #[serde(skip)]
    pub directions_only: bool,
}

impl Default for GaConfig {
    /// Chosen for error at equal time, every phase counted (reports/README.md): on fig5,
    /// 256², `ga-pt` at 64 spp, 30 × 20 with M = 10 000 on a 32-pixel grid plans in 0.5 s
    /// for relMSE 0.64; 60 × 50 with M = 50 000 plans in 4.3 s for 0.46, and the paper-like
    /// 60 × 50, M = 50 000, grid 16 in 14 s for 0.42 — better per sample, worse at every
    /// budget up to 60 s. On one fig5 floor pixel (tests/genetic.rs `ga_improves_on_srt`,
    /// V on 200 000 fresh srt paths; srt 16.6) 40 × 30 reached 8.0 and 60 × 50 6.6: a few
    /// tens of generations on a fixed set of test paths get most of the way. Below
    /// M ≈ 2 000 (27 light-carrying paths there) the GA over-fits. Mutation rates follow the
    /// usual "about one change per offspring": S = 4 generators of 4 steps and a light
    /// sampler hold 20 samplers.
    fn default() -> Self {
        Self {
            population: 30,
            generations: 20,
            generators: 4,
            test_paths: 10_000,
            elitism: 2,
            p_cross: 0.7,
            p_sampler_mutate: 0.1,
            p_switch: 0.1,
            p_weight: 0.3,
            p_absorb: 0.1,
            defensive_weight: 0.05,
            srt_absorption: crate::path::generator::Nee::default().default_srt_absorption(),
            nee: crate::path::generator::Nee::default(),
            anchor_shift: 0.05,
            max_steps: None,
            convex_weights: true,
            max_light_paths: 1_000,
            data_anchors: 0.5,
            patches: 0.5,
            held_out: None,
            directions_only: false,
        }
    }
}

/// An invalid [`GaConfig`].
#[derive(Debug, thiserror::Error)]
#[error("invalid genetic-algorithm setting: {0}")]
pub struct GaConfigError(String);

impl GaConfig {
    /// Checks the ranges that [`population::evolve`] relies on.
    pub fn validate(&self) -> Result<(), GaConfigError> {
        let fail = |m: String| Err(GaConfigError(m));
        if self.population == 0 || self.generations == 0 || self.generators == 0 {
            return fail("population, generations and generators must be at least 1".into());
        }
        for (name, share) in [
            ("data_anchors", self.data_anchors),
            ("patches", self.patches),
        ] {
            if !(share.is_finite() && (0.0..=1.0).contains(&share)) {
                return fail(format!("{name} {share} is not in [0, 1]"));
            }
        }
        if self.max_light_paths == 0 {
            return fail("max_light_paths must be at least 1".into());
        }
        if self.elitism > self.population {
            return fail(format!(
                "elitism {} exceeds the population {}",
                self.elitism, self.population
            ));
        }
        for (name, p) in [
            ("p_cross", self.p_cross),
            ("p_sampler_mutate", self.p_sampler_mutate),
            ("p_switch", self.p_switch),
            ("p_weight", self.p_weight),
            ("p_absorb", self.p_absorb),
        ] {
            if !(0.0..=1.0).contains(&p) {
                return fail(format!("{name} {p} is not in [0, 1]"));
            }
        }
        let w_min = crate::path::mixture_file::W_MIN;
        if !(w_min..1.0).contains(&self.defensive_weight) {
            return fail(format!(
                "defensive_weight {} is not in [{w_min}, 1)",
                self.defensive_weight
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
        if !(self.anchor_shift.is_finite() && self.anchor_shift >= 0.0) {
            return fail(format!(
                "anchor_shift {} must be finite and ≥ 0",
                self.anchor_shift
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
/// instead weights blue by 0.07: on fig5 the mixture then aims at the red wall's light,
/// and the image's blue channel keeps 1.5 times the red one's relative error.
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
