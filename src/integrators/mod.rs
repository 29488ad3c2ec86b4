//! The rendering methods behind one seam, in the manner of pbrt-v4's `Integrator` →
//! `ImageTileIntegrator::EvaluatePixelSample` and Mitsuba 3's `SamplingIntegrator::sample`.
//!
//! A method is *prepared* once per render by [`prepare`]: it builds what it renders with
//! (a mixture, a GA plan, a spatial guide with its training passes) and owns it, as a
//! [`Integrator`]. Every command renders an integrator the same way,
//! [`Integrator::render`], which runs the film's loop ([`crate::film::render`]): each tile
//! asks the integrator for a [`PixelEstimator`], starts it at each pixel, and sums the
//! radiance of its samples. Samples an integrator took while preparing (a spatial guide's training
//! passes) are part of its image, and only the integrator counts them.
//!
//! Adding a method is one file here with a `prepare` function and one line in
//! [`methods!`]'s list below.

pub mod ga;
pub mod ga_pt;
pub mod learned;
pub mod mixture;
pub mod pg;
pub mod pt;
pub mod settings;
#[cfg(feature = "testing")]
pub mod test_method;

use crate::film::{self, Control, Film, Pass, PixelEstimator, PixelSums, Shard};
use crate::genetic::plan::{LearnStore, Plan, PlanError};
use crate::genetic::GaConfigError;
use crate::guiding::SpatialField;
use crate::path::mixture::Mixture;
use crate::path::SceneView;
pub use learned::{prepare_learned, Learned};
pub use settings::Settings;
use std::sync::Arc;

/// Declares [`Method`] and [`prepare`] from one list: each entry is a method's `--method`
/// variant (its documentation is its help text) and the function that prepares it.
macro_rules! methods {
    ($($(#[doc = $doc:literal])* $(#[cfg($cfg:meta)])? $variant:ident => $prepare:path,)*) => {
        /// Rendering methods selectable with `--method`.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
        #[serde(rename_all = "kebab-case")]
        pub enum Method {
            $($(#[doc = $doc])* $(#[cfg($cfg)])? $variant,)*
        }

        /// Prepares `settings.method`: builds and trains what it renders with.
        pub fn prepare(
            view: &SceneView,
            config: &Settings,
            settings: &RenderSettings,
        ) -> Result<Box<dyn Integrator>, PrepareError> {
            let context = Context { view, config, settings };
            if !settings.shard.is_whole() && settings.method.learns() {
                return Err(PrepareError::ShardLearns(settings.method));
            }
            match settings.method {
                $($(#[cfg($cfg)])? Method::$variant => $prepare(&context),)*
            }
        }
    };
}

methods! {
    /// Path tracing: NEE at every vertex + BSDF sampling, power heuristic, Russian roulette
    /// from depth 5 (the modern baseline, as Mitsuba 3 `path`).
    Pt => pt::prepare,
    /// The paper's baseline "stochastic ray tracing": BRDF sampling with fixed absorption,
    /// next-event estimation at every vertex (`--nee every`) or only at the path's end
    /// (`--nee end`, the paper's).
    Srt => mixture::prepare_srt,
    /// A mixture of path generators read from `--generators FILE` (eq. 7–8).
    Mixture => mixture::prepare,
    /// Genetic path generation: per GA pixel, a mixture evolved to minimise the variance
    /// on test paths (paper §4–5); every pixel renders with its neighbours' mixtures.
    Ga => ga::prepare,
    /// Beyond the paper: path tracing (`pt`) whose direction sampling is guided by the GA's
    /// evolved anchor samplers, and past them by `pg`'s spatial guide (`--spatial-guide`),
    /// with next-event estimation at every vertex.
    GaPt => ga_pt::prepare,
    /// Beyond the paper: path tracing guided by a spatial guide learned from path-traced
    /// training passes whose samples stay in the image (`guiding::field`), without the GA:
    /// the baseline that shows what the GA adds.
    Pg => pg::prepare,
    /// Test-only (feature `testing`): path tracing with next-event estimation alone (no
    /// MIS); shows that a method is one file and one line.
    #[cfg(feature = "testing")]
    NeeOnly => test_method::prepare,
}

impl Method {
    /// Whether preparing the method learns from the scene (a GA plan, a spatial guide), so
    /// that two renders of it with different sample shares would learn differently.
    pub fn learns(self) -> bool {
        matches!(self, Method::Ga | Method::GaPt | Method::Pg)
    }

    /// The method's `--method` name.
    pub fn name(self) -> String {
        use clap::ValueEnum;
        self.to_possible_value()
            .map_or_else(String::new, |v| v.get_name().to_string())
    }
}

/// What one render needs besides the scene.
#[derive(Clone, Debug, serde::Serialize)]
pub struct RenderSettings {
    pub method: Method,
    pub spp: u32,
    pub max_bounces: u32,
    pub seed: u64,
    /// Show a progress bar on stderr.
    #[serde(skip)]
    pub progress: bool,
    /// Which of every pixel's `spp` samples this render takes (all by default).
    #[serde(skip_serializing_if = "Shard::is_whole")]
    pub shard: Shard,
    /// How the render may be stopped, resumed and checkpointed (only methods that do not
    /// learn: see [`Method::learns`]).
    #[serde(skip)]
    pub control: Control,
    /// Where learning keeps what it finished between processes (`genpath learn`): a GA
    /// plan's waves of GA pixels and the spatial guide's passes, so that learning goes on
    /// after a signal, and the GA splits over jobs.
    #[serde(skip)]
    pub learning: Option<Arc<dyn LearnStore>>,
}

impl RenderSettings {
    /// The film's run of `spp` samples per pixel with these settings.
    pub fn pass(&self, spp: u32) -> Pass {
        Pass {
            spp,
            seed: self.seed,
            shard: self.shard,
            control: self.control.clone(),
            progress: self.progress,
        }
    }
}

/// Why a method cannot be prepared.
#[derive(Debug, thiserror::Error)]
pub enum PrepareError {
    #[error(transparent)]
    Ga(#[from] GaConfigError),
    #[error(transparent)]
    Plan(#[from] PlanError),
    /// What `genpath learn` kept of an earlier run cannot be used.
    #[error("{0}")]
    Kept(String),
    #[error(transparent)]
    Settings(#[from] settings::SettingsError),
    #[error("--method mixture needs --generators FILE")]
    NoMixture,
    #[error(
        "--shard: --method {} learns in every render (its GA plan or spatial guide), so shards \
         of it would not be parts of one render: the learned state must be trained once and \
         shared with every shard: `genpath learn … -o plan.bin`, then `render --plan plan.bin \
         --shard K/N` (docs/shards.md); or shard pt, srt or mixture",
        .0.name()
    )]
    ShardLearns(Method),
    #[error("the learned state is not one --method {} learns: {what}", method.name())]
    Learned { method: Method, what: String },
    #[error(
        "--spatial-passes {passes} trains on {needs} samples per pixel, more than --spp {spp} \
         (pass i takes 2^i)"
    )]
    TrainingExceedsSpp { passes: u32, needs: u64, spp: u32 },
}

/// What a method's `prepare` is given.
pub struct Context<'a> {
    pub view: &'a SceneView<'a>,
    pub config: &'a Settings,
    pub settings: &'a RenderSettings,
}

/// A prepared method as the image loop sees it: it gives each tile a [`PixelEstimator`].
/// Every such method is an [`Integrator`].
pub trait PixelIntegrator: Send + Sync {
    type Estimator<'a>: PixelEstimator
    where
        Self: 'a;
    /// An estimator for one tile's pixels.
    fn estimator(&self) -> Self::Estimator<'_>;
    /// The per-pixel sums of the samples preparing took, which the image keeps (none in a
    /// shard rendered with a saved learned state: the learn job's training shard has them).
    fn taken(&self) -> Option<&PixelSums> {
        None
    }
    /// Samples per pixel preparing took, whether or not the image keeps them.
    fn taken_spp(&self) -> u32 {
        self.taken().map_or(0, |t| t.spp)
    }
    /// What preparing learned (methods that learn).
    fn learned(&self) -> Option<Learned> {
        None
    }
    /// The GA plan it renders with.
    fn plan(&self) -> Option<&Plan> {
        None
    }
    /// The spatial guide it renders with.
    fn spatial(&self) -> Option<&SpatialField> {
        None
    }
    /// The one mixture it renders every pixel with.
    fn mixture(&self) -> Option<&Mixture> {
        None
    }
}

/// A prepared method, as every command renders it.
pub trait Integrator: Send + Sync {
    /// Renders the image with `settings.spp` samples per pixel in all, those preparing took
    /// included.
    fn render(&self, view: &SceneView, settings: &RenderSettings) -> Film {
        let more = settings.spp.saturating_sub(self.samples_taken());
        self.render_more(view, settings, more)
    }
    /// Renders `spp` samples per pixel more than preparing took (a time budget's render).
    fn render_more(&self, view: &SceneView, settings: &RenderSettings, spp: u32) -> Film;
    /// Samples per pixel preparing took, which are in every image it renders (but in a shard
    /// rendered with a saved learned state, which leaves them to the training shard).
    fn samples_taken(&self) -> u32;
    /// What preparing learned, for a plan file (methods that learn).
    fn learned(&self) -> Option<Learned>;
    fn plan(&self) -> Option<&Plan>;
    fn spatial(&self) -> Option<&SpatialField>;
    fn mixture(&self) -> Option<&Mixture>;
}

impl<I: PixelIntegrator> Integrator for I {
    fn render_more(&self, view: &SceneView, settings: &RenderSettings, spp: u32) -> Film {
        film::render(view, &settings.pass(spp), self.taken(), || self.estimator())
    }
    fn samples_taken(&self) -> u32 {
        self.taken_spp()
    }
    fn learned(&self) -> Option<Learned> {
        PixelIntegrator::learned(self)
    }
    fn plan(&self) -> Option<&Plan> {
        PixelIntegrator::plan(self)
    }
    fn spatial(&self) -> Option<&SpatialField> {
        PixelIntegrator::spatial(self)
    }
    fn mixture(&self) -> Option<&Mixture> {
        PixelIntegrator::mixture(self)
    }
}
