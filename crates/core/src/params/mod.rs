//! The evaluation parameters, defined once.
//!
//! Each parameter is one entry of the table below: its key, its type, what its flag takes, its help,
//! its default and its range. From that entry come the `eval`/`batch`/`sweep` flags (the command line
//! builds them from [`SPECS`]), the manifest and preset keys (serde, the key as written here), the
//! default every reader of [`Parameters`] gets (a getter per parameter with a fixed default), the
//! range check ([`Parameters::validate`]) and the help and man page text. A parameter is added here,
//! in one place; the algorithm that uses it reads it through its getter.
//!
//! A default written here is the algorithm's own (`OffsetParams::default().max_offset_s`), so the
//! number stands once in the code: where the algorithm defines it.
//!
//! Every field of [`Parameters`] is optional: an unset parameter keeps its default, and layers merge in
//! one order ([`Parameters::layered`]): preset < manifest `[defaults]` < mission < command line.

mod budget;
mod value;

use serde::Deserialize;

pub use budget::{check_search_size, FINE_WORK_BUDGET, MEMORY_BUDGET_BYTES, PROFILE_WORK_BUDGET_S};
use value::{de_param, word_values};
pub use value::{
    show_number, triple, Bound, DefaultValue, ParamSpec, ParamValue, Range, ValueKind, Word,
};

use crate::align::auto_offset::OffsetRefine;
use crate::align::clock_model::{ModelChoice, OffsetModel};
use crate::align::curvature::CurvatureParams;
use crate::align::offset_params::{OffsetMethod, OffsetParams, COARSE_GRID_S};
use crate::align::offset_profile::ProfileParams;
use crate::error::{Error, Result};
use crate::metrics::drift_error::DriftParams;
use crate::metrics::lever::LeverCorrection;
use crate::metrics::standard::in_eval::{EvalMetric, MetricSet};
use crate::sources::StampSource;

/// The table: one entry per parameter, `key: Type, "VALUE", (default), (range);`.
/// - default: `(default EXPR => getter)` — a fixed default and the getter that returns the value or it;
///   or `(otherwise "what happens")` — no fixed default (measured, or off).
/// - range: `(range > MIN, <= MAX, "unit")` (`>`/`>=`, `<`/`<=`) — every number the value holds is
///   checked against it; or `()`.
macro_rules! parameters {
    ($(
        $(#[doc = $doc:literal])+
        $key:ident : $ty:ty, $value_name:literal, $default:tt, $range:tt;
    )*) => {
        /// Every evaluation parameter; `None` = not set at this layer.
        #[derive(Debug, Clone, Default, PartialEq, Deserialize)]
        #[serde(deny_unknown_fields)]
        pub struct Parameters {
            $(
                $(#[doc = $doc])+
                #[serde(default, deserialize_with = "de_param")]
                pub $key: Option<$ty>,
            )*
        }

        /// Every parameter's description, in the order the help lists them.
        pub const SPECS: &[ParamSpec] = &[$(
            ParamSpec {
                key: stringify!($key),
                value_name: $value_name,
                doc: concat!($($doc),+),
                default: parameters!(@default $ty, $default),
                range: parameters!(@range $range),
                kind: <$ty as ParamValue>::KIND,
            },
        )*];

        impl Parameters {
            /// The values set in `self`, over those of `lower` (a field set in both takes `self`'s).
            pub fn over(self, lower: Parameters) -> Parameters {
                Parameters { $($key: self.$key.or(lower.$key),)* }
            }

            /// The parameters given on a command line: `given(key)` is the flag's arguments (a list's
            /// items one by one), `None` when the flag is absent. The error names the flag.
            pub fn from_flags(
                given: impl Fn(&str) -> Option<Vec<String>>,
            ) -> std::result::Result<Parameters, String> {
                Ok(Parameters {$(
                    $key: match given(stringify!($key)) {
                        Some(items) => Some(<$ty as ParamValue>::from_items(&items).map_err(|e| {
                            format!("--{}: {e}", stringify!($key).replace('_', "-"))
                        })?),
                        None => None,
                    },
                )*})
            }

            /// Every number set here against its parameter's range; the refusal names `name(key)`
            /// (the flag, or the manifest key), the value and the range.
            fn check_ranges(&self, name: &dyn Fn(&str) -> String) -> Result<()> {
                $(parameters!(@check self, name, $key, $range);)*
                Ok(())
            }

            $(parameters!(@getter $key, $ty, $default);)*
        }
    };

    (@default $ty:ty, (default $d:expr => $getter:ident)) => {
        DefaultValue::Fixed(|| <$ty as ParamValue>::show(&$d))
    };
    (@default $ty:ty, (otherwise $text:literal)) => {
        DefaultValue::Otherwise($text)
    };

    (@getter $key:ident, $ty:ty, (default $d:expr => $getter:ident)) => {
        #[doc = concat!("`", stringify!($key), "`, or its default.")]
        pub fn $getter(&self) -> $ty {
            value_or(&self.$key, || $d)
        }
    };
    (@getter $key:ident, $ty:ty, (otherwise $text:literal)) => {};

    (@range (range $lo:tt $min:expr, $hi:tt $max:expr, $unit:literal)) => {
        Some(Range {
            min: parameters!(@bound $lo $min),
            max: parameters!(@bound $hi $max),
            unit: $unit,
        })
    };
    (@range ()) => { None };
    (@bound > $v:expr) => { Bound::Exclusive($v) };
    (@bound >= $v:expr) => { Bound::Inclusive($v) };
    (@bound < $v:expr) => { Bound::Exclusive($v) };
    (@bound <= $v:expr) => { Bound::Inclusive($v) };

    (@check $self:ident, $name:ident, $key:ident, ()) => {};
    (@check $self:ident, $name:ident, $key:ident, $range:tt) => {
        if let (Some(v), Some(range)) = (&$self.$key, parameters!(@range $range)) {
            for x in ParamValue::numbers(v) {
                range.check(&$name(stringify!($key)), x)?;
            }
        }
    };
}

fn value_or<T: Clone>(v: &Option<T>, default: impl FnOnce() -> T) -> T {
    v.as_ref().cloned().unwrap_or_else(default)
}

parameters! {
    /// Which stamp to use: header (when the sensor measured) or log (when the recorder received it).
    stamp: StampSource, "WORD", (default StampSource::default() => stamp), ();
    /// ENU origin for NavSatFix topics: lat,lon,h.
    origin: [f64; 3], "LAT,LON,H", (otherwise "the first valid fix"), ();
    /// Platform: the paper's ε_min (legged 0.1 m, wheeled 0.3 m), or auto: ε and the curvature Δt_max
    /// measured on the reference.
    platform: Platform, "WORD", (default Platform::default() => platform), ();
    /// ε_min for both curvature and path length (the paper's single ε), metres.
    eps_min: f64, "M", (otherwise "by --platform"), (range > 0.0, <= 1000.0, "m");
    /// ε for curvature, metres (over --eps-min).
    curvature_eps: f64, "M", (otherwise "--eps-min"), (range > 0.0, <= 1000.0, "m");
    /// ε for path-length decimation, metres (over --eps-min).
    path_eps: f64, "M", (otherwise "--eps-min"), (range > 0.0, <= 1000.0, "m");
    /// θ_max: turning angles above it are discontinuities, radians.
    theta_max: f64, "RAD",
        (default CurvatureParams::default().theta_max_rad => theta_max_rad),
        (range > 0.0, <= std::f64::consts::PI, "rad");
    /// Δt_max: a chord slower than this marks a stationary robot or a gap, seconds (sets the
    /// curvature's too; with --platform auto the curvature's is otherwise from the robot's speed).
    dt_max: f64, "S", (default DriftParams::default().dt_max_s => dt_max_s),
        (range > 0.0, <= 86_400.0, "s");
    /// Drift Error window sizes, metres of reference path (comma-separated).
    window: Vec<f64>, "M[,M...]", (default vec![DriftParams::default().window_m] => windows_m),
        (range > 0.0, <= 1.0e6, "m");
    /// Window overlap as a fraction in [0, 1).
    overlap: f64, "F", (default DriftParams::default().overlap => overlap), (range >= 0.0, < 1.0, "");
    /// Lever-arm correction of path lengths.
    lever_correction: LeverCorrection, "WORD",
        (default DriftParams::default().lever_correction => lever_correction), ();
    /// Expected lever arm a between the two sensors, metres (bound of the paper's correction).
    lever_arm: f64, "M", (default DriftParams::default().lever_arm_m => lever_arm_m),
        (range >= 0.0, <= 100.0, "m");
    /// Time-offset method applied.
    offset_method: OffsetMethod, "WORD", (default OffsetMethod::Auto => offset_method), ();
    /// Clock model of the time offset: constant, linear (a drift), piecewise (steps), or auto (chosen
    /// from the offset profile; constant unless the data refute it).
    offset_model: ModelChoice, "WORD", (default ModelChoice::Auto => offset_model), ();
    /// How `--offset-method auto` refines its answer: pose (the pose fit, when the estimate has
    /// orientations) or none (the signal searches' answer stands).
    offset_refine: OffsetRefine, "WORD", (default OffsetRefine::default() => offset_refine), ();
    /// Window of the offset profile, seconds; at least 1 s (a shorter stretch holds no start, stop
    /// or turn to correlate).
    offset_window: f64, "S", (otherwise "a tenth of the overlap, in 20–120 s"),
        (range >= OFFSET_WINDOW_MIN_S, <= 86_400.0, "s");
    /// Step of the offset profile, seconds; at least 0.1 s (clocks drift and step over minutes, and
    /// the windows' work grows with the mission over the step: a long mission needs a longer step).
    offset_step: f64, "S", (otherwise "half the window"),
        (range >= OFFSET_STEP_MIN_S, <= 86_400.0, "s");
    /// Largest offset searched, seconds (GPS time and UTC alone differ by 18 s).
    max_offset: f64, "S", (default OffsetParams::default().max_offset_s => max_offset_s),
        (range > 0.0, <= 86_400.0, "s");
    /// Fine grid step of the offset search, seconds.
    grid: f64, "S", (default OffsetParams::default().grid_s => grid_s),
        (range >= GRID_MIN_S, <= COARSE_GRID_S, "s");
    /// Skip the search and apply this offset, seconds (t_est + offset = reference clock).
    time_offset: f64, "S", (otherwise "searched"), (range >= -1.0e10, <= 1.0e10, "s");
    /// Crop start on the reference clock: epoch seconds, or seconds from the first reference sample.
    t_start: f64, "S", (otherwise "the first sample"), (range >= -1.0e10, <= 1.0e10, "s");
    /// Crop end, like --t-start.
    t_end: f64, "S", (otherwise "the last sample"), (range >= -1.0e10, <= 1.0e10, "s");
    /// Metrics beside the offset: de (Drift Error), ape (evo's APE, SE(3)), rpe (evo's RPE over 1 m
    /// and point distance), kitti (KITTI segment drift); evo's on the time-aligned estimate.
    metrics: Vec<EvalMetric>, "LIST",
        (default vec![EvalMetric::De, EvalMetric::Ape, EvalMetric::Rpe] => metrics), ();
}

/// The finest grid step of the offset search, seconds.
pub const GRID_MIN_S: f64 = 1.0e-4;
/// The shortest window of the offset profile, seconds.
pub const OFFSET_WINDOW_MIN_S: f64 = 1.0;
/// The finest step of the offset profile, seconds.
pub const OFFSET_STEP_MIN_S: f64 = 0.1;

/// The ranges of `--origin`'s three numbers: latitude °, longitude °, ellipsoidal height m.
const ORIGIN_RANGES: [(&str, Range); 3] = [
    ("latitude", range_of(-90.0, 90.0, "°")),
    ("longitude", range_of(-180.0, 180.0, "°")),
    ("height", range_of(-1.0e4, 1.0e5, "m")),
];

/// The range of a sensor lever's components (`--reference-lever`, `--estimate-lever`), metres.
pub const LEVER_RANGE: Range = range_of(-1000.0, 1000.0, "m");

const fn range_of(min: f64, max: f64, unit: &'static str) -> Range {
    Range {
        min: Bound::Inclusive(min),
        max: Bound::Inclusive(max),
        unit,
    }
}

/// The most Drift Error window sizes one evaluation takes (duplicates are dropped first).
pub const MAX_WINDOWS: usize = 64;

impl Parameters {
    /// The one merge order: `layers` from the lowest (a preset) to the highest (the command line).
    pub fn layered<'a>(layers: impl IntoIterator<Item = &'a Parameters>) -> Parameters {
        layers
            .into_iter()
            .fold(Parameters::default(), |acc, l| l.clone().over(acc))
    }

    /// The spec of the parameter `key`.
    pub fn spec(key: &str) -> Option<&'static ParamSpec> {
        SPECS.iter().find(|s| s.key == key)
    }

    /// Checks every value set; a refusal names the flag (`--grid`), the value and the range.
    pub fn validate(&self) -> Result<()> {
        self.validate_as(&|key| format!("--{}", key.replace('_', "-")))
    }

    /// Like [`Self::validate`], naming each parameter by `name(key)` (a manifest names its key).
    pub fn validate_as(&self, name: &dyn Fn(&str) -> String) -> Result<()> {
        self.check_ranges(name)?;
        if let Some(o) = &self.origin {
            for (v, (part, range)) in o.iter().zip(ORIGIN_RANGES) {
                range.check(&format!("{} {part}", name("origin")), *v)?;
            }
        }
        if self.window.as_ref().is_some_and(|w| w.is_empty()) {
            return Err(Error::InvalidArgument(format!(
                "{} needs at least one size in metres",
                name("window")
            )));
        }
        if let Some(w) = self.window.as_ref().filter(|w| w.len() > MAX_WINDOWS) {
            return Err(Error::InvalidArgument(format!(
                "{}: {} sizes; give at most {MAX_WINDOWS} (each size is a full Drift Error pass)",
                name("window"),
                w.len()
            )));
        }
        if let (Some(a), Some(b)) = (self.t_start, self.t_end) {
            if a >= b {
                return Err(Error::InvalidArgument(format!(
                    "{} ({a}) must be before {} ({b})",
                    name("t_start"),
                    name("t_end")
                )));
            }
        }
        Ok(())
    }

    /// ε for curvature: `curvature_eps`, else `eps_min`, else the platform's.
    pub fn curvature_eps_m(&self) -> f64 {
        self.curvature_eps
            .or(self.eps_min)
            .unwrap_or(self.platform().eps_min_m())
    }

    /// ε for path lengths: `path_eps`, else `eps_min`, else the platform's.
    pub fn path_eps_m(&self) -> f64 {
        self.path_eps
            .or(self.eps_min)
            .unwrap_or(self.platform().eps_min_m())
    }

    /// The clock model forced with `offset_model`, if any.
    pub fn forced_offset_model(&self) -> Option<OffsetModel> {
        self.offset_model().forced()
    }

    /// The offset profile's window and step (`None`: from the data).
    pub fn offset_profile(&self) -> ProfileParams {
        ProfileParams {
            window_s: self.offset_window,
            step_s: self.offset_step,
        }
    }

    /// The metrics asked for.
    pub fn metric_set(&self) -> MetricSet {
        MetricSet::of(&self.metrics())
    }
}

/// The kind of robot: it sets the paper's default ε_min (about 3σ of the reference noise it expects),
/// or `Auto`: ε and the curvature Δt_max chosen from the reference's measured noise and speed
/// ([`crate::align::auto_params`]), the default.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Platform {
    /// Legged robots: ε_min 0.1 m.
    Legged,
    /// Wheeled robots: ε_min 0.3 m.
    Wheeled,
    /// Parameters from the data (the default).
    #[default]
    Auto,
}

impl Platform {
    /// The paper's ε_min for this platform, metres.
    pub fn eps_min_m(self) -> f64 {
        match self {
            Platform::Legged => 0.1,
            Platform::Wheeled => 0.3,
            // Only a fallback: the evaluation replaces it with the value measured on the reference.
            Platform::Auto => 0.1,
        }
    }
}

impl Word for Platform {
    const ALL: &'static [Self] = &[Platform::Auto, Platform::Legged, Platform::Wheeled];
    fn word(self) -> &'static str {
        match self {
            Platform::Legged => "legged",
            Platform::Wheeled => "wheeled",
            Platform::Auto => "auto",
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

impl Word for OffsetRefine {
    const ALL: &'static [Self] = &[OffsetRefine::Pose, OffsetRefine::None];
    fn word(self) -> &'static str {
        match self {
            OffsetRefine::Pose => "pose",
            OffsetRefine::None => "none",
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

word_values!(
    StampSource,
    Platform,
    LeverCorrection,
    OffsetMethod,
    ModelChoice,
    OffsetRefine,
    EvalMetric
);

#[cfg(test)]
mod tests {
    use super::*;

    fn flags(pairs: &[(&str, &[&str])]) -> Parameters {
        Parameters::from_flags(|key| {
            pairs
                .iter()
                .find(|(k, _)| *k == key)
                .map(|(_, v)| v.iter().map(|s| s.to_string()).collect())
        })
        .unwrap()
    }

    #[test]
    fn words_parse_on_the_command_line_and_in_toml() {
        let p = flags(&[
            ("offset_method", &["signed-curvature"]),
            ("stamp", &["log"]),
        ]);
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
        let preset = flags(&[("window", &["5", "10"]), ("platform", &["legged"])]);
        let cli = flags(&[("platform", &["wheeled"])]);
        let p = Parameters::layered([&preset, &Parameters::default(), &cli]);
        assert_eq!(p.window, Some(vec![5.0, 10.0]));
        assert_eq!(p.platform, Some(Platform::Wheeled));
    }

    /// An example value for every parameter, as the command line writes it.
    fn example(spec: &ParamSpec) -> Vec<String> {
        let v: &[&str] = match spec.kind {
            ValueKind::Number => &["0.5"],
            ValueKind::Numbers => &["7", "9"],
            ValueKind::Triple => &["1,2,3"],
            ValueKind::Word(_) | ValueKind::Words(_) => &[],
        };
        if let ValueKind::Word(words) | ValueKind::Words(words) = spec.kind {
            return vec![words().last().unwrap().to_string()];
        }
        v.iter().map(|s| s.to_string()).collect()
    }

    /// `over`, `from_flags` and the table cover every field: each parameter set alone survives both
    /// merge orders.
    #[test]
    fn every_parameter_parses_and_merges() {
        for spec in SPECS {
            let value = example(spec);
            let one = Parameters::from_flags(|k| (k == spec.key).then(|| value.clone())).unwrap();
            assert_ne!(one, Parameters::default(), "{}", spec.key);
            assert_eq!(one.clone().over(Parameters::default()), one, "{}", spec.key);
            assert_eq!(Parameters::default().over(one.clone()), one, "{}", spec.key);
        }
    }

    #[test]
    fn every_default_is_in_its_range_and_nan_inf_are_not() {
        let defaults = Parameters::default();
        let all = Parameters {
            theta_max: Some(defaults.theta_max_rad()),
            dt_max: Some(defaults.dt_max_s()),
            window: Some(defaults.windows_m()),
            overlap: Some(defaults.overlap()),
            lever_arm: Some(defaults.lever_arm_m()),
            max_offset: Some(defaults.max_offset_s()),
            grid: Some(defaults.grid_s()),
            ..Default::default()
        };
        all.validate().unwrap();
        for spec in SPECS {
            let Some(r) = spec.range else { continue };
            for v in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                assert!(!r.contains(v), "{} {v}", spec.key);
            }
        }
    }

    #[test]
    fn refusal_names_flag_value_and_range() {
        let p = Parameters {
            grid: Some(1e-9),
            ..Default::default()
        };
        let e = p.validate().unwrap_err().to_string();
        assert!(
            e.contains("--grid 1e-9") && e.contains("[1e-4, 0.02] s"),
            "{e}"
        );
        let p = Parameters {
            overlap: Some(1.0),
            ..Default::default()
        };
        let e = p
            .validate_as(&|k| format!("`{k}`"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("`overlap` 1") && e.contains("[0, 1)"), "{e}");
    }

    #[test]
    fn help_states_each_default_once() {
        let s = Parameters::spec("max_offset").unwrap();
        assert_eq!(s.flag(), "--max-offset");
        assert!(
            s.help_with_default().ends_with("[default: 30]"),
            "{}",
            s.help_with_default()
        );
        assert_eq!(Parameters::spec("window").unwrap().default_text(), "5");
        assert_eq!(
            Parameters::spec("metrics").unwrap().default_text(),
            "de,ape,rpe"
        );
    }
}
