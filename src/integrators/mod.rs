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
//! Adding a method is one file here that declares its [`MethodInfo`] and one line in
//! [`methods!`]'s list below (docs/architecture.md has the recipe).

pub mod ga;
pub mod ga_pt;
pub mod learned;
pub mod lt;
pub mod mixture;
pub mod pg;
pub mod pt;
pub mod settings;
#[cfg(feature = "testing")]
pub mod test_constant;
#[cfg(feature = "testing")]
pub mod test_method;
#[cfg(feature = "testing")]
pub mod test_splat;

use crate::film::{self, Control, Film, Pass, PixelEstimator, PixelSums, Shard};
use crate::genetic::plan::{LearnStore, PlanError};
use crate::genetic::GaConfigError;
use crate::image::Image;
use crate::path::mixture::Mixture;
use crate::path::SceneView;
use crate::scene::Camera;
pub use learned::{prepare_learned, Learned};
pub use settings::Settings;
use std::sync::Arc;

/// Declares [`Method`] from one list: each entry is a method's `--method` variant (its
/// documentation is its help text) and the [`MethodInfo`] its file declares.
macro_rules! methods {
    ($($(#[doc = $doc:literal])* $(#[cfg($cfg:meta)])? $variant:ident => $info:path,)*) => {
        /// Rendering methods selectable with `--method`.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
        #[serde(rename_all = "kebab-case")]
        pub enum Method {
            $($(#[doc = $doc])* $(#[cfg($cfg)])? $variant,)*
        }

        impl Method {
            /// What the method's file declares of it.
            pub fn info(self) -> &'static MethodInfo {
                match self {
                    $($(#[cfg($cfg)])? Method::$variant => &$info,)*
                }
            }
        }
    };
}

methods! {
    /// Path tracing: NEE at every vertex + BSDF sampling, power heuristic, Russian roulette
    /// from depth 5 (the modern baseline, as Mitsuba 3 `path`).
    Pt => pt::METHOD,
    /// The paper's baseline "stochastic ray tracing": BRDF sampling with fixed absorption,
    /// next-event estimation at every vertex (`--nee every`) or only at the path's end
    /// (`--nee end`, the paper's).
    Srt => mixture::SRT,
    /// A mixture of path generators read from `--generators FILE` (eq. 7–8).
    Mixture => mixture::METHOD,
    /// Genetic path generation: per GA pixel, a mixture evolved to minimise the variance
    /// on test paths (paper §4–5); every pixel renders with its neighbours' mixtures.
    Ga => ga::METHOD,
    /// Beyond the paper: path tracing (`pt`) whose direction sampling is guided by the GA's
    /// evolved anchor samplers, and past them by `pg`'s spatial guide (`--spatial-guide`),
    /// with next-event estimation at every vertex.
    GaPt => ga_pt::METHOD,
    /// Beyond the paper: path tracing guided by a spatial guide learned from path-traced
    /// training passes whose samples stay in the image (`guiding::field`), without the GA:
    /// the baseline that shows what the GA adds.
    Pg => pg::METHOD,
    /// Beyond the paper: light tracing, paths from the lights (picked by power) splatted
    /// through the camera at every non-delta vertex; the camera's direct view of the lights
    /// from its own rays. It cannot see mirrors or smooth glass directly.
    Lt => lt::METHOD,
    /// Test-only (feature `testing`): path tracing with next-event estimation alone (no
    /// MIS); shows that a method is one file and one line.
    #[cfg(feature = "testing")]
    NeeOnly => test_method::METHOD,
    /// Test-only (feature `testing`): `pt`'s samples splatted onto the pixel mirrored left
    /// to right; shows that the film takes splats.
    #[cfg(feature = "testing")]
    SplatMirror => test_splat::METHOD,
    /// Test-only (feature `testing`): path tracing that learns one number per pixel and
    /// traces each sample's path with a probability that grows with it; shows that a method
    /// that learns is one file and one line.
    #[cfg(feature = "testing")]
    PixelConstant => test_constant::METHOD,
}

/// What a method is, as every command sees it: how it is prepared and what it learns. Each
/// method's file declares one (`pub const METHOD: MethodInfo`), named in [`methods!`]'s list.
pub struct MethodInfo {
    /// Builds and trains what it renders with.
    pub prepare: Prepare,
    /// For a method that learns: prepares it again from what an earlier preparation learned
    /// ([`Learned`], kept in a plan file by `genpath learn`) instead of training.
    pub prepare_learned: Option<PrepareLearned>,
    /// Whether `genpath learn --shard K/N` splits its learning over jobs.
    pub splits_learning: bool,
    /// Whether `render --explain FILE.svg` draws why its image is what it is.
    pub explains: bool,
    /// Whether its image is the scene's, so that `check` compares it with `pt`'s.
    pub renders_the_scene: bool,
    /// Whether its image holds the light the camera sees through a delta lobe at a camera
    /// ray's hit (a mirror or smooth glass seen directly); a light tracer's does not, and
    /// `check` compares it with `pt` restricted likewise ([`pt::NoDeltaFirst`]).
    pub sees_through_delta: bool,
    /// The tables of [`Settings`] it reads (`["srt", "ga", …]`; none for one that has no
    /// settings of its own), which docs/settings.md lists beside each table.
    pub settings: &'static [&'static str],
}

/// How a method is prepared ([`MethodInfo::prepare`]).
pub type Prepare = fn(&Context) -> Result<Box<dyn Integrator>, PrepareError>;
/// How a method is prepared from what it learned ([`MethodInfo::prepare_learned`]).
pub type PrepareLearned = fn(&Context, Learned) -> Result<Box<dyn Integrator>, PrepareError>;

impl MethodInfo {
    /// A method that learns nothing and renders the scene's image.
    pub const fn plain(prepare: Prepare) -> Self {
        Self {
            prepare,
            prepare_learned: None,
            splits_learning: false,
            explains: false,
            renders_the_scene: true,
            sees_through_delta: true,
            settings: &[],
        }
    }
}

/// Prepares `settings.method`: builds and trains what it renders with.
pub fn prepare(
    view: &SceneView,
    config: &Settings,
    settings: &RenderSettings,
) -> Result<Box<dyn Integrator>, PrepareError> {
    let context = Context {
        view,
        config,
        settings,
    };
    if !settings.shard.is_whole() && settings.method.learns() {
        return Err(PrepareError::ShardLearns(settings.method));
    }
    lit(view, config, |view| {
        (settings.method.info().prepare)(&Context { view, ..context })
    })
}

/// Prepares a method with `view` as `config`'s light sampling sees it
/// ([`crate::path::SceneView::light_sampler`]), and has it render with that view too.
pub(crate) fn lit(
    view: &SceneView,
    config: &Settings,
    prepare: impl FnOnce(&SceneView) -> Result<Box<dyn Integrator>, PrepareError>,
) -> Result<Box<dyn Integrator>, PrepareError> {
    let sampler = config.lights.light_sampler.resolve(view.scene);
    let inner = prepare(&view.with_light_sampler(sampler))?;
    Ok(match sampler == view.light_sampler {
        true => inner,
        false => Box::new(Lit { inner, sampler }),
    })
}

/// A prepared method that renders with its own light sampler ([`lit`]).
struct Lit {
    inner: Box<dyn Integrator>,
    sampler: crate::scene::LightSampler,
}

impl Integrator for Lit {
    fn render(&self, view: &SceneView, settings: &RenderSettings) -> Film {
        self.inner
            .render(&view.with_light_sampler(self.sampler), settings)
    }
    fn render_more(&self, view: &SceneView, settings: &RenderSettings, spp: u32) -> Film {
        (self.inner).render_more(&view.with_light_sampler(self.sampler), settings, spp)
    }
    fn samples_taken(&self) -> u32 {
        self.inner.samples_taken()
    }
    fn learned(&self) -> Option<Learned> {
        self.inner.learned()
    }
    fn describe(&self, config: &Settings) -> Description {
        self.inner.describe(config)
    }
    fn explain(&self, camera: &Camera, image: &Image) -> Option<Result<String, ExplainError>> {
        self.inner.explain(camera, image)
    }
    fn self_check(&self) -> SelfCheck<'_> {
        self.inner.self_check()
    }
}

impl Method {
    /// Whether preparing the method learns from the scene (a GA plan, a spatial guide), so
    /// that two renders of it with different sample shares would learn differently.
    pub fn learns(self) -> bool {
        self.info().prepare_learned.is_some()
    }

    /// The method named `name` (its `--method` name).
    pub fn named(name: &str) -> Option<Method> {
        use clap::ValueEnum;
        Method::value_variants()
            .iter()
            .copied()
            .find(|m| m.name() == name)
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
    /// The film's run of `run_spp` samples per pixel with these settings.
    pub fn pass(&self, run_spp: u32) -> Pass {
        Pass {
            run_spp,
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
    #[error("the learned state is not one --method {method} learns: {what}")]
    Learned { method: String, what: String },
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
    /// What it tells of itself ([`Integrator::describe`]).
    fn describe(&self, _config: &Settings) -> Description {
        Description::default()
    }
    /// `render --explain`'s picture of `image` (methods whose [`MethodInfo::explains`]).
    fn explain(&self, _camera: &Camera, _image: &Image) -> Option<Result<String, ExplainError>> {
        None
    }
    /// What `check` verifies of it besides its image.
    fn self_check(&self) -> SelfCheck<'_> {
        SelfCheck::default()
    }
}

/// What `check` verifies of a prepared method besides its image: the densities of the
/// mixtures it samples with at the pixels it chose (each must be finite and positive), and
/// the numbers it computed while learning (each must be finite).
#[derive(Debug, Default)]
pub struct SelfCheck<'a> {
    pub mixtures: Vec<((u32, u32), &'a Mixture)>,
    pub numbers: Vec<f64>,
}

/// What a prepared method tells of itself, so that commands need not know its insides.
#[derive(Debug, Default)]
pub struct Description {
    /// Its entries in a render's JSON statistics (the GA's, the spatial guide's, its
    /// mixture's), by key.
    pub stats: serde_json::Map<String, serde_json::Value>,
    /// The seconds of each phase of its preparation, by name (`ga`, `spatial`, …), for the
    /// JSON's `times_s` and the sweep's time budgets.
    pub phases: Vec<(&'static str, f64)>,
    /// What it tells on stderr after a render (what it learned), a line each.
    pub lines: Vec<String>,
}

impl Description {
    /// The seconds of phase `name` (0 if it has none).
    pub fn seconds(&self, name: &str) -> f64 {
        self.phases
            .iter()
            .filter(|(n, _)| *n == name)
            .map(|(_, s)| s)
            .sum()
    }
}

/// Why `render --explain` drew no picture.
#[derive(Debug, thiserror::Error)]
#[error(transparent)]
pub struct ExplainError(#[from] pub Box<dyn std::error::Error + Send + Sync>);

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
    /// What it tells of itself: its JSON statistics, its phases' seconds, its report
    /// (`config`: the settings it was prepared with).
    fn describe(&self, config: &Settings) -> Description;
    /// `render --explain`'s picture of `image` (methods whose [`MethodInfo::explains`]).
    fn explain(&self, camera: &Camera, image: &Image) -> Option<Result<String, ExplainError>>;
    /// What `check` verifies of it besides its image.
    fn self_check(&self) -> SelfCheck<'_>;
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
    fn describe(&self, config: &Settings) -> Description {
        PixelIntegrator::describe(self, config)
    }
    fn explain(&self, camera: &Camera, image: &Image) -> Option<Result<String, ExplainError>> {
        PixelIntegrator::explain(self, camera, image)
    }
    fn self_check(&self) -> SelfCheck<'_> {
        PixelIntegrator::self_check(self)
    }
}

/// The settings tables that `methods` name but `tables` lacks, and the tables no method
/// reads: what the methods' declarations ([`MethodInfo::settings`]) must not have.
pub fn settings_mismatches(methods: &[(String, &[&str])], tables: &[&str]) -> Vec<String> {
    let mut out = Vec::new();
    for (method, named) in methods {
        for table in named.iter().filter(|t| !tables.contains(t)) {
            out.push(format!(
                "{method} reads a table `{table}` that the settings lack"
            ));
        }
    }
    for table in tables {
        if !methods.iter().any(|(_, named)| named.contains(table)) {
            out.push(format!("no method reads the table `{table}`"));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::{settings_mismatches, Method};
    use clap::ValueEnum;

    /// Every table a method declares is one of [`super::Settings`]'s, and every table is read
    /// by some method; the twin: a method that names a table the settings lack.
    #[test]
    fn methods_declare_the_tables_they_read() {
        let methods: Vec<(String, &[&str])> = (Method::value_variants().iter())
            .map(|m| (m.name(), m.info().settings))
            .collect();
        let tables: Vec<&str> = (super::settings::tables().into_iter())
            .map(|(name, _)| name)
            .collect();
        assert_eq!(tables.len(), 7, "{tables:?}");
        assert_eq!(settings_mismatches(&methods, &tables), Vec::<String>::new());
        let mut wrong = methods.clone();
        wrong.push(("made-up".into(), &["srt", "gaa"]));
        assert_eq!(
            settings_mismatches(&wrong, &tables),
            ["made-up reads a table `gaa` that the settings lack"]
        );
        assert_eq!(
            settings_mismatches(&methods, &[&tables[..], &["orphan"]].concat()),
            ["no method reads the table `orphan`"]
        );
    }
}
