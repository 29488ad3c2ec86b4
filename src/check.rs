//! `genpath check SCENE`: the numerical invariants every method must keep on any scene, at
//! a small size.
//!
//! * Every method ([`Method`]'s list, `ga-pt` with and without the spatial guide, `srt`
//!   and `ga` with either estimator (`nee`), and `mixture` when given one) renders without a
//!   NaN, infinite or negative pixel; each is prepared and rendered as `genpath render`
//!   does it.
//! * Every density a generator samples with — the `srt` generator and every generator the GA
//!   evolved — is finite and positive, and so is the mixture density of every light-carrying
//!   path (the estimator divides by it).
//! * Every fitness value (eq. 10) the GA computed is finite.
//! * The image means of the other methods agree with `pt`'s per channel, inside a
//!   99.9 % interval Šidák-corrected over the comparisons (unbiasedness, as far as the sample
//!   count can tell); a method that cannot see through a delta lobe at the camera ray's hit
//!   (`lt`, [`crate::integrators::MethodInfo::sees_through_delta`]) agrees with `pt`
//!   restricted likewise ([`crate::integrators::pt::NoDeltaFirst`]).

use crate::film::sample_pixel;
use crate::film::Film;
use crate::genetic::plan::{GateConfig, PlanConfig};
use crate::genetic::GaConfig;
use crate::integrators::pt::NoDeltaFirst;
use crate::integrators::{prepare, Integrator, Method, PrepareError, RenderSettings, Settings};
use crate::path::generator::{Contribution, Nee, PathGenerator, PathVertices};
use crate::path::mixture::Mixture;
use crate::path::{mixture_file, RayCounts, SceneView};
use statrs::distribution::{ContinuousCDF, Normal};
use std::ops::ControlFlow;

/// What `check` renders and samples.
#[derive(Clone, Debug, serde::Serialize)]
pub struct CheckConfig {
    pub spp: u32,
    pub max_bounces: u32,
    pub seed: u64,
    /// Paths sampled per generator for the density survey.
    pub paths_per_generator: usize,
    /// The methods' settings; `mixture` is rendered when it holds one.
    #[serde(skip)]
    pub methods: Settings,
}

impl CheckConfig {
    /// A small GA (the invariants do not depend on how well it converges).
    pub fn new(spp: u32, max_bounces: u32, seed: u64) -> Self {
        Self {
            spp,
            max_bounces,
            seed,
            paths_per_generator: 200,
            methods: Settings {
                ga: GaConfig {
                    population: 12,
                    generations: 6,
                    test_paths: 4000,
                    ..GaConfig::default()
                },
                // Without the gate, so that `ga` and `ga-pt` render with evolved mixtures
                // wherever the GA found one, not with `pt`.
                plan: PlanConfig {
                    grid: Some(8),
                    ..PlanConfig::default()
                },
                gate: GateConfig { gate: false },
                ..Settings::default()
            },
        }
    }
}

/// One method's render.
#[derive(Clone, Debug, serde::Serialize)]
pub struct MethodCheck {
    /// The method, with `:key=value` for a variant (as `sweep --methods` writes it).
    pub method: String,
    /// Pixels with a NaN, infinite or negative channel.
    pub bad_pixels: usize,
    /// Image mean per channel and its standard error.
    pub mean: [f64; 3],
    pub standard_error: [f64; 3],
    /// Largest |z| of the mean against `pt`'s (or restricted `pt`'s, for a method that does
    /// not see through a delta lobe at the camera ray's hit), over the channels (0 for
    /// either `pt`).
    pub z_vs_pt: f64,
    pub seconds: f64,
}

/// Everything `check` measured, and what failed.
#[derive(Clone, Debug, serde::Serialize)]
pub struct CheckReport {
    pub methods: Vec<MethodCheck>,
    /// Densities seen while sampling (directions in solid angle, light points by area,
    /// and mixture densities of whole paths): count, smallest, largest, and how many were
    /// not finite and positive.
    pub pdf_samples: usize,
    pub pdf_min: f64,
    pub pdf_max: f64,
    pub pdf_bad: usize,
    /// Fitness values computed by the GA, and how many were not finite.
    pub fitness_values: usize,
    pub fitness_bad: usize,
    /// Critical |z| for the unbiasedness comparisons.
    pub z_critical: f64,
    pub failures: Vec<String>,
}

impl CheckReport {
    pub fn passed(&self) -> bool {
        self.failures.is_empty()
    }
}

/// The image's mean per channel and its standard error. A light path splats onto up to
/// `max_bounces` pixels, so the splat layer's pixels are not independent: the variance of
/// their mean is at most `max_bounces` times the sum of theirs (Cauchy–Schwarz over each
/// path's splats), which is what is taken for it.
fn image_mean(film: &Film, max_bounces: u32) -> ([f64; 3], [f64; 3]) {
    let n = film.image.pixels.len().max(1) as f64;
    let mut mean = [0.0; 3];
    let mut var = [0.0; 3];
    let splats = film.sums.splats.as_ref();
    for (i, (p, v)) in film
        .image
        .pixels
        .iter()
        .zip(&film.variance_of_mean)
        .enumerate()
    {
        let more = splats.map_or(glam::DVec3::ZERO, |s| {
            s.variance(i) * f64::from(max_bounces.max(1) - 1)
        });
        for c in 0..3 {
            mean[c] += p[c] as f64 / n;
            var[c] += (v[c] + more[c]) / (n * n);
        }
    }
    (mean, var.map(f64::sqrt))
}

#[derive(Default)]
struct PdfSurvey {
    count: usize,
    min: f64,
    max: f64,
    bad: usize,
}

impl PdfSurvey {
    fn see(&mut self, pdf: f64) {
        if self.count == 0 {
            (self.min, self.max) = (f64::INFINITY, 0.0);
        }
        self.count += 1;
        if pdf.is_finite() && pdf > 0.0 {
            self.min = self.min.min(pdf);
            self.max = self.max.max(pdf);
        } else {
            self.bad += 1;
        }
    }

    /// Samples `n` paths with `g` from pixel `(x, y)`, recording every sampled density and
    /// the density `mixture` gives each light-carrying path.
    #[allow(clippy::too_many_arguments)]
    fn sample(
        &mut self,
        view: &SceneView,
        g: &PathGenerator,
        mixture: &Mixture,
        (x, y): (u32, u32),
        n: usize,
        max_bounces: u32,
        seed: u64,
    ) {
        let camera = &view.scene.camera;
        let mut path = PathVertices::default();
        let mut contributions: Vec<Contribution> = Vec::new();
        let mut counts = RayCounts::default();
        sample_pixel(camera, seed, (x, y), 0..n as u64, |ray, rng| {
            let Some(x1) = view.trace_through(ray, rng, &mut counts) else {
                return ControlFlow::Continue(());
            };
            contributions.clear();
            g.sample_path(
                view,
                ray.origin,
                x1,
                (max_bounces, mixture.nee),
                rng,
                &mut counts,
                &mut path,
                &mut contributions,
            );
            for v in path
                .vertices
                .iter()
                .filter(|v| !v.delta && v.wi != glam::Vec3::ZERO)
            {
                self.see(v.pdf_sampled);
            }
            if let Some(light) = path.light {
                self.see(light.pdf_sampled);
            }
            for c in &contributions {
                if let Some(light) = c.light {
                    self.see(light.pdf_sampled);
                }
                self.see(mixture.pdf_path(view, &path, c, max_bounces));
            }
            ControlFlow::Continue(())
        });
    }
}

/// The methods `check` renders: every [`Method`] that renders the scene's image with
/// `config`'s settings (`mixture` only with a mixture), `ga-pt` without the spatial guide,
/// and `srt` and `ga` with the estimator that `config` does not use.
fn variants(config: &Settings) -> Vec<(String, Method, Settings)> {
    use clap::ValueEnum as _;
    let mut out: Vec<_> = Method::value_variants()
        .iter()
        .filter(|&&m| m != Method::Mixture || config.loaded_mixture.is_some())
        .filter(|&&m| m.info().renders_the_scene)
        .map(|&m| {
            let name = m.to_possible_value().map(|v| v.get_name().to_string());
            (name.unwrap_or_default(), m, config.clone())
        })
        .collect();
    let mut without = config.clone();
    without.spatial.spatial_guide = false;
    out.push(("ga-pt:spatial=0".to_string(), Method::GaPt, without));
    let mut other = config.clone();
    other.srt.nee = match config.srt.nee {
        Nee::Every => Nee::End,
        Nee::End => Nee::Every,
    };
    let name = other
        .srt
        .nee
        .to_possible_value()
        .map(|v| v.get_name().to_string());
    let name = name.unwrap_or_default();
    for (label, method) in [("srt", Method::Srt), ("ga", Method::Ga)] {
        out.push((format!("{label}:nee={name}"), method, other.clone()));
    }
    out
}

/// Films with their methods' labels and the film each is compared with (none for `pt` and
/// its restriction, the references).
type LabelledFilms = Vec<(String, Film, Option<usize>)>;

/// The label of `pt` restricted to the paths that do not go on through a delta lobe at the
/// camera ray's hit.
const PT_NO_DELTA_FIRST: &str = "pt:no-delta-first";

/// Renders every method of [`variants`] as `genpath render` would; the films, labelled; the
/// densities of the mixtures they chose are surveyed into `survey` and the numbers they
/// learned gathered in `numbers` ([`crate::integrators::SelfCheck`]).
fn render_every_method(
    view: &SceneView,
    config: &CheckConfig,
    (survey, numbers): (&mut PdfSurvey, &mut Vec<f64>),
) -> Result<LabelledFilms, PrepareError> {
    let mut films: LabelledFilms = Vec::new();
    let mut restricted = None;
    for (label, method, methods) in variants(&config.methods) {
        let settings = RenderSettings {
            method,
            spp: config.spp,
            max_bounces: config.max_bounces,
            seed: config.seed,
            progress: false,
            shard: Default::default(),
            control: Default::default(),
            learning: None,
        };
        let reference = match method.info().sees_through_delta {
            true => 0,
            false => *restricted.get_or_insert_with(|| {
                let pt = NoDeltaFirst {
                    max_bounces: config.max_bounces,
                };
                let view = view.with_light_sampler(methods.lights.light_sampler);
                let film = pt.render(
                    &view,
                    &RenderSettings {
                        method: Method::Pt,
                        ..settings.clone()
                    },
                );
                films.push((PT_NO_DELTA_FIRST.into(), film, None));
                films.len() - 1
            }),
        };
        let integrator = prepare(view, &methods, &settings)?;
        let film = integrator.render(view, &settings);
        films.push((label, film, (!films.is_empty()).then_some(reference)));
        let checked = integrator.self_check();
        for &(at, mixture) in &checked.mixtures {
            survey_mixture(survey, view, config, (at, mixture));
        }
        numbers.extend(checked.numbers);
    }
    Ok(films)
}

/// Each film's bad pixels and its image mean against the first film's (`pt`'s), with the
/// Šidák-corrected critical |z|; failures are added to `failures`.
fn judge_films(
    films: &LabelledFilms,
    max_bounces: u32,
    failures: &mut Vec<String>,
) -> (Vec<MethodCheck>, f64) {
    let comparisons = 3 * films.iter().filter(|f| f.2.is_some()).count().max(1);
    let alpha = 1.0 - 0.999f64.powf(1.0 / comparisons as f64);
    let z_critical = Normal::new(0.0, 1.0)
        .map(|n| n.inverse_cdf(1.0 - alpha / 2.0))
        .unwrap_or(4.0);
    let mut methods = Vec::new();
    for (method, film, reference) in films {
        let bad_pixels = film
            .image
            .pixels
            .iter()
            .filter(|p| p.iter().any(|c| !c.is_finite() || *c < 0.0))
            .count();
        if bad_pixels > 0 {
            failures.push(format!(
                "{method}: {bad_pixels} NaN, infinite or negative pixels"
            ));
        }
        let (mean, se) = image_mean(film, max_bounces);
        let mut z: f64 = 0.0;
        if let Some(reference) = *reference {
            let (reference, (pt_mean, pt_se)) = (
                &films[reference].0,
                image_mean(&films[reference].1, max_bounces),
            );
            for c in 0..3 {
                let s = (se[c] * se[c] + pt_se[c] * pt_se[c]).sqrt();
                if s > 0.0 {
                    z = z.max((mean[c] - pt_mean[c]).abs() / s);
                } else if mean[c] != pt_mean[c] {
                    z = f64::INFINITY;
                }
            }
            if z.is_nan() || z > z_critical {
                failures.push(format!(
                    "{method}: image mean differs from {reference}'s by |z| = {z:.2} > {z_critical:.2}"
                ));
            }
        }
        methods.push(MethodCheck {
            method: method.clone(),
            bad_pixels,
            mean,
            standard_error: se,
            z_vs_pt: z,
            seconds: film.elapsed.as_secs_f64(),
        });
    }
    (methods, z_critical)
}

/// The densities `srt` samples with, from the image's centre.
fn survey_srt(view: &SceneView, config: &CheckConfig) -> PdfSurvey {
    let methods = &config.methods.srt;
    let srt = mixture_file::srt(
        view.scene,
        config.max_bounces,
        methods.absorption(methods.nee),
    )
    .with_nee(methods.nee);
    let mut survey = PdfSurvey::default();
    let camera = &view.scene.camera;
    let centre = (camera.width / 2, camera.height / 2);
    survey.sample(
        view,
        &srt.generators[0],
        &srt,
        centre,
        config.paths_per_generator,
        config.max_bounces,
        config.seed,
    );
    survey
}

/// Adds the densities each generator of `mixture` samples with from pixel `at` to `survey`.
fn survey_mixture(
    survey: &mut PdfSurvey,
    view: &SceneView,
    config: &CheckConfig,
    (at, mixture): ((u32, u32), &Mixture),
) {
    for g in &mixture.generators {
        survey.sample(
            view,
            g,
            mixture,
            at,
            config.paths_per_generator / 4,
            config.max_bounces,
            config.seed,
        );
    }
}

/// Runs every check on `view`'s scene at its camera's size.
pub fn check(view: &SceneView, config: &CheckConfig) -> Result<CheckReport, PrepareError> {
    let mut failures = Vec::new();
    let mut survey = survey_srt(view, config);
    let mut values = Vec::new();
    let films = render_every_method(view, config, (&mut survey, &mut values))?;
    let (methods, z_critical) = judge_films(&films, config.max_bounces, &mut failures);
    if survey.bad > 0 {
        failures.push(format!(
            "{} of {} sampled densities are not finite and positive",
            survey.bad, survey.count
        ));
    }
    let fitness_bad = values.iter().filter(|v| !v.is_finite()).count();
    if fitness_bad > 0 {
        failures.push(format!(
            "{fitness_bad} of {} fitness values are not finite",
            values.len()
        ));
    }
    Ok(CheckReport {
        methods,
        pdf_samples: survey.count,
        pdf_min: survey.min,
        pdf_max: survey.max,
        pdf_bad: survey.bad,
        fitness_values: values.len(),
        fitness_bad,
        z_critical,
        failures,
    })
}
