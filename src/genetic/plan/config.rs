//! The plan's settings ([`PlanConfig`]): where the GA runs, how its results spread over the
//! image, and its time limit (the gate's settings are [`GateConfig`], the
//! spatial guide's `integrators::settings::SpatialConfig`).

use super::super::GaConfigError;
use super::types::PlanFor;

crate::settings_table! {
    /// The gate's settings, table `[gate]`.
    #[derive(Clone, Copy, Debug, PartialEq)]
    pub struct GateConfig {
        table: "gate",
        heading: "Gate (--method ga, ga-pt)",
        settings: {
            /// A pilot of the GA predicts whether it pays, and each pixel renders with its
            /// evolved mixture only where it is predicted to beat pt (see docs/methods/ga.md,
            /// "The gate"); `false` is the paper's method everywhere.
            #[negation = "no_gate"]
            pub gate: bool = true,
        },
    }
}

crate::settings_table! {
    /// Where the genetic algorithm runs and how its results spread over the image, table
    /// `[plan]`.
    #[derive(Clone, Debug, PartialEq)]
    pub struct PlanConfig {
        table: "plan",
        heading: "GA plan (--method ga, ga-pt)",
        settings: {
            /// Distance between GA pixels on the grid, in pixels. Default: 32 for ga, 64 for
            /// ga-pt
            #[key = "ga_grid"]
            #[value_name = "PIXELS"]
            #[range = 1..=i64::from(crate::scene::MAX_IMAGE_SIDE)]
            pub grid: Option<u32> = None,
            /// Extra GA pixels where the baseline variance is high, as a fraction of the
            /// grid's.
            #[key = "ga_extra"]
            #[range = 0.0..=16.0]
            pub extra: f64 = 0.25,
            /// srt samples per pixel of the baseline pass that places the extra GA pixels.
            #[range = 1..=65_536]
            pub baseline_spp: u32 = 4,
            /// ga: the image keeps the baseline's samples (they count among --spp, which must
            /// hold them) where the GA pixels' test paths show srt's variance at most this
            /// many times the evolved mixtures' (median); 0: never, inf: always.
            #[range = 0.0..=f64::INFINITY]
            pub baseline_keep_ratio: f64 = super::BASELINE_KEEP_RATIO,
            // The union of `k` mixtures costs `ga` every component's densities on every
            // path it samples, while `ga-pt` blends only the guides' first steps; hence the
            // defaults (reports/README.md, "The settings' defaults: the measurements behind
            // them", `ga_neighbours`).
            /// Nearest GA pixels whose mixtures each pixel combines (and whose best
            /// individuals start a warm-started GA pixel's population). Default: 2 for ga, 4
            /// for ga-pt
            #[key = "ga_neighbours"]
            #[value_name = "K"]
            #[range = 1..=64]
            pub neighbours: Option<usize> = None,
            /// Grid cells whose pooled baseline relative variance (of one srt sample,
            /// Var/(mean² + 0.01)) is below this get no GA pixel.
            #[range = 0.0..]
            pub prune_variance: f64 = 0.5,
            /// Leave out of the GA the grid cells of low baseline variance and the generator
            /// steps past the depth the test paths need, and out of `ga`'s evolved mixtures
            /// the components that lower the variance on the test paths by less than their
            /// densities cost; `false` runs it everywhere with every step and component
            /// (ga-pt: still at most --guide-steps).
            #[negation = "no_prune"]
            pub prune: bool = true,
            /// Evolve half the GA pixels (a checkerboard of grid cells) first and the others
            /// from their evolved neighbours' best individuals, with half the generations.
            pub warm_start: bool = true,
            /// Seconds the GA plan may take (baseline included); GA pixels not evolved by
            /// then are left out. The plan then depends on timing, not only on the seed.
            #[key = "ga_time_limit"]
            #[value_name = "SECONDS"]
            #[range = 0.0..]
            pub time_limit: Option<f64> = None,
            // One step leaves the GA a search space it explores in its generations, and
            // path tracing's next-event estimation already finds the light from the
            // vertices after the first (reports/README.md, "The settings' defaults: the
            // measurements behind them", `guide_steps`).
            /// ga-pt: vertices the evolved guide steers (the GA evolves that many directional
            /// steps, at most as many as the test paths need); path tracing's own sampling
            /// beyond.
            #[range = 1..=64]
            pub guide_steps: usize = 1,
            // ga-pt's default is 0: the footprint let its guides through the pilot where they
            // lose (docs/methods/ga.md, "Footprint").
            /// A GA pixel's test paths start in the square of this many grid spacings
            /// (--ga-grid) centred on it: the pixels its mixture renders, not that pixel alone
            /// (0: the pixel, the paper's). Default: 1 for ga, 0 for ga-pt
            #[value_name = "GRID_SPACINGS"]
            #[range = 0.0..=16.0]
            pub footprint: Option<f64> = None,
        },
    }
}

impl PlanConfig {
    /// The side, in pixels, of the square a GA pixel's test paths start in, in a plan for
    /// the mixture estimator (`ga`) or for guides (`ga-pt`).
    pub fn footprint_pixels(&self, plan_for: PlanFor) -> f32 {
        let share = self.footprint.unwrap_or(match plan_for {
            PlanFor::Mixture => 1.0,
            PlanFor::Guide => 0.0,
        });
        (share * f64::from(self.grid(plan_for))).max(1.0) as f32
    }

    /// Distance between grid GA pixels in a plan for `plan_for`. `ga-pt`'s guides beside
    /// the spatial guide pay for fewer GA pixels: a coarser grid halves its GA phase on
    /// fig5 and lowers its error against `pg` there, and changes little elsewhere
    /// (docs/methods/ga.md, "Grid").
    pub fn grid(&self, plan_for: PlanFor) -> u32 {
        self.grid.unwrap_or(match plan_for {
            PlanFor::Mixture => 32,
            PlanFor::Guide => 64,
        })
    }

    /// GA pixels whose mixtures each pixel combines in a plan for `plan_for`.
    pub fn neighbours(&self, plan_for: PlanFor) -> usize {
        self.neighbours.unwrap_or(match plan_for {
            PlanFor::Mixture => 2,
            PlanFor::Guide => 4,
        })
    }

    /// Every setting within its declared range.
    pub fn validate(&self) -> Result<(), GaConfigError> {
        crate::settings_table::Table::check(self).map_err(|e| GaConfigError(e.to_string()))
    }
}
