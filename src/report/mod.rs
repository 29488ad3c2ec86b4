//! Error against run time (reports/README.md): `genpath sweep` renders each method at
//! increasing budgets, measures relMSE and MSE against a reference, and writes a CSV and an
//! SVG plot.
//!
//! The time of a row is everything the method spends on the image: for `ga` the baseline,
//! test paths and evolution plus the render. Within one repetition the GA runs once and its
//! time is added to every budget's render (the plan depends on the seed, not on the budget).

pub mod bench;
pub mod picture;
pub mod plot;

use crate::film::Shard;
use crate::image::{metrics, Image};
use crate::integrators::settings::SettingsError;
use crate::integrators::{prepare, Integrator, Method, PrepareError, RenderSettings, Settings};
use crate::path::SceneView;
use crate::progress::progress_bar;
use std::fmt::Write as _;
use std::time::Instant;

/// A method to sweep, with a label for the CSV and the plot.
#[derive(Clone, Debug)]
pub struct MethodSpec {
    pub label: String,
    pub method: Method,
    pub config: Settings,
}

/// The sweep's short keys of the first line of work, kept as aliases of the settings they
/// name: `(alias, setting)`.
pub const KEY_ALIASES: [(&str, &str); 17] = [
    ("m", "test_paths"),
    ("l", "max_light_paths"),
    ("pop", "population"),
    ("gen", "generations"),
    ("s", "ga_generators"),
    ("e", "elitism"),
    ("grid", "ga_grid"),
    ("extra", "ga_extra"),
    ("neighbours", "ga_neighbours"),
    ("cw", "convex_weights"),
    ("gate", "gate"),
    ("warm", "warm_start"),
    ("da", "data_anchors"),
    ("pa", "patches"),
    ("gs", "guide_steps"),
    ("spatial", "spatial_guide"),
    ("sp", "spatial_passes"),
];

/// Why a `--methods` entry is no method with settings; each names the entry.
#[derive(Debug, thiserror::Error)]
pub enum MethodSpecError {
    #[error("unknown method `{name}` in `{text}`")]
    UnknownMethod { name: String, text: String },
    #[error("`{text}`: `{part}` is not key=value")]
    NotKeyValue { text: String, part: String },
    #[error("`{text}`: {source}")]
    Setting { text: String, source: SettingsError },
}

impl MethodSpec {
    /// A method name, optionally followed by `:key=value` pairs that override `base`'s
    /// settings: any setting's one name (`ga:test_paths=10000:ga_grid=32`), or an alias of
    /// [`KEY_ALIASES`] (`ga:m=10000:grid=32`); booleans are `true`/`false` (or 1/0).
    pub fn parse(text: &str, base: &Settings) -> Result<Self, MethodSpecError> {
        let mut parts = text.split(':');
        let name = parts.next().unwrap_or_default();
        let method = <Method as clap::ValueEnum>::from_str(name, false).map_err(|_| {
            MethodSpecError::UnknownMethod {
                name: name.to_string(),
                text: text.to_string(),
            }
        })?;
        let mut config = base.clone();
        for part in parts {
            let Some((key, value)) = part.split_once('=') else {
                return Err(MethodSpecError::NotKeyValue {
                    text: text.to_string(),
                    part: part.to_string(),
                });
            };
            let key = KEY_ALIASES
                .iter()
                .find(|(alias, _)| *alias == key)
                .map_or(key, |(_, setting)| setting);
            config
                .set(key, value)
                .map_err(|source| MethodSpecError::Setting {
                    text: text.to_string(),
                    source,
                })?;
        }
        Ok(Self {
            label: text.to_string(),
            method,
            config,
        })
    }
}

/// What a budget counts.
#[derive(Clone, Debug)]
pub enum Budgets {
    /// Samples per pixel.
    Spp(Vec<u32>),
    /// Wall-clock seconds per image, all phases included.
    Seconds(Vec<f64>),
}

impl Budgets {
    fn len(&self) -> usize {
        match self {
            Budgets::Spp(b) => b.len(),
            Budgets::Seconds(b) => b.len(),
        }
    }
}

/// One render of a sweep.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Row {
    pub scene: String,
    pub method: String,
    /// The budget asked for: samples per pixel, or seconds with time budgets.
    pub budget: f64,
    pub spp: u32,
    /// Everything: GA phases (if any) and the render.
    pub seconds: f64,
    pub ga_seconds: f64,
    pub relmse: f64,
    pub mse: f64,
    pub seed: u64,
    /// Fraction of the image's pixels with a NaN, infinite or negative channel, which
    /// relMSE leaves out of its mean ([`crate::image::metrics::ErrorMetrics`]): a row's
    /// relMSE compares with another's only where both are 0.
    pub bad_fraction: f64,
}

impl Row {
    /// `1 / (relMSE × seconds)`: higher is better, independent of the budget for an
    /// estimator whose error falls as 1/time.
    pub fn efficiency(&self) -> f64 {
        1.0 / (self.relmse * self.seconds)
    }
}

/// Header of the CSV that [`csv`] writes.
pub const CSV_HEADER: &str =
    "scene,method,spp,seconds,ga_seconds,relmse,mse,seed,efficiency,budget,bad_fraction";

/// The rows as CSV, with [`CSV_HEADER`].
pub fn csv(rows: &[Row]) -> String {
    let mut out = String::from(CSV_HEADER);
    out.push('\n');
    for r in rows {
        let _ = writeln!(
            out,
            "{},{},{},{:.6},{:.6},{:.6e},{:.6e},{},{:.6e},{},{}",
            r.scene,
            r.method,
            r.spp,
            r.seconds,
            r.ga_seconds,
            r.relmse,
            r.mse,
            r.seed,
            r.efficiency(),
            r.budget,
            r.bad_fraction
        );
    }
    out
}

/// Why a sweep's CSV cannot be read back; each names the line.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum CsvError {
    #[error("line 1: not the header `{CSV_HEADER}`")]
    Header,
    #[error("line {line}: {found} fields, not {expected}")]
    Fields {
        line: usize,
        found: usize,
        expected: usize,
    },
    #[error("line {line}: `{field}` is not a number")]
    NotANumber { line: usize, field: String },
    #[error("line {line}: `{field}` is not a whole number")]
    NotAWholeNumber { line: usize, field: String },
    #[error("line {line}: spp out of range")]
    SppOutOfRange { line: usize },
}

/// The rows of a CSV that [`csv`] wrote (its `efficiency` column, which follows from the
/// others, is not read).
pub fn parse_csv(text: &str) -> Result<Vec<Row>, CsvError> {
    let mut lines = text.lines().enumerate();
    match lines.next() {
        Some((_, header)) if header.trim() == CSV_HEADER => {}
        _ => return Err(CsvError::Header),
    }
    let mut rows = Vec::new();
    // A row has the header's fields.
    let fields = CSV_HEADER.split(',').count();
    for (i, line) in lines.filter(|(_, l)| !l.trim().is_empty()) {
        let f: Vec<&str> = line.split(',').collect();
        let line = i + 1;
        if f.len() != fields {
            return Err(CsvError::Fields {
                line,
                found: f.len(),
                expected: fields,
            });
        }
        let num = |k: usize| {
            f[k].parse::<f64>().map_err(|_| CsvError::NotANumber {
                line,
                field: f[k].to_string(),
            })
        };
        let int = |k: usize| {
            f[k].parse::<u64>().map_err(|_| CsvError::NotAWholeNumber {
                line,
                field: f[k].to_string(),
            })
        };
        rows.push(Row {
            scene: f[0].to_string(),
            method: f[1].to_string(),
            spp: u32::try_from(int(2)?).map_err(|_| CsvError::SppOutOfRange { line })?,
            seconds: num(3)?,
            ga_seconds: num(4)?,
            relmse: num(5)?,
            mse: num(6)?,
            seed: int(7)?,
            budget: num(9)?,
            bad_fraction: num(10)?,
        });
    }
    Ok(rows)
}

/// Everything a sweep needs besides the scene.
pub struct Sweep<'a> {
    pub scene_name: String,
    pub reference: &'a Image,
    pub methods: Vec<MethodSpec>,
    pub budgets: Budgets,
    /// Repetitions with seeds `seed, seed + 1, …`.
    pub reps: u32,
    /// `spp` and `method` are set per row; `seed` is the first repetition's.
    pub settings: RenderSettings,
    pub progress: bool,
    /// Which of the sweep's runs this one makes (`sweep --shard K/N`): run `j = rep ×
    /// budgets + b` (every method at budget `b` of repetition `rep`) is part `j mod N`'s.
    pub part: Shard,
}

/// Why a sweep cannot run.
#[derive(Debug, thiserror::Error)]
pub enum SweepError {
    #[error(transparent)]
    Prepare(#[from] PrepareError),
    #[error("the reference is {}×{} but the renders are {}×{} (use --width/--height)", reference.0, reference.1, image.0, image.1)]
    Size {
        reference: (u32, u32),
        image: (u32, u32),
    },
}

/// Samples per pixel of the two renders that calibrate a time budget: long enough that
/// their difference is not lost in timing noise, which with fewer samples made a budgeted
/// render run far past its budget (reports/README.md, "Measurements formerly in code
/// comments (2026-12-07)").
const CALIBRATION_SPP: [u32; 2] = [2, 16];

/// With budgets in seconds, a GA plan may take this share of each budget
/// (`PlanConfig::time_limit`); the render gets the rest.
pub const GA_BUDGET_SHARE: f64 = 0.25;

/// With budgets in seconds, a spatial guide's training passes may take this share of each
/// budget (`SpatialConfig::spatial_time_limit`); their samples stay in the image.
pub const SPATIAL_BUDGET_SHARE: f64 = 0.5;

/// Samples per pixel that fill `seconds` of rendering with `prepared`: render time is a
/// fixed part (per-pixel mixtures are built once per pixel whatever the spp) plus a cost per
/// sample, measured by two short renders.
fn calibrated_spp(
    view: &SceneView,
    settings: &RenderSettings,
    integrator: &dyn Integrator,
    seconds: f64,
) -> u32 {
    let time = |spp: u32| {
        integrator
            .render_more(view, settings, spp)
            .elapsed
            .as_secs_f64()
    };
    let [a, b] = CALIBRATION_SPP;
    let (t1, t2) = (time(a), time(b));
    let per_spp = ((t2 - t1) / f64::from(b - a))
        .max(t2 / f64::from(b) * 0.5)
        .max(1e-9);
    let fixed = (t1 - per_spp * f64::from(a)).max(0.0);
    ((seconds - fixed) / per_spp)
        .floor()
        .clamp(1.0, f64::from(1u32 << 24)) as u32
}

impl Sweep<'_> {
    /// Runs every method × repetition × budget; `on_row` sees each row, with its image, as
    /// it is done.
    pub fn run(
        &self,
        view: &SceneView,
        mut on_row: impl FnMut(&Row, &Image),
    ) -> Result<Vec<Row>, SweepError> {
        let camera = &view.scene.camera;
        if (self.reference.width, self.reference.height) != (camera.width, camera.height) {
            return Err(SweepError::Size {
                reference: (self.reference.width, self.reference.height),
                image: (camera.width, camera.height),
            });
        }
        let runs = (0..self.reps as usize * self.budgets.len())
            .filter(|j| j % self.part.count as usize == self.part.index as usize)
            .count();
        let total = self.methods.len() * runs;
        let bar = progress_bar(total as u64, "sweep", self.progress);
        let mut rows = Vec::with_capacity(total);
        // Each budget prepares its method anew: with budgets in seconds, a GA plan gets its
        // time limit (`GA_BUDGET_SHARE` of the budget) and a spatial guide's training
        // `SPATIAL_BUDGET_SHARE`; with budgets in samples, a spatial guide trains on half
        // of them (see `TrainingSchedule`).
        let plans: Vec<(Option<f64>, u32)> = match &self.budgets {
            Budgets::Spp(b) => b.iter().map(|&spp| (None, spp)).collect(),
            // Seconds decide how many samples a render takes: no sample count bounds what
            // preparing may keep for the image (a GA plan's baseline).
            Budgets::Seconds(b) => b.iter().map(|&t| (Some(t), u32::MAX)).collect(),
        };
        // The methods run one after the other at each budget, not each through all budgets
        // in turn: renders to be compared at equal time then run minutes closer together,
        // so that a shared machine's slow spells weigh on them more alike.
        for rep in 0..self.reps {
            for (b, &(seconds, spp)) in plans.iter().enumerate() {
                let run = rep as usize * plans.len() + b;
                if run % self.part.count as usize != self.part.index as usize {
                    continue;
                }
                for spec in &self.methods {
                    let settings = RenderSettings {
                        method: spec.method,
                        seed: self.settings.seed.wrapping_add(rep as u64),
                        progress: false,
                        spp,
                        ..self.settings.clone()
                    };
                    let mut config = spec.config.clone();
                    config.plan.time_limit = seconds.map(|t| GA_BUDGET_SHARE * t);
                    config.spatial.spatial_time_limit = seconds.map(|t| SPATIAL_BUDGET_SHARE * t);
                    let t0 = Instant::now();
                    let integrator = prepare(view, &config, &settings)?;
                    let prepare_s = t0.elapsed().as_secs_f64();
                    let phases = integrator.describe(&config);
                    let ga_seconds = phases.seconds("baseline") + phases.seconds("ga");
                    let (budget, film) = match seconds {
                        None => (f64::from(spp), integrator.render(view, &settings)),
                        Some(t) => {
                            let more = calibrated_spp(view, &settings, &*integrator, t - prepare_s);
                            (t, integrator.render_more(view, &settings, more))
                        }
                    };
                    let Some(m) = metrics::compare(&film.image, self.reference) else {
                        unreachable!("sizes checked above");
                    };
                    let row = Row {
                        scene: self.scene_name.clone(),
                        method: spec.label.clone(),
                        budget,
                        spp: film.spp,
                        seconds: prepare_s + film.elapsed.as_secs_f64(),
                        ga_seconds,
                        relmse: m.relmse,
                        mse: m.mse,
                        seed: settings.seed,
                        bad_fraction: m.bad_fraction,
                    };
                    on_row(&row, &film.image);
                    rows.push(row);
                    bar.inc(1);
                }
            }
        }
        bar.finish_and_clear();
        Ok(rows)
    }
}

/// Per method and budget: the mean samples per pixel, seconds, relMSE and efficiency over
/// repetitions, and the relMSE relative to `pt`'s at equal time, as a Markdown table. The
/// last is `pt`'s efficiency at the same budget over the method's: for estimators whose
/// relMSE falls as 1/time it is the ratio of their relMSEs at the same time, even where the
/// measured times of the two differ.
pub fn summary(rows: &[Row]) -> String {
    let mut out = String::from(
        "| method | budget | spp | seconds | relMSE | efficiency | relMSE / pt at equal time |\n|---|---|---|---|---|---|---|\n",
    );
    let mut methods: Vec<&str> = Vec::new();
    for r in rows {
        if !methods.contains(&r.method.as_str()) {
            methods.push(&r.method);
        }
    }
    let pt: Vec<&Row> = rows.iter().filter(|r| r.method == "pt").collect();
    let pt = plot::means(&pt);
    for m in methods {
        let of: Vec<&Row> = rows.iter().filter(|r| r.method == m).collect();
        for mean in plot::means(&of) {
            let ratio =
                pt.iter()
                    .find(|p| p.budget == mean.budget)
                    .map_or("–".to_string(), |p| {
                        format!(
                            "{:.3}",
                            (mean.relmse * mean.seconds) / (p.relmse * p.seconds)
                        )
                    });
            let _ = writeln!(
                out,
                "| {m} | {} | {:.0} | {:.2} | {:.4e} | {:.4} | {ratio} |",
                mean.budget,
                mean.spp,
                mean.seconds,
                mean.relmse,
                1.0 / (mean.relmse * mean.seconds)
            );
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(method: &str, bad_fraction: f64) -> Row {
        Row {
            scene: "fig5".into(),
            method: method.into(),
            budget: 2.0,
            spp: 40,
            seconds: 2.01,
            ga_seconds: 0.5,
            relmse: 3.5e-3,
            mse: 1.25e-3,
            seed: 401,
            bad_fraction,
        }
    }

    /// The CSV keeps each row's fraction of bad pixels, and a CSV without that column (an
    /// older sweep's) is refused by its header rather than read with a made-up one.
    #[test]
    fn csv_round_trip_keeps_bad_fraction() {
        let rows = [row("pt", 0.0), row("ga", 3.0 / 65536.0)];
        let back = parse_csv(&csv(&rows)).unwrap();
        let fractions: Vec<f64> = back.iter().map(|r| r.bad_fraction).collect();
        assert_eq!(fractions, [0.0, 3.0 / 65536.0]);
        assert_eq!(back[1].relmse, 3.5e-3);
        let old = "scene,method,spp,seconds,ga_seconds,relmse,mse,seed,efficiency,budget\n\
                   fig5,pt,40,2.01,0.5,3.5e-3,1.25e-3,401,1.4e2,2\n";
        let err = parse_csv(old).unwrap_err().to_string();
        assert!(
            err.contains("line 1") && err.contains("bad_fraction"),
            "{err}"
        );
        let short = format!("{CSV_HEADER}\nfig5,pt,40,2.01,0.5,3.5e-3,1.25e-3,401,1.4e2,2\n");
        let err = parse_csv(&short).unwrap_err().to_string();
        assert!(
            err.contains("line 2") && err.contains("10 fields, not 11"),
            "{err}"
        );
    }
}
