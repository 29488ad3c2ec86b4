//! Every method's settings, one table per concern, with one name each.
//!
//! A setting's name is its key in its table, and that key is unique across the tables, so
//! the one name serves everywhere: the TOML of `--config FILE` (`[ga] test_paths = 4000`),
//! `--set test_paths=4000` (or `--set ga.test_paths=4000`), the flag `--test-paths` (the key
//! with dashes), the sweep's method keys (`ga:test_paths=4000`) and the JSON statistics
//! (`"ga": { "test_paths": 4000 }`). Defaults are the tables' `Default`s, in one place; a
//! key that no table has is refused wherever it is written (`deny_unknown_fields` on every
//! table, and no `flatten`, which would silently defeat it).

use crate::genetic::plan::{GateConfig, PlanConfig};
use crate::genetic::{GaConfig, GaConfigError};
use crate::path::generator::{Nee, SrtAbsorption, ABSORPTION_MAX, ABSORPTION_MIN};
use crate::path::mixture::Mixture;
use serde::de::{self, Visitor};
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
    /// The mixture of `mixture.generators`, loaded for the scene (`--method mixture`).
    #[serde(skip)]
    pub loaded_mixture: Option<Mixture>,
}

/// `srt`, the paper's stochastic ray tracing (and the defensive generator of every evolved
/// mixture).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SrtConfig {
    /// Absorption (Russian-roulette probability) of the `srt` generator at each vertex; by
    /// default (unset) with next-event estimation at every vertex none before the fifth
    /// vertex and 0.1 from it (as `pt`'s roulette), with `nee = end` the paper's 0.5 at
    /// every vertex (also for `ga-pt`'s GA, whose test paths are end-only).
    pub srt_absorption: Option<f64>,
    /// Where the mixture estimators (`srt`, `mixture`, `ga`) do next-event estimation:
    /// `every` non-delta vertex, with the balance heuristic over each generator's direction
    /// and light-point techniques, or only at the path's `end` (the paper's, for its Fig. 7).
    pub nee: Nee,
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

/// `mixture`: a mixture of path generators from a file.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MixtureConfig {
    /// The file (TOML or JSON) of `--method mixture`.
    pub generators: Option<PathBuf>,
}

/// The spatial guide: `pg`'s, and `ga-pt`'s past the vertices its GA steers.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SpatialConfig {
    /// `ga-pt`: guide the vertices past the GA's with a spatial guide (`guiding::field`), as
    /// `pg` guides every vertex. On by default: at equal time (reports at e5f1d58, 2 / 8 /
    /// 30 s) `ga-pt` had 0.32 / 0.27 / 0.27 of `pt`'s relMSE on fig5 with it and 0.33 /
    /// 0.30 / 0.31 without, fig1 0.48 / 0.43 / 0.40 against 1.00 / 1.01 / 0.99, glossy
    /// 0.33 / 0.33 / 0.43 against 1.04 / 1.03 / 1.02 and cbox 0.92 / 0.92 / 0.82 against
    /// 1.01 / 1.01 / 0.99.
    pub spatial_guide: bool,
    /// `pg`, and `ga-pt` with `spatial_guide`: passes of path tracing that train the spatial
    /// guide, pass `i` with `2^i` samples per pixel (they stay in the image). `None`: as
    /// many as `spatial_time_limit` allows if set, else as many as fit in half the samples
    /// per pixel.
    pub spatial_passes: Option<u32>,
    /// Seconds the spatial guide's training may take (see `spatial_passes`; set by the
    /// equal-time sweep, not a setting).
    #[serde(skip)]
    pub spatial_time_limit: Option<f64>,
}

impl Default for SpatialConfig {
    fn default() -> Self {
        Self {
            spatial_guide: true,
            spatial_passes: None,
            spatial_time_limit: None,
        }
    }
}

impl SpatialConfig {
    fn validate(&self) -> Result<(), SettingsError> {
        if let Some(p) = self.spatial_passes.filter(|p| !(1..=12).contains(p)) {
            return Err(SettingsError::Spatial(format!(
                "spatial_passes {p} is not in [1, 12]"
            )));
        }
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
    #[error("srt_absorption {0} is not in [{ABSORPTION_MIN}, {ABSORPTION_MAX}]")]
    SrtAbsorption(f64),
    #[error("invalid spatial guide setting: {0}")]
    Spatial(String),
}

/// The tables and their keys, in the order documentation lists them.
pub fn tables() -> Vec<(&'static str, &'static [&'static str])> {
    vec![
        ("srt", fields::<SrtConfig>()),
        ("mixture", fields::<MixtureConfig>()),
        ("ga", fields::<GaConfig>()),
        ("plan", fields::<PlanConfig>()),
        ("gate", fields::<GateConfig>()),
        ("spatial", fields::<SpatialConfig>()),
    ]
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
        .flat_map(|(t, keys)| keys.iter().map(move |k| format!("{t}.{k}")))
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
        settings.validate()?;
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
        if let Some(a) = self.srt.srt_absorption {
            if !(ABSORPTION_MIN..=ABSORPTION_MAX).contains(&a) {
                return Err(SettingsError::SrtAbsorption(a));
            }
        }
        self.ga.validate()?;
        self.plan.validate()?;
        self.spatial.validate()
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
                if let Some(v) = all.get(table).and_then(|t| t.get(*key)) {
                    out.push((format!("{table}.{key}"), v.to_string()));
                }
            }
        }
        out
    }
}

/// The field names a struct deserialises, as serde's derive lists them (skipped fields
/// left out): the deserialiser below answers nothing but that list.
fn fields<'de, T: serde::Deserialize<'de>>() -> &'static [&'static str] {
    struct Fields(std::cell::Cell<&'static [&'static str]>);
    impl<'de> de::Deserializer<'de> for &Fields {
        type Error = de::value::Error;
        fn deserialize_any<V: Visitor<'de>>(self, _: V) -> Result<V::Value, Self::Error> {
            Err(de::Error::custom("not a struct"))
        }
        fn deserialize_struct<V: Visitor<'de>>(
            self,
            _name: &'static str,
            fields: &'static [&'static str],
            _visitor: V,
        ) -> Result<V::Value, Self::Error> {
            self.0.set(fields);
            Err(de::Error::custom("fields listed"))
        }
        serde::forward_to_deserialize_any! {
            bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string bytes
            byte_buf option unit unit_struct newtype_struct seq tuple tuple_struct map enum
            identifier ignored_any
        }
    }
    let fields = Fields(std::cell::Cell::new(&[]));
    let _ = T::deserialize(&fields);
    fields.0.get()
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
                if let Some(other) = seen.insert(*key, table) {
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
}
