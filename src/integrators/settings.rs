//! Every method's settings, one table per concern, with one name each.
//!
//! A setting's name is its key in its table, and that key is unique across the tables, so
//! the one name serves everywhere: the TOML of `--config FILE` (`[ga] test_paths = 4000`),
//! `--set test_paths=4000` (or `--set ga.test_paths=4000`), the flag `--test-paths` (the key
//! with dashes), the sweep's method keys (`ga:test_paths=4000`) and the JSON statistics
//! (`"ga": { "test_paths": 4000 }`). Each table is declared once, with
//! [`crate::settings_table!`] beside what it configures: every setting's help, default and
//! range are written there only, and the flags, the TOML, the range check and
//! docs/settings.md derive from it. A key that no table has is refused wherever it is
//! written (`deny_unknown_fields` on every table, and no `flatten`, which would silently
//! defeat it), and so is a value outside its range, in the same words.

use crate::genetic::plan::{GateConfig, PlanConfig};
use crate::genetic::{GaConfig, GaConfigError};
use crate::guiding::selection::Selection;
use crate::path::generator::{Nee, SrtAbsorption, ABSORPTION_MAX, ABSORPTION_MIN};
use crate::path::mixture::Mixture;
use crate::scene::LightSampler;
use crate::settings_table::{Interval, Kind, OutOfRange, Setting, Table};
use clap::builder::ValueParser;
use clap::ArgMatches;
use std::path::PathBuf;

/// The settings of every method, one table per concern.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Settings {
    pub srt: SrtConfig,
    pub mixture: MixtureConfig,
    pub ga: GaConfig,
    pub plan: PlanConfig,
    pub gate: GateConfig,
    pub spatial: SpatialConfig,
    pub lights: LightsConfig,
    /// The mixture of `mixture.generators`, loaded for the scene (`--method mixture`).
    #[serde(skip)]
    pub loaded_mixture: Option<Mixture>,
}

/// Most training passes of the spatial guide (the last one of 2048 samples per pixel).
pub const MAX_SPATIAL_PASSES: u32 = 12;

crate::settings_table! {
    /// `srt`, the paper's stochastic ray tracing (and the defensive generator of every
    /// evolved mixture), table `[srt]`.
    #[derive(Clone, Debug, PartialEq)]
    pub struct SrtConfig {
        table: "srt",
        heading: "srt (--method srt, and the defensive generator of ga)",
        settings: {
            /// Absorption (Russian-roulette probability) of the `srt` generator at each
            /// vertex. Default: with next-event estimation at every vertex none before the
            /// fifth vertex and 0.1 from it (as pt's roulette), the paper's 0.5 at every vertex
            /// with `--nee end` (and for ga-pt's GA, whose test paths are end-only)
            #[range = ABSORPTION_MIN..=ABSORPTION_MAX]
            pub srt_absorption: Option<f64> = None,
            /// Where srt, mixture and ga do next-event estimation: at every non-delta vertex
            /// (balance heuristic over each generator's direction and light-point
            /// techniques), or only at the path's end (the paper's, for its Fig. 7).
            pub nee: Nee = Nee::default(),
        },
    }
}

impl SrtConfig {
    /// The `srt` generator's absorption for an estimator with next-event estimation `nee`:
    /// `srt_absorption` where set, else that estimator's default
    /// ([`Nee::default_srt_absorption`]).
    pub fn absorption(&self, nee: Nee) -> SrtAbsorption {
        self.srt_absorption
            .map_or_else(|| nee.default_srt_absorption(), SrtAbsorption::from)
    }
}

crate::settings_table! {
    /// How path tracing's next-event estimation picks a light, table `[lights]`.
    #[derive(Clone, Debug, PartialEq)]
    pub struct LightsConfig {
        table: "lights",
        heading: "Light sampling (--method pt, pg, ga-pt)",
        settings: {
            /// How next-event estimation picks the light it samples: `bvh`, a light tree that
            /// picks each light by an estimate of what it sends to the point (after pbrt-v4's
            /// BVH light sampler); `uniform`, Mitsuba 3's uniform pick among the environment,
            /// each delta light and the area emitters taken as one (their points by area);
            /// `auto`, the tree where the scene has more than one light (each connected
            /// emitting surface counted as one), else `uniform`. The mixtures of srt,
            /// mixture and ga keep the paper's light-point sampler.
            pub light_sampler: LightSampler = LightSampler::default(),
        },
    }
}

/// A setting whose values are those of a `clap::ValueEnum` (`--nee every|end`,
/// `--light-sampler auto|uniform|bvh`, `--guide-selection fixed|learned`), named as its
/// `clap::ValueEnum` names them.
macro_rules! value_enum_kind {
    ($($t:ty),*) => {$(
        impl Kind for $t {
            fn parser(_: &'static str, _: Option<Interval>) -> ValueParser {
                clap::builder::EnumValueParser::<$t>::new().into()
            }
            fn default_text(&self) -> Option<String> {
                clap::ValueEnum::to_possible_value(self).map(|v| v.get_name().to_string())
            }
            fn from_matches(matches: &ArgMatches, id: &str) -> Self {
                matches
                    .get_one::<$t>(id)
                    .copied()
                    .expect("a flag given on the command line has its parsed value")
            }
        }
    )*};
}

value_enum_kind!(Nee, LightSampler, Selection);

crate::settings_table! {
    /// `mixture`: a mixture of path generators from a file, table `[mixture]`.
    #[derive(Clone, Debug, PartialEq)]
    pub struct MixtureConfig {
        table: "mixture",
        heading: "Mixture (--method mixture)",
        settings: {
            /// Mixture of path generators for `--method mixture` (TOML or JSON; see
            /// docs/scenes.md).
            #[value_name = "FILE"]
            pub generators: Option<PathBuf> = None,
        },
    }
}

crate::settings_table! {
    /// The spatial guide: `pg`'s, and `ga-pt`'s past the vertices its GA steers, table
    /// `[spatial]`.
    #[derive(Clone, Debug, PartialEq)]
    pub struct SpatialConfig {
        table: "spatial",
        heading: "Spatial guide (--method pg, ga-pt)",
        settings: {
            // On by default: at equal time `ga-pt` with it has less error than without on
            // every tuning scene (reports/README.md).
            /// ga-pt: guide the vertices the GA does not steer with a spatial guide learned
            /// from path-traced training passes (see --spatial-passes), as --method pg does
            /// everywhere (beyond the paper). `false`: path tracing's own sampling there.
            pub spatial_guide: bool = true,
            /// pg, and ga-pt with the spatial guide: passes of path tracing that train the
            /// spatial guide, pass i with 2^i samples per pixel; their samples count in --spp
            /// and stay in the image. Default: as many as fit in half of --spp.
            #[range = 1..=i64::from(MAX_SPATIAL_PASSES)]
            pub spatial_passes: Option<u32> = None,
            /// pg, and ga-pt with the spatial guide: the probability with which a guided
            /// vertex samples its region's guide rather than the BSDF. `fixed`: 1/2 in every
            /// region; `learned`: per region, fitted to the training records by the
            /// Kullback-Leibler divergence, within [0.1, 1/2] (docs/methods/pg.md).
            pub guide_selection: Selection = Selection::default(),
        },
        internal: {
            /// Seconds the spatial guide's training may take (see `spatial_passes`; set by the
            /// equal-time sweep, not a setting): unset, as many passes as fit in half the
            /// samples per pixel.
            pub spatial_time_limit: Option<f64> = None,
        },
    }
}

impl SpatialConfig {
    /// What the declared ranges do not say: the training's time limit.
    fn validate(&self) -> Result<(), SettingsError> {
        if let Some(t) = self
            .spatial_time_limit
            .filter(|t| !(t.is_finite() && *t >= 0.0))
        {
            return Err(SettingsError::Spatial(format!(
                "the training's time limit {t} must be finite and ≥ 0 seconds"
            )));
        }
        Ok(())
    }
}

/// Why settings cannot be read or set.
#[derive(Debug, thiserror::Error)]
pub enum SettingsError {
    #[error("{origin}: {message}")]
    Parse { origin: String, message: String },
    #[error("unknown setting `{key}` (settings: {known})")]
    UnknownKey { key: String, known: String },
    #[error("`{0}` is not key=value")]
    NotAssignment(String),
    #[error(transparent)]
    Invalid(#[from] GaConfigError),
    #[error(transparent)]
    OutOfRange(#[from] OutOfRange),
    #[error("invalid spatial guide setting: {0}")]
    Spatial(String),
}

/// The tables and their keys, in the order documentation lists them.
pub fn tables() -> Vec<(&'static str, Vec<&'static str>)> {
    fn table<T: Table>() -> (&'static str, Vec<&'static str>) {
        (T::NAME, T::keys())
    }
    vec![
        table::<SrtConfig>(),
        table::<MixtureConfig>(),
        table::<GaConfig>(),
        table::<PlanConfig>(),
        table::<GateConfig>(),
        table::<SpatialConfig>(),
        table::<LightsConfig>(),
    ]
}

/// Every setting as its table declares it, in the order of the flags (which the help
/// shows): the mixture's file first, then `srt`'s, the GA's, its plan's, the gate's, the
/// spatial guide's and light sampling's.
pub fn declarations() -> Vec<Setting> {
    [
        MixtureConfig::settings(),
        SrtConfig::settings(),
        GaConfig::settings(),
        PlanConfig::settings(),
        GateConfig::settings(),
        SpatialConfig::settings(),
        LightsConfig::settings(),
    ]
    .concat()
}

/// The table holding `key`.
pub fn table_of(key: &str) -> Option<&'static str> {
    tables()
        .into_iter()
        .find(|(_, keys)| keys.contains(&key))
        .map(|(table, _)| table)
}

fn known_keys() -> String {
    let keys: Vec<String> = tables()
        .into_iter()
        .flat_map(|(t, keys)| keys.into_iter().map(move |k| format!("{t}.{k}")))
        .collect();
    keys.join(", ")
}

impl Settings {
    /// Settings from TOML `text` (a `--config` file, named `origin` in errors), every table
    /// and key optional.
    pub fn from_toml(text: &str, origin: &str) -> Result<Self, SettingsError> {
        let settings: Self = toml::from_str(text).map_err(|e| SettingsError::Parse {
            origin: origin.to_string(),
            message: e.to_string().trim_end().to_string(),
        })?;
        settings.validate().map_err(|e| SettingsError::Parse {
            origin: origin.to_string(),
            message: e.to_string(),
        })?;
        Ok(settings)
    }

    /// Sets `key` (`table.key`, or a key alone: keys are unique across tables) to `value`,
    /// written as in TOML (`4000`, `0.25`, `true`, `"file.toml"`; a bare word is a string).
    pub fn set(&mut self, key: &str, value: &str) -> Result<(), SettingsError> {
        let known = |t: &str, k: &str| {
            tables()
                .iter()
                .any(|(n, keys)| *n == t && keys.contains(&k))
        };
        let resolved = match key.split_once('.') {
            Some((t, k)) => known(t, k).then_some((t, k)),
            None => table_of(key).map(|t| (t, key)),
        };
        let Some((table, key)) = resolved else {
            return Err(SettingsError::UnknownKey {
                key: key.to_string(),
                known: known_keys(),
            });
        };
        let origin = format!("{table}.{key}={value}");
        let parse_error = |message: String| SettingsError::Parse {
            origin: origin.clone(),
            message,
        };
        let mut value = toml::from_str::<toml::Table>(&format!("v = {value}"))
            .ok()
            .and_then(|mut t| t.remove("v"))
            .unwrap_or_else(|| toml::Value::String(value.to_string()));
        let toml::Value::Table(mut all) =
            toml::Value::try_from(&*self).map_err(|e| parse_error(e.to_string()))?
        else {
            unreachable!("settings serialise to a table");
        };
        let Some(toml::Value::Table(section)) = all.get_mut(table) else {
            unreachable!("every table serialises");
        };
        // An integer where a number is expected is that number, and 0 or 1 where a boolean
        // is, false or true.
        match (section.get(key), &value) {
            (Some(toml::Value::Float(_)), toml::Value::Integer(i)) => {
                value = toml::Value::Float(*i as f64);
            }
            (Some(toml::Value::Boolean(_)), toml::Value::Integer(i @ (0 | 1))) => {
                value = toml::Value::Boolean(*i == 1);
            }
            _ => {}
        }
        section.insert(key.to_string(), value);
        let mut settings: Self = toml::Value::Table(all)
            .try_into()
            .map_err(|e: toml::de::Error| parse_error(e.message().to_string()))?;
        settings.validate()?;
        settings.loaded_mixture = self.loaded_mixture.take();
        *self = settings;
        Ok(())
    }

    /// [`Self::set`] from `key=value`.
    pub fn assign(&mut self, assignment: &str) -> Result<(), SettingsError> {
        let (key, value) = assignment
            .split_once('=')
            .ok_or_else(|| SettingsError::NotAssignment(assignment.to_string()))?;
        self.set(key.trim(), value.trim())
    }

    /// Every setting within its range.
    pub fn validate(&self) -> Result<(), SettingsError> {
        self.srt.check()?;
        self.mixture.check()?;
        self.ga.check()?;
        self.plan.check()?;
        self.gate.check()?;
        self.spatial.check()?;
        self.lights.check()?;
        self.ga.validate()?;
        self.spatial.validate()
    }

    /// The flags of every setting ([`declarations`]), for a command that renders.
    pub fn args() -> Vec<clap::Arg> {
        declarations().iter().flat_map(Setting::args).collect()
    }

    /// Sets what the flags of [`Self::args`] given on the command line (`matches`) set, in
    /// the order of the flags, and checks the result: what ties settings together
    /// (`--elitism` at most `--population`) is checked once all are read.
    pub fn read_flags(&mut self, matches: &ArgMatches) -> Result<(), SettingsError> {
        self.mixture.read_flags(matches);
        self.srt.read_flags(matches);
        self.ga.read_flags(matches);
        self.plan.read_flags(matches);
        self.gate.read_flags(matches);
        self.spatial.read_flags(matches);
        self.lights.read_flags(matches);
        self.validate()
    }

    /// Each setting's value as TOML would write it, `table.key` → value (unset options
    /// left out).
    pub fn values(&self) -> Vec<(String, String)> {
        let Ok(toml::Value::Table(all)) = toml::Value::try_from(self) else {
            unreachable!("settings serialise to a table");
        };
        let mut out = Vec::new();
        for (table, keys) in tables() {
            for key in keys {
                if let Some(v) = all.get(table).and_then(|t| t.get(key)) {
                    out.push((format!("{table}.{key}"), v.to_string()));
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_are_unique_across_tables() {
        let mut seen = std::collections::BTreeMap::new();
        for (table, keys) in tables() {
            assert!(!keys.is_empty(), "{table} lists no keys");
            for key in keys {
                if let Some(other) = seen.insert(key, table) {
                    panic!("`{key}` is in both [{other}] and [{table}]");
                }
            }
        }
        assert_eq!(table_of("test_paths"), Some("ga"));
    }

    #[test]
    fn set_reaches_every_table_and_refuses_what_none_has() {
        let mut s = Settings::default();
        s.set("test_paths", "1234").unwrap();
        s.set("ga.population", "7").unwrap();
        s.set("srt_absorption", "0.25").unwrap();
        s.set("generators", "anchors.toml").unwrap();
        s.set("anchor_shift", "1").unwrap();
        assert_eq!((s.ga.test_paths, s.ga.population), (1234, 7));
        assert_eq!(s.srt.srt_absorption, Some(0.25));
        assert_eq!(
            s.srt.nee,
            Nee::Every,
            "next-event estimation at every vertex by default"
        );
        s.set("nee", "end").unwrap();
        assert_eq!(s.srt.nee, Nee::End);
        assert!(s.set("nee", "sometimes").is_err());
        assert_eq!(s.mixture.generators, Some(PathBuf::from("anchors.toml")));
        assert_eq!(s.ga.anchor_shift, 1.0);
        let unknown = s.set("test_pathz", "1").unwrap_err().to_string();
        assert!(
            unknown.contains("unknown setting `test_pathz`"),
            "{unknown}"
        );
        assert!(unknown.contains("ga.test_paths"), "{unknown}");
        assert!(
            s.set("plan.test_paths", "1").is_err(),
            "a key in the wrong table"
        );
        assert!(s.set("population", "many").is_err());
        assert!(s.set("population", "0").is_err(), "out of range");
        assert!(s.assign("population").is_err());
        assert_eq!(s.ga.population, 7, "a refused value changes nothing");
    }

    #[test]
    fn toml_refuses_unknown_keys_and_tables() {
        let s =
            Settings::from_toml("[ga]\ntest_paths = 99\n[srt]\nsrt_absorption = 0.3", "a").unwrap();
        assert_eq!((s.ga.test_paths, s.srt.srt_absorption), (99, Some(0.3)));
        for bad in [
            "[ga]\ntest_pathz = 1",
            "[gaa]\ntest_paths = 1",
            "test_paths = 1",
        ] {
            let e = Settings::from_toml(bad, "file.toml")
                .unwrap_err()
                .to_string();
            assert!(
                e.starts_with("file.toml: ") && e.contains("unknown"),
                "{bad}: {e}"
            );
        }
    }

    #[test]
    fn flags_come_from_the_declarations_and_set_what_they_name() {
        let command = clap::Command::new("t").args(Settings::args());
        command.clone().debug_assert();
        let flags: Vec<_> = command
            .get_arguments()
            .filter_map(|a| a.get_long())
            .collect();
        for (table, keys) in tables() {
            for key in keys {
                assert!(
                    flags.contains(&key.replace('_', "-").as_str()),
                    "{table}.{key}"
                );
            }
        }
        let matches = command
            .try_get_matches_from([
                "t",
                "--population=7",
                "--ga-grid=8",
                "--no-gate",
                "--nee=end",
                "--generators=a.toml",
                "--held-out=true",
                "--footprint=0.5",
            ])
            .unwrap();
        let mut s = Settings::default();
        s.read_flags(&matches).unwrap();
        assert_eq!((s.ga.population, s.plan.grid), (7, Some(8)));
        assert!(!s.gate.gate);
        assert_eq!(s.srt.nee, Nee::End);
        assert_eq!(s.mixture.generators, Some(PathBuf::from("a.toml")));
        assert_eq!((s.ga.held_out, s.plan.footprint), (Some(true), Some(0.5)));
        let defaults = Settings::default();
        assert_eq!(
            (s.ga.generations, s.plan.prune, s.spatial.spatial_passes),
            (
                defaults.ga.generations,
                defaults.plan.prune,
                defaults.spatial.spatial_passes
            ),
            "flags not given leave their settings alone"
        );
    }

    #[test]
    fn a_range_reads_the_same_from_set_and_toml() {
        for setting in declarations() {
            let Some(range) = setting.range else { continue };
            let value = if range.hi.is_finite() {
                range.hi + 1.0
            } else {
                range.lo - 1.0
            };
            let want = format!("{} {value} is not in {range}", setting.key);
            let set = Settings::default()
                .set(setting.key, &value.to_string())
                .unwrap_err()
                .to_string();
            let toml = format!("[{}]\n{} = {value}\n", setting.table, setting.key);
            let file = Settings::from_toml(&toml, "f.toml")
                .unwrap_err()
                .to_string();
            assert!(set.ends_with(&want), "{set}");
            assert_eq!(file, format!("f.toml: {want}"));
        }
    }
}
