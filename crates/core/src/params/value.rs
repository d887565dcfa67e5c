//! The pieces the parameter table is made of: the values a parameter takes ([`ParamValue`]: a number,
//! a list of numbers, a triple, one word or a list of words), the words of an enum ([`Word`]), a
//! range ([`Range`]) and the description of one parameter ([`ParamSpec`]) that the command line, the
//! manifests, the presets and the checks all read.

use serde::{Deserialize, Deserializer};

use crate::error::{Error, Result};

/// A parameter whose value is one word out of a few, written the same on the command line, in TOML
/// and in reports.
pub trait Word: Sized + Copy + Send + Sync + 'static {
    /// Every value, in the order the help lists them.
    const ALL: &'static [Self];
    /// The value's word.
    fn word(self) -> &'static str;

    /// The value written `w`, if any.
    fn from_word(w: &str) -> Option<Self> {
        Self::ALL.iter().copied().find(|v| v.word() == w)
    }

    /// Every word, in order.
    fn words() -> Vec<&'static str> {
        Self::ALL.iter().map(|v| v.word()).collect()
    }

    /// The words, for messages: `a, b or c`.
    fn choices() -> String {
        let words = Self::words();
        match words.split_last() {
            Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
            _ => words.concat(),
        }
    }

    /// The value written `w`, or a message naming the words it could be.
    fn parse_word(w: &str) -> std::result::Result<Self, String> {
        Self::from_word(w).ok_or_else(|| format!("`{w}`: expected {}", Self::choices()))
    }
}

/// How a value is written on the command line (what the command line needs to know to parse it).
#[derive(Debug, Clone, Copy)]
pub enum ValueKind {
    /// One number.
    Number,
    /// Comma-separated numbers.
    Numbers,
    /// Three comma-separated numbers in one argument (`a,b,c`).
    Triple,
    /// One word of a list.
    Word(fn() -> Vec<&'static str>),
    /// Comma-separated words of a list.
    Words(fn() -> Vec<&'static str>),
}

/// A type a parameter can take: parsed from the command line's text, read from TOML, shown in help.
pub trait ParamValue: Sized + Clone {
    /// How it is written on the command line.
    const KIND: ValueKind;
    /// Parses one command-line argument (a list's items arrive one by one, see [`Self::from_items`]).
    fn from_items(items: &[String]) -> std::result::Result<Self, String>;
    /// Reads it from a manifest or preset (TOML through serde).
    fn deserialize_value<'de, D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error>;
    /// As written on the command line, for `--help` and the docs.
    fn show(&self) -> String;
    /// The numbers to check against the parameter's range.
    fn numbers(&self) -> Vec<f64> {
        Vec::new()
    }
}

/// A number as a person reads it: plain for everyday magnitudes, scientific beyond.
pub fn show_number(v: f64) -> String {
    if v == 0.0 || !v.is_finite() || (1e-3..1e6).contains(&v.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

pub(crate) fn one(items: &[String]) -> std::result::Result<&str, String> {
    match items {
        [s] => Ok(s.as_str()),
        _ => Err(format!("takes one value, got {}", items.len())),
    }
}

fn number(s: &str) -> std::result::Result<f64, String> {
    s.trim().parse::<f64>().map_err(|e| format!("`{s}`: {e}"))
}

impl ParamValue for f64 {
    const KIND: ValueKind = ValueKind::Number;
    fn from_items(items: &[String]) -> std::result::Result<Self, String> {
        number(one(items)?)
    }
    fn deserialize_value<'de, D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        f64::deserialize(d)
    }
    fn show(&self) -> String {
        show_number(*self)
    }
    fn numbers(&self) -> Vec<f64> {
        vec![*self]
    }
}

/// `v` with each number once, in the order first given (a window size given twice is computed once).
fn distinct(v: Vec<f64>) -> Vec<f64> {
    let mut seen = std::collections::HashSet::with_capacity(v.len());
    v.into_iter().filter(|x| seen.insert(x.to_bits())).collect()
}

impl ParamValue for Vec<f64> {
    const KIND: ValueKind = ValueKind::Numbers;
    fn from_items(items: &[String]) -> std::result::Result<Self, String> {
        items
            .iter()
            .map(|s| number(s))
            .collect::<std::result::Result<Vec<f64>, String>>()
            .map(distinct)
    }
    fn deserialize_value<'de, D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        Vec::<f64>::deserialize(d).map(distinct)
    }
    fn show(&self) -> String {
        self.iter()
            .map(|v| show_number(*v))
            .collect::<Vec<_>>()
            .join(",")
    }
    fn numbers(&self) -> Vec<f64> {
        self.clone()
    }
}

/// Parses `a,b,c` into three numbers.
pub fn triple(s: &str) -> std::result::Result<[f64; 3], String> {
    let bad = || format!("takes three comma-separated numbers, got `{s}`");
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| bad())?;
    <[f64; 3]>::try_from(v).map_err(|_| bad())
}

impl ParamValue for [f64; 3] {
    const KIND: ValueKind = ValueKind::Triple;
    fn from_items(items: &[String]) -> std::result::Result<Self, String> {
        triple(one(items)?)
    }
    fn deserialize_value<'de, D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        <[f64; 3]>::deserialize(d)
    }
    fn show(&self) -> String {
        self.map(show_number).join(",")
    }
    fn numbers(&self) -> Vec<f64> {
        self.to_vec()
    }
}

/// Implements [`ParamValue`] for enums that are [`Word`]s, one word or a list of them.
macro_rules! word_values {
    ($($t:ty),*) => {$(
        impl $crate::params::ParamValue for $t {
            const KIND: $crate::params::ValueKind = $crate::params::ValueKind::Word(<$t as $crate::params::Word>::words);
            fn from_items(items: &[String]) -> std::result::Result<Self, String> {
                <$t as $crate::params::Word>::parse_word($crate::params::value::one(items)?)
            }
            fn deserialize_value<'de, D: serde::Deserializer<'de>>(
                d: D,
            ) -> std::result::Result<Self, D::Error> {
                let w = <String as serde::Deserialize>::deserialize(d)?;
                <$t as $crate::params::Word>::parse_word(&w).map_err(serde::de::Error::custom)
            }
            fn show(&self) -> String {
                $crate::params::Word::word(*self).to_string()
            }
        }

        impl $crate::params::ParamValue for Vec<$t> {
            const KIND: $crate::params::ValueKind = $crate::params::ValueKind::Words(<$t as $crate::params::Word>::words);
            fn from_items(items: &[String]) -> std::result::Result<Self, String> {
                items.iter().map(|w| <$t as $crate::params::Word>::parse_word(w)).collect()
            }
            fn deserialize_value<'de, D: serde::Deserializer<'de>>(
                d: D,
            ) -> std::result::Result<Self, D::Error> {
                let words = <Vec<String> as serde::Deserialize>::deserialize(d)?;
                words
                    .iter()
                    .map(|w| <$t as $crate::params::Word>::parse_word(w).map_err(serde::de::Error::custom))
                    .collect()
            }
            fn show(&self) -> String {
                self.iter().map(|v| $crate::params::Word::word(*v)).collect::<Vec<_>>().join(",")
            }
        }
    )*};
}
pub(crate) use word_values;

/// serde's reader for an optional parameter (every field of [`super::Parameters`]).
pub(crate) fn de_param<'de, D: Deserializer<'de>, T: ParamValue>(
    d: D,
) -> std::result::Result<Option<T>, D::Error> {
    T::deserialize_value(d).map(Some)
}

/// One end of a range.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Bound {
    /// The value itself is allowed.
    Inclusive(f64),
    /// Only values strictly beyond it.
    Exclusive(f64),
}

impl Bound {
    /// The number at this end.
    pub fn value(self) -> f64 {
        match self {
            Bound::Inclusive(v) | Bound::Exclusive(v) => v,
        }
    }
}

/// The values a number may take; NaN and infinities never.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Range {
    pub min: Bound,
    pub max: Bound,
    /// The unit, as written after the range (`s`, `m`, or empty).
    pub unit: &'static str,
}

impl Range {
    /// Whether `v` is in range (never NaN or infinite).
    pub fn contains(&self, v: f64) -> bool {
        let above = match self.min {
            Bound::Inclusive(m) => v >= m,
            Bound::Exclusive(m) => v > m,
        };
        let below = match self.max {
            Bound::Inclusive(m) => v <= m,
            Bound::Exclusive(m) => v < m,
        };
        v.is_finite() && above && below
    }

    /// As text, e.g. `(0, 86400] s`.
    pub fn text(&self) -> String {
        let (open, lo) = match self.min {
            Bound::Inclusive(v) => ('[', v),
            Bound::Exclusive(v) => ('(', v),
        };
        let (close, hi) = match self.max {
            Bound::Inclusive(v) => (']', v),
            Bound::Exclusive(v) => (')', v),
        };
        format!(
            "{open}{}, {}{close} {}",
            show_number(lo),
            show_number(hi),
            self.unit
        )
        .trim_end()
        .to_string()
    }

    /// `v`, or the refusal naming `what` (a flag or a key), the value and the range: a usage error.
    pub fn check(&self, what: &str, v: f64) -> Result<f64> {
        if self.contains(v) {
            return Ok(v);
        }
        Err(Error::InvalidArgument(format!(
            "{what} {}: out of range; expected a finite value in {}",
            show_number(v),
            self.text()
        )))
    }
}

/// The default of a parameter, as its help states it.
#[derive(Debug, Clone, Copy)]
pub enum DefaultValue {
    /// A fixed value (shown as the command line writes it).
    Fixed(fn() -> String),
    /// None fixed: what happens when it is not given.
    Otherwise(&'static str),
}

/// One evaluation parameter, as the command line, the manifests, the presets, the checks and the docs
/// see it. Made by the table in [`super`], never by hand.
#[derive(Debug, Clone, Copy)]
pub struct ParamSpec {
    /// The manifest and preset key, and the field of [`super::Parameters`] (`max_offset`).
    pub key: &'static str,
    /// What the flag takes, e.g. `S` or `LAT,LON,H`.
    pub value_name: &'static str,
    /// The help, without its default (the table's doc comment, lines joined).
    pub doc: &'static str,
    pub default: DefaultValue,
    /// The range of every number it holds, if it holds numbers.
    pub range: Option<Range>,
    pub kind: ValueKind,
}

impl ParamSpec {
    /// The command-line flag: the key with `-` for `_` (`--max-offset`).
    pub fn flag(&self) -> String {
        format!("--{}", self.key.replace('_', "-"))
    }

    /// The default as the help ends with it: `30`, or `the first valid fix`.
    pub fn default_text(&self) -> String {
        match self.default {
            DefaultValue::Fixed(show) => show(),
            DefaultValue::Otherwise(text) => text.to_string(),
        }
    }

    /// The help, without its default.
    pub fn help(&self) -> &'static str {
        self.doc.trim()
    }

    /// The help with its default: `Largest offset searched, seconds [default: 30]`.
    pub fn help_with_default(&self) -> String {
        format!(
            "{} [default: {}]",
            self.help().trim_end_matches('.'),
            self.default_text()
        )
    }

    /// Whether a value may start with `-` (its range holds negative numbers).
    pub fn takes_negative(&self) -> bool {
        self.range.is_some_and(|r| r.min.value() < 0.0)
    }
}
