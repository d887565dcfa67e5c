//! The evaluation parameters, defined once. The `eval` and `batch` flags (clap), the keys of a
//! manifest's `[defaults]` / `[mission.parameters]` and of a preset's `[parameters]` (serde, the flag
//! with `-` written `_`), and the words each takes all come from [`Parameters`]; every value a flag
//! takes, a manifest and a preset take. Every field is optional: an unset parameter keeps the default
//! of [`EvalConfig::new`], and layers are merged by [`Parameters::layered`] in one order: preset <
//! manifest `[defaults]` < mission < command line.

use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use serde::{Deserialize, Deserializer};

use crate::align::clock_model::{ModelChoice, OffsetModel};
use crate::align::time_offset::OffsetMethod;
use crate::error::Result;
use crate::eval::config::{EvalConfig, Platform};
use crate::metrics::lever::LeverCorrection;
use crate::metrics::standard::in_eval::{EvalMetric, MetricSet};
use crate::sources::StampSource;

/// Every evaluation parameter; `None` = not set at this layer.
#[derive(Debug, Clone, Default, PartialEq, clap::Args, Deserialize)]
#[serde(deny_unknown_fields)]
#[command(
    next_help_heading = "Evaluation parameters (also manifest and preset keys, `-` written `_`)"
)]
pub struct Parameters {
    /// Which stamp to use: header (when the sensor measured) or log (when the recorder received it)
    /// [default: header].
    #[arg(long, value_name = "WORD", value_parser = word::<StampSource>())]
    #[serde(default, deserialize_with = "opt_word")]
    pub stamp: Option<StampSource>,
    /// ENU origin for NavSatFix topics: lat,lon,h [default: the first valid fix].
    #[arg(long, value_name = "LAT,LON,H", allow_hyphen_values = true, value_parser = triple)]
    pub origin: Option<[f64; 3]>,
    /// Platform: the paper's ε_min (legged 0.1 m, wheeled 0.3 m), or auto: ε and the curvature Δt_max
    /// measured on the reference [default: auto].
    #[arg(long, value_name = "WORD", value_parser = word::<Platform>())]
    #[serde(default, deserialize_with = "opt_word")]
    pub platform: Option<Platform>,
    /// ε_min for both curvature and path length (the paper's single ε), metres.
    #[arg(long, value_name = "M")]
    pub eps_min: Option<f64>,
    /// ε for curvature, metres (over --eps-min).
    #[arg(long, value_name = "M")]
    pub curvature_eps: Option<f64>,
    /// ε for path-length decimation, metres (over --eps-min).
    #[arg(long, value_name = "M")]
    pub path_eps: Option<f64>,
    /// θ_max: turning angles above it are discontinuities, radians [default: π/2].
    #[arg(long, value_name = "RAD")]
    pub theta_max: Option<f64>,
    /// Δt_max: a chord slower than this marks a stationary robot or a gap, seconds (sets the
    /// curvature's too) [default: 2 for gaps and standstills; the curvature's from the robot's speed
    /// with --platform auto].
    #[arg(long, value_name = "S")]
    pub dt_max: Option<f64>,
    /// Drift Error window sizes, metres of reference path (comma-separated) [default: 5].
    #[arg(long, value_name = "M[,M...]", value_delimiter = ',')]
    pub window: Option<Vec<f64>>,
    /// Window overlap as a fraction in [0, 1) [default: 0].
    #[arg(long, value_name = "F")]
    pub overlap: Option<f64>,
    /// Lever-arm correction of path lengths [default: fit].
    #[arg(long, value_name = "WORD", value_parser = word::<LeverCorrection>())]
    #[serde(default, deserialize_with = "opt_word")]
    pub lever_correction: Option<LeverCorrection>,
    /// Expected lever arm a between the two sensors, metres (bound of the paper's correction)
    /// [default: 0.1].
    #[arg(long, value_name = "M")]
    pub lever_arm: Option<f64>,
    /// Time-offset method applied [default: auto].
    #[arg(long, value_name = "WORD", value_parser = word::<OffsetMethod>())]
    #[serde(default, deserialize_with = "opt_word")]
    pub offset_method: Option<OffsetMethod>,
    /// Clock model of the time offset: constant, linear (a drift), piecewise (steps), or auto (chosen
    /// from the offset profile; constant unless the data refute it) [default: auto].
    #[arg(long, value_name = "WORD", value_parser = word::<ModelChoice>())]
    #[serde(default, deserialize_with = "opt_word")]
    pub offset_model: Option<ModelChoice>,
    /// Window of the offset profile, seconds [default: a tenth of the overlap, in 20–120 s].
    #[arg(long, value_name = "S")]
    pub offset_window: Option<f64>,
    /// Step of the offset profile, seconds [default: half the window].
    #[arg(long, value_name = "S")]
    pub offset_step: Option<f64>,
    /// Largest offset searched, seconds (GPS time and UTC alone differ by 18 s) [default: 30].
    #[arg(long, value_name = "S")]
    pub max_offset: Option<f64>,
    /// Fine grid step of the offset search, seconds [default: 0.001].
    #[arg(long, value_name = "S")]
    pub grid: Option<f64>,
    /// Skip the search and apply this offset, seconds (t_est + offset = reference clock).
    #[arg(long, value_name = "S", allow_hyphen_values = true)]
    pub time_offset: Option<f64>,
    /// Crop start on the reference clock: epoch seconds, or seconds from the first reference sample.
    #[arg(long, value_name = "S", allow_hyphen_values = true)]
    pub t_start: Option<f64>,
    /// Crop end, like --t-start.
    #[arg(long, value_name = "S", allow_hyphen_values = true)]
    pub t_end: Option<f64>,
    /// Metrics beside the offset: de (Drift Error), ape (evo's APE, SE(3)), rpe (evo's RPE over 1 m
    /// and point distance), kitti (KITTI segment drift); evo's on the time-aligned estimate
    /// [default: de,ape,rpe].
    #[arg(long, value_name = "LIST", value_delimiter = ',', value_parser = word::<EvalMetric>())]
    #[serde(default, deserialize_with = "opt_words")]
    pub metrics: Option<Vec<EvalMetric>>,
}

impl Parameters {
    /// The values set in `self`, over those of `lower` (a field set in both takes `self`'s).
    pub fn over(self, lower: Parameters) -> Parameters {
        Parameters {
            stamp: self.stamp.or(lower.stamp),
            origin: self.origin.or(lower.origin),
            platform: self.platform.or(lower.platform),
            eps_min: self.eps_min.or(lower.eps_min),
            curvature_eps: self.curvature_eps.or(lower.curvature_eps),
            path_eps: self.path_eps.or(lower.path_eps),
            theta_max: self.theta_max.or(lower.theta_max),
            dt_max: self.dt_max.or(lower.dt_max),
            window: self.window.or(lower.window),
            overlap: self.overlap.or(lower.overlap),
            lever_correction: self.lever_correction.or(lower.lever_correction),
            lever_arm: self.lever_arm.or(lower.lever_arm),
            offset_method: self.offset_method.or(lower.offset_method),
            offset_model: self.offset_model.or(lower.offset_model),
            offset_window: self.offset_window.or(lower.offset_window),
            offset_step: self.offset_step.or(lower.offset_step),
            max_offset: self.max_offset.or(lower.max_offset),
            grid: self.grid.or(lower.grid),
            time_offset: self.time_offset.or(lower.time_offset),
            t_start: self.t_start.or(lower.t_start),
            t_end: self.t_end.or(lower.t_end),
            metrics: self.metrics.or(lower.metrics),
        }
    }

    /// The one merge order: `layers` from the lowest (a preset) to the highest (the command line).
    pub fn layered<'a>(layers: impl IntoIterator<Item = &'a Parameters>) -> Parameters {
        layers
            .into_iter()
            .fold(Parameters::default(), |acc, l| l.clone().over(acc))
    }

    /// Writes the set values into `c` (the others keep `c`'s).
    pub fn apply(&self, c: &mut EvalConfig) -> Result<()> {
        let set = |dst: &mut f64, v: Option<f64>| {
            if let Some(v) = v {
                *dst = v;
            }
        };
        c.stamp = self.stamp.unwrap_or(c.stamp);
        c.origin = self.origin.or(c.origin);
        c.platform = self.platform.unwrap_or(c.platform);
        c.eps_min_m = self.eps_min.or(c.eps_min_m);
        c.curvature_eps_m = self.curvature_eps.or(c.curvature_eps_m);
        c.path_eps_m = self.path_eps.or(c.path_eps_m);
        set(&mut c.theta_max_rad, self.theta_max);
        if let Some(v) = self.dt_max {
            c.dt_max_s = v;
            c.curvature_dt_max_s = Some(v);
        }
        if let Some(w) = &self.window {
            c.windows_m = w.clone();
        }
        set(&mut c.overlap, self.overlap);
        c.lever_correction = self.lever_correction.unwrap_or(c.lever_correction);
        set(&mut c.lever_arm_m, self.lever_arm);
        c.offset_method = self.offset_method.unwrap_or(c.offset_method);
        if let Some(m) = self.offset_model {
            c.offset_model = m.forced();
        }
        c.offset_profile.window_s = self.offset_window.or(c.offset_profile.window_s);
        c.offset_profile.step_s = self.offset_step.or(c.offset_profile.step_s);
        set(&mut c.max_offset_s, self.max_offset);
        set(&mut c.grid_s, self.grid);
        c.time_offset_s = self.time_offset.or(c.time_offset_s);
        c.t_start = self.t_start.or(c.t_start);
        c.t_end = self.t_end.or(c.t_end);
        if let Some(m) = &self.metrics {
            c.metrics = MetricSet::of(m);
        }
        Ok(())
    }
}

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

    /// The words, for messages: `a, b or c`.
    fn choices() -> String {
        let words: Vec<&str> = Self::ALL.iter().map(|v| v.word()).collect();
        match words.split_last() {
            Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
            _ => words.concat(),
        }
    }
}

impl Word for StampSource {
    const ALL: &'static [Self] = &[StampSource::Header, StampSource::Log];
    fn word(self) -> &'static str {
        match self {
            StampSource::Header => "header",
            StampSource::Log => "log",
        }
    }
}

impl Word for Platform {
    const ALL: &'static [Self] = &[Platform::Auto, Platform::Legged, Platform::Wheeled];
    fn word(self) -> &'static str {
        self.as_str()
    }
}

impl Word for LeverCorrection {
    const ALL: &'static [Self] = &[
        LeverCorrection::Fit,
        LeverCorrection::Paper,
        LeverCorrection::None,
    ];
    fn word(self) -> &'static str {
        self.as_str()
    }
}

impl Word for OffsetMethod {
    const ALL: &'static [Self] = &[
        OffsetMethod::Auto,
        OffsetMethod::Speed,
        OffsetMethod::SignedCurvature,
        OffsetMethod::Curvature,
    ];
    fn word(self) -> &'static str {
        self.as_str()
    }
}

/// clap's parser for a [`Word`] parameter: the possible values are listed in `--help` and in the
/// error of a wrong one.
pub fn word<T: Word>() -> impl TypedValueParser<Value = T> {
    let values = T::ALL.iter().map(|v| PossibleValue::new(v.word()));
    PossibleValuesParser::new(values).map(|w| T::from_word(&w).expect("a possible value"))
}

/// serde's reader for an optional [`Word`] parameter; an unknown word names what it accepts.
fn opt_word<'de, D: Deserializer<'de>, T: Word>(d: D) -> Result<Option<T>, D::Error> {
    let w = String::deserialize(d)?;
    T::from_word(&w)
        .map(Some)
        .ok_or_else(|| serde::de::Error::custom(format!("`{w}`: expected {}", T::choices())))
}

/// serde's reader for an optional list of [`Word`]s.
fn opt_words<'de, D: Deserializer<'de>, T: Word>(d: D) -> Result<Option<Vec<T>>, D::Error> {
    let words = Vec::<String>::deserialize(d)?;
    words
        .iter()
        .map(|w| {
            T::from_word(w).ok_or_else(|| {
                serde::de::Error::custom(format!("`{w}`: expected {}", T::choices()))
            })
        })
        .collect::<Result<Vec<T>, D::Error>>()
        .map(Some)
}

impl Word for ModelChoice {
    const ALL: &'static [Self] = &[
        ModelChoice::Auto,
        ModelChoice::Fixed(OffsetModel::Constant),
        ModelChoice::Fixed(OffsetModel::Linear),
        ModelChoice::Fixed(OffsetModel::Piecewise),
    ];
    fn word(self) -> &'static str {
        match self {
            ModelChoice::Auto => "auto",
            ModelChoice::Fixed(m) => m.as_str(),
        }
    }
}

impl Word for EvalMetric {
    const ALL: &'static [Self] = &[
        EvalMetric::De,
        EvalMetric::Ape,
        EvalMetric::Rpe,
        EvalMetric::Kitti,
    ];
    fn word(self) -> &'static str {
        match self {
            EvalMetric::De => "de",
            EvalMetric::Ape => "ape",
            EvalMetric::Rpe => "rpe",
            EvalMetric::Kitti => "kitti",
        }
    }
}

/// Parses a finite number above zero (clap's parser for durations and rates).
pub fn positive(s: &str) -> std::result::Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("takes a number above zero, got `{s}`")),
    }
}

/// Parses `a,b,c` into three numbers (clap's parser for `--origin` and other triples).
pub fn triple(s: &str) -> std::result::Result<[f64; 3], String> {
    let bad = || format!("takes three comma-separated numbers, got `{s}`");
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| bad())?;
    <[f64; 3]>::try_from(v).map_err(|_| bad())
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::{Args, Command, FromArgMatches};

    fn from_flags(flags: &[&str]) -> Parameters {
        let cmd = Parameters::augment_args(Command::new("t").allow_negative_numbers(true));
        let m = cmd
            .try_get_matches_from(std::iter::once("t").chain(flags.iter().copied()))
            .unwrap();
        Parameters::from_arg_matches(&m).unwrap()
    }

    #[test]
    fn words_parse_on_the_command_line_and_in_toml() {
        let p = from_flags(&["--offset-method", "signed-curvature", "--stamp", "log"]);
        assert_eq!(p.offset_method, Some(OffsetMethod::SignedCurvature));
        let t: Parameters =
            toml::from_str("offset_method = \"signed-curvature\"\nstamp = \"log\"").unwrap();
        assert_eq!(t, p);
        let e = toml::from_str::<Parameters>("offset_method = \"fast\"").unwrap_err();
        assert!(
            e.to_string()
                .contains("auto, speed, signed-curvature or curvature"),
            "{e}"
        );
    }

    #[test]
    fn later_layers_win_and_unset_fields_fall_through() {
        let preset = from_flags(&["--window", "5,10", "--platform", "legged"]);
        let cli = from_flags(&["--platform", "wheeled"]);
        let p = Parameters::layered([&preset, &Parameters::default(), &cli]);
        assert_eq!(p.window, Some(vec![5.0, 10.0]));
        assert_eq!(p.platform, Some(Platform::Wheeled));
    }

    /// Every numeric parameter has its range in the one table of ranges ([`crate::eval::params`]):
    /// a numeric parameter added here without a range fails.
    #[test]
    fn every_numeric_parameter_has_a_range() {
        let words = [
            "stamp",
            "platform",
            "lever_correction",
            "offset_method",
            "offset_model",
            "metrics",
        ];
        let cmd = Parameters::augment_args(Command::new("t"));
        for arg in cmd.get_arguments() {
            let id = arg.get_id().as_str();
            if words.contains(&id) {
                continue;
            }
            let key = if id == "origin" {
                "origin_latitude"
            } else {
                id
            };
            let found = crate::eval::params::PARAMS
                .iter()
                .any(|p| p.key().replace(' ', "_") == key);
            assert!(found, "--{id} has no range in src/eval/params.rs");
        }
    }

    /// `over` keeps every field: a parameter added to the struct but forgotten in `over` fails here.
    #[test]
    fn over_covers_every_parameter() {
        let cmd = Parameters::augment_args(Command::new("t"));
        for arg in cmd.get_arguments() {
            let id = arg.get_id().as_str();
            let value = match id {
                "stamp" => "log",
                "platform" => "legged",
                "lever_correction" => "paper",
                "offset_method" => "speed",
                "origin" => "1,2,3",
                "window" => "7",
                "metrics" => "kitti",
                "offset_model" => "linear",
                _ => "0.5",
            };
            let one = from_flags(&[&format!("--{}", id.replace('_', "-")), value]);
            assert_ne!(one, Parameters::default(), "{id}");
            assert_eq!(one.clone().over(Parameters::default()), one, "{id}");
            assert_eq!(Parameters::default().over(one.clone()), one, "{id}");
        }
    }
}
