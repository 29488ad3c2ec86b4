//! One declaration per setting: [`crate::settings_table!`] declares a table of settings
//! (`[ga]`, `[plan]`, …) as a struct whose every setting carries its help (its doc
//! comment), its default, its valid range and its flag's value name, and derives from that
//! one place the struct and its `Default`, its TOML (serde, unknown keys refused), the range
//! check ([`Table::check`]), the command line's flags ([`Table::args`]) and their reading
//! ([`Table::read_flags`]).
//!
//! It lives low in the tree and knows nothing of the commands, so that each table stays
//! with what it configures (the GA's in `genetic`, the spatial guide's in `integrators`).

use clap::builder::ValueParser;
use clap::parser::ValueSource;
use clap::{Arg, ArgAction, ArgMatches};
use std::error::Error;
use std::fmt;
use std::ops::{Range, RangeFrom, RangeInclusive};
use std::path::PathBuf;

/// The values a numeric setting may take: `[lo, hi]`, or `[lo, hi)` when `hi_open`. NaN is
/// in none; an infinite `hi` is in a closed interval only (`0.0..=f64::INFINITY`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval {
    pub lo: f64,
    pub hi: f64,
    pub hi_open: bool,
}

impl Interval {
    /// Whether `value` lies in the interval.
    pub fn contains(&self, value: f64) -> bool {
        value >= self.lo
            && if self.hi_open {
                value < self.hi
            } else {
                value <= self.hi
            }
    }

    /// Refuses `value`, the setting `key`'s, outside the interval (`None`: an unset option).
    pub fn check(&self, key: &'static str, value: Option<f64>) -> Result<(), OutOfRange> {
        match value {
            Some(value) if !self.contains(value) => Err(OutOfRange {
                key,
                value,
                range: *self,
            }),
            _ => Ok(()),
        }
    }
}

impl fmt::Display for Interval {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        let close = if self.hi_open { ')' } else { ']' };
        write!(f, "[{}, {}{close}", self.lo, self.hi)
    }
}

/// Whole numbers: `1..=64`.
impl From<RangeInclusive<i64>> for Interval {
    fn from(r: RangeInclusive<i64>) -> Self {
        Self {
            lo: *r.start() as f64,
            hi: *r.end() as f64,
            hi_open: false,
        }
    }
}

/// `0.0..=1.0`; `0.0..=f64::INFINITY` takes infinity too.
impl From<RangeInclusive<f64>> for Interval {
    fn from(r: RangeInclusive<f64>) -> Self {
        Self {
            lo: *r.start(),
            hi: *r.end(),
            hi_open: false,
        }
    }
}

/// `W_MIN..1.0`: the upper end left out.
impl From<Range<f64>> for Interval {
    fn from(r: Range<f64>) -> Self {
        Self {
            lo: r.start,
            hi: r.end,
            hi_open: true,
        }
    }
}

/// `0.0..`: at least the start, and finite.
impl From<RangeFrom<f64>> for Interval {
    fn from(r: RangeFrom<f64>) -> Self {
        (r.start..f64::INFINITY).into()
    }
}

/// A setting outside its declared range, wherever it was written: its flag, `--set`, a
/// sweep's method key or a `--config` file all say this.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{key} {value} is not in {range}")]
pub struct OutOfRange {
    pub key: &'static str,
    pub value: f64,
    pub range: Interval,
}

/// What a setting's type brings to its flag: the parser of its text, the flag's value name
/// and default as its help shows them, and the number its range applies to.
pub trait Kind: Sized {
    /// The flag's parser: it refuses what is not a `Self` and, for a number, what lies
    /// outside `range`, in the words of the range check of TOML and `--set`.
    fn parser(key: &'static str, range: Option<Interval>) -> ValueParser;
    /// The flag's value name where the declaration gives none (`None`: the key in capitals).
    fn value_name() -> Option<&'static str> {
        None
    }
    /// The default as the flag's help shows it (`None`: not shown).
    fn default_text(&self) -> Option<String>;
    /// The number a range applies to (`None`: an unset option, or not a number).
    fn number(&self) -> Option<f64> {
        None
    }
    /// The value the parser of the flag `id` gave.
    fn from_matches(matches: &ArgMatches, id: &str) -> Self;
}

/// The value of a flag whose parser is `Kind::parser`: clap checked its type.
fn parsed<T: Clone + Send + Sync + 'static>(matches: &ArgMatches, id: &str) -> T {
    matches
        .get_one::<T>(id)
        .cloned()
        .expect("a flag given on the command line has its parsed value")
}

/// Numbers: parsed, then checked against their range.
macro_rules! number_kind {
    ($($t:ty => $as_f64:expr),*) => {$(
        impl Kind for $t {
            fn parser(key: &'static str, range: Option<Interval>) -> ValueParser {
                ValueParser::new(
                    move |text: &str| -> Result<$t, Box<dyn Error + Send + Sync>> {
                        let value: $t = text.parse()?;
                        if let Some(range) = range {
                            range.check(key, Kind::number(&value))?;
                        }
                        Ok(value)
                    },
                )
            }
            fn default_text(&self) -> Option<String> {
                Some(self.to_string())
            }
            fn number(&self) -> Option<f64> {
                Some($as_f64(*self))
            }
            fn from_matches(matches: &ArgMatches, id: &str) -> Self {
                parsed(matches, id)
            }
        }
    )*};
}
// Settings' whole numbers are far below 2^53, where `f64` holds every integer.
number_kind!(u32 => f64::from, usize => |v| v as f64, f64 => |v| v);

/// `true` or `false`, given as the flag's value (`--gate false`).
impl Kind for bool {
    fn parser(_: &'static str, _: Option<Interval>) -> ValueParser {
        clap::value_parser!(bool)
    }
    fn value_name() -> Option<&'static str> {
        Some("BOOL")
    }
    fn default_text(&self) -> Option<String> {
        Some(self.to_string())
    }
    fn from_matches(matches: &ArgMatches, id: &str) -> Self {
        parsed(matches, id)
    }
}

impl Kind for PathBuf {
    fn parser(_: &'static str, _: Option<Interval>) -> ValueParser {
        clap::value_parser!(PathBuf)
    }
    fn default_text(&self) -> Option<String> {
        Some(self.display().to_string())
    }
    fn from_matches(matches: &ArgMatches, id: &str) -> Self {
        parsed(matches, id)
    }
}

/// An option: unset by default, its flag that of its value. Its help says what unset means.
impl<T: Kind> Kind for Option<T> {
    fn parser(key: &'static str, range: Option<Interval>) -> ValueParser {
        T::parser(key, range)
    }
    fn value_name() -> Option<&'static str> {
        T::value_name()
    }
    fn default_text(&self) -> Option<String> {
        self.as_ref().and_then(T::default_text)
    }
    fn number(&self) -> Option<f64> {
        self.as_ref().and_then(T::number)
    }
    fn from_matches(matches: &ArgMatches, id: &str) -> Self {
        Some(T::from_matches(matches, id))
    }
}

/// One setting, as its table declares it.
#[derive(Clone, Debug)]
pub struct Setting {
    /// Its table (`ga`).
    pub table: &'static str,
    /// Its one name (`test_paths`): the TOML key, the `--set` key, the flag with dashes.
    pub key: &'static str,
    /// The help heading of its table's flags.
    pub heading: &'static str,
    /// Its doc comment's first paragraph, as the short help.
    pub help: String,
    /// Its whole doc comment, where it has more than one paragraph.
    pub long_help: Option<String>,
    /// Its default as its flag's help shows it.
    pub default: Option<String>,
    /// The value name of its flag (`M`).
    pub value_name: String,
    /// The values it may take, if a number.
    pub range: Option<Interval>,
    /// The id of a flag that sets it to `false` (`no_gate` for `--no-gate`).
    pub negation: Option<&'static str>,
    parser: ValueParser,
}

impl Setting {
    /// A setting of type `T` with its default `default`; `doc`: its doc comment's lines.
    #[allow(clippy::too_many_arguments)]
    pub fn new<T: Kind>(
        (table, heading): (&'static str, &'static str),
        key: &'static str,
        doc: &[&str],
        default: &T,
        value_name: Option<&'static str>,
        range: Option<Interval>,
        negation: Option<&'static str>,
    ) -> Self {
        let (help, long_help) = help_of(doc);
        Self {
            table,
            key,
            heading,
            help,
            long_help,
            default: default.default_text(),
            value_name: value_name
                .or(T::value_name())
                .map_or_else(|| key.to_uppercase(), str::to_string),
            range,
            negation,
            parser: T::parser(key, range),
        }
    }

    /// Its flag, and the flag that negates it if any.
    pub fn args(&self) -> Vec<Arg> {
        let mut arg = Arg::new(self.key)
            .long(self.key.replace('_', "-"))
            .help(self.help.clone())
            .help_heading(self.heading)
            .value_name(self.value_name.clone())
            .value_parser(self.parser.clone())
            .action(ArgAction::Set);
        if let Some(long) = &self.long_help {
            arg = arg.long_help(long.clone());
        }
        if let Some(default) = &self.default {
            arg = arg.default_value(default.clone());
        }
        let negation = self.negation.map(|id| {
            Arg::new(id)
                .long(id.replace('_', "-"))
                .help(format!(
                    "Alias of `--{} false` (the first line of work's spelling)",
                    self.key.replace('_', "-")
                ))
                .help_heading(self.heading)
                .action(ArgAction::SetTrue)
        });
        std::iter::once(arg).chain(negation).collect()
    }
}

/// The short help (the first paragraph, its lines joined, without its final period) and the
/// long one (every paragraph, where there are several) of a doc comment's lines.
fn help_of(doc: &[&str]) -> (String, Option<String>) {
    let mut paragraphs: Vec<String> = Vec::new();
    let mut open = false;
    for line in doc.iter().map(|l| l.trim()) {
        if line.is_empty() {
            open = false;
        } else if let (true, Some(p)) = (open, paragraphs.last_mut()) {
            p.push(' ');
            p.push_str(line);
        } else {
            paragraphs.push(line.to_string());
            open = true;
        }
    }
    let first = paragraphs.first().map_or("", String::as_str);
    let short = first.strip_suffix('.').unwrap_or(first).to_string();
    let long = (paragraphs.len() > 1).then(|| paragraphs.join("\n\n"));
    (short, long)
}

/// What [`crate::settings_table!`] derives for a table.
pub trait Table: Default {
    /// The table's name in TOML (`ga`).
    const NAME: &'static str;
    /// Its settings, in the order of their flags.
    fn settings() -> Vec<Setting>;
    /// Refuses a setting outside its declared range.
    fn check(&self) -> Result<(), OutOfRange>;
    /// Sets what the flags given on the command line (`matches`) set; clap checked them.
    fn read_flags(&mut self, matches: &ArgMatches);
    /// The flags of every setting.
    fn args() -> Vec<Arg> {
        Self::settings().iter().flat_map(Setting::args).collect()
    }
    /// The settings' keys.
    fn keys() -> Vec<&'static str> {
        Self::settings().iter().map(|s| s.key).collect()
    }
}

/// Whether the flag `id` was given on the command line (not a default).
pub fn given(matches: &ArgMatches, id: &str) -> bool {
    matches.value_source(id) == Some(ValueSource::CommandLine)
}

/// The given value, else the default: `__or!(, default)` or `__or!(given, default)`.
#[doc(hidden)]
#[macro_export]
macro_rules! __settings_or {
    (, $default:expr) => {
        $default
    };
    ($given:expr, $default:expr) => {
        $given
    };
}

/// Declares a table of settings: the struct, with serde's `default` and
/// `deny_unknown_fields`, its `Default` and its [`Table`]. Each setting is a field with its
/// doc comment (the flag's help: say what it does, for users), its type and its default,
/// and optionally, in this order:
///
/// * `#[key = "ga_grid"]`: its one name where it is not the field's;
/// * `#[value_name = "PIXELS"]`: its flag's value name (else `BOOL` for a boolean, else the
///   key in capitals);
/// * `#[range = 1..=64]`: the values a number may take (see [`Interval`]'s `From`s);
/// * `#[negation = "no_gate"]`: a flag `--no-gate` that sets a boolean to `false`.
///
/// Fields after `internal:` are not settings: the code sets them (serde skips them).
///
/// ```ignore
/// settings_table! {
///     /// The gate's settings.
///     #[derive(Clone, Debug, PartialEq)]
///     pub struct GateConfig {
///         table: "gate",
///         heading: "Gate (--method ga, ga-pt)",
///         settings: {
///             /// Render with the evolved mixture only where a pilot predicts it beats pt.
///             #[negation = "no_gate"]
///             pub gate: bool = true,
///         },
///     }
/// }
/// ```
#[macro_export]
macro_rules! settings_table {
    (
        $(#[$meta:meta])*
        $vis:vis struct $name:ident {
            table: $table:literal,
            heading: $heading:literal,
            settings: {
                $(
                    $(#[doc = $doc:literal])*
                    $(#[key = $key:literal])?
                    $(#[value_name = $value_name:literal])?
                    $(#[range = $range:expr])?
                    $(#[negation = $negation:literal])?
                    $fvis:vis $field:ident: $ty:ty = $default:expr,
                )*
            },
            $(internal: {
                $(
                    $(#[$imeta:meta])*
                    $ivis:vis $ifield:ident: $ity:ty = $idefault:expr,
                )*
            },)?
        }
    ) => {
        $(#[$meta])*
        #[derive(serde::Serialize, serde::Deserialize)]
        #[serde(default, deny_unknown_fields)]
        $vis struct $name {
            $(
                $(#[doc = $doc])*
                $(#[serde(rename = $key)])?
                $fvis $field: $ty,
            )*
            $($(
                $(#[$imeta])*
                #[serde(skip)]
                $ivis $ifield: $ity,
            )*)?
        }

        impl Default for $name {
            fn default() -> Self {
                Self {
                    $($field: $default,)*
                    $($($ifield: $idefault,)*)?
                }
            }
        }

        impl $crate::settings_table::Table for $name {
            const NAME: &'static str = $table;

            fn settings() -> Vec<$crate::settings_table::Setting> {
                let defaults = Self::default();
                vec![$(
                    $crate::settings_table::Setting::new::<$ty>(
                        ($table, $heading),
                        $crate::__settings_or!($($key)?, stringify!($field)),
                        &[$($doc),*],
                        &defaults.$field,
                        $crate::__settings_or!($(Some($value_name))?, None),
                        $crate::__settings_or!(
                            $(Some($crate::settings_table::Interval::from($range)))?,
                            None
                        ),
                        $crate::__settings_or!($(Some($negation))?, None),
                    ),
                )*]
            }

            fn check(&self) -> Result<(), $crate::settings_table::OutOfRange> {
                $(
                    let _key = $crate::__settings_or!($($key)?, stringify!($field));
                    $(
                        $crate::settings_table::Interval::from($range)
                            .check(_key, $crate::settings_table::Kind::number(&self.$field))?;
                    )?
                )*
                Ok(())
            }

            fn read_flags(&mut self, matches: &clap::ArgMatches) {
                $(
                    let key = $crate::__settings_or!($($key)?, stringify!($field));
                    if $crate::settings_table::given(matches, key) {
                        self.$field = $crate::settings_table::Kind::from_matches(matches, key);
                    }
                    $(
                        if $crate::settings_table::given(matches, $negation) {
                            self.$field = false;
                        }
                    )?
                )*
            }
        }
    };
}
