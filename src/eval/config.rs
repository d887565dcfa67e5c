//! What an evaluation is asked to do: inputs and parameters, with the paper's defaults and the rules
//! that turn user flags into the numbers the methods use.

use std::path::PathBuf;

use crate::align::auto_params::AutoParams;
use crate::align::curvature::CurvatureParams;
use crate::align::time_offset::{OffsetMethod, OffsetParams};
use crate::error::{Error, Result};
use crate::metrics::drift_error::DriftParams;
use crate::metrics::lever::LeverCorrection;
use crate::sources::text::TextOptions;
use crate::sources::StampSource;

/// The kind of robot: it sets the paper's default ε_min (about 3σ of the reference noise it expects),
/// or `Auto`: ε and the curvature Δt_max chosen from the reference's measured noise and speed
/// ([`crate::align::auto_params`]), the default.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Platform {
    /// Legged robots: ε_min 0.1 m.
    Legged,
    /// Wheeled robots: ε_min 0.3 m.
    Wheeled,
    /// Parameters from the data (the default): see [`EvalConfig::resolved`].
    #[default]
    Auto,
}

impl Platform {
    /// The paper's ε_min for this platform, metres.
    pub fn eps_min_m(self) -> f64 {
        match self {
            Platform::Legged => 0.1,
            Platform::Wheeled => 0.3,
            // Only a fallback: `evaluate` replaces it with the value measured on the reference.
            Platform::Auto => 0.1,
        }
    }

    /// Name as written in reports.
    pub fn as_str(self) -> &'static str {
        match self {
            Platform::Legged => "legged",
            Platform::Wheeled => "wheeled",
            Platform::Auto => "auto",
        }
    }
}

/// Where one trajectory comes from.
#[derive(Debug, Clone, PartialEq)]
pub enum TrajectoryInput {
    /// A topic of the recording.
    Topic(String),
    /// A text trajectory file: TUM, or any format of [`crate::sources::text`] (picked per file, see
    /// `EvalConfig::text`). The name is kept from when TUM was the only one.
    TumFile(PathBuf),
}

/// A named trajectory input.
#[derive(Debug, Clone, PartialEq)]
pub struct NamedInput {
    pub name: String,
    pub input: TrajectoryInput,
}

impl NamedInput {
    /// Parses `[NAME=]TOPIC`; the default name is the topic without its leading `/`, `:` turned into `/`.
    pub fn topic(spec: &str) -> Self {
        let (name, topic) = split_name(spec);
        let name = name.unwrap_or_else(|| topic.trim_start_matches('/').replace(':', "/"));
        NamedInput {
            name,
            input: TrajectoryInput::Topic(topic.to_string()),
        }
    }

    /// Parses `[NAME=]PATH`; the default name is the file stem.
    pub fn file(spec: &str) -> Self {
        let (name, path) = split_name(spec);
        let path = PathBuf::from(path);
        let name = name.unwrap_or_else(|| {
            path.file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default()
        });
        NamedInput {
            name,
            input: TrajectoryInput::TumFile(path),
        }
    }

    /// The topic, or the file's path, as written in reports.
    pub fn label(&self) -> String {
        match &self.input {
            TrajectoryInput::Topic(t) => t.clone(),
            TrajectoryInput::TumFile(p) => p.display().to_string(),
        }
    }
}

/// A lever arm as given (see [`crate::trajectory::extrinsics`] for the convention).
#[derive(Debug, Clone, PartialEq)]
pub enum LeverSpec {
    /// `X,Y,Z`: the sensor's position in the body frame, metres.
    Offset([f64; 3]),
    /// `tf-static:[BODY:]FRAME`: the translation of FRAME in BODY (FRAME's origin in the body frame),
    /// composed from the recording's `/tf_static` edges. BODY defaults to the evaluation's body frame:
    /// CHILD of its `/tf:PARENT:CHILD` inputs when they name one and agree; otherwise it must be
    /// written. E.g. estimate `/tf:odom:base_link` with `--reference-lever tf-static:gnss_link`: the
    /// GNSS antenna's offset in base_link.
    TfStatic { body: Option<String>, frame: String },
}

impl From<[f64; 3]> for LeverSpec {
    fn from(l: [f64; 3]) -> Self {
        LeverSpec::Offset(l)
    }
}

impl LeverSpec {
    /// Parses `X,Y,Z` or `tf-static:[BODY:]FRAME`; errors name `flag`.
    pub fn parse(flag: &str, s: &str) -> Result<LeverSpec> {
        if let Some(rest) = s.strip_prefix("tf-static:") {
            let parts: Vec<&str> = rest.split(':').collect();
            return match parts.as_slice() {
                [f] if !f.is_empty() => Ok(LeverSpec::TfStatic {
                    body: None,
                    frame: f.to_string(),
                }),
                [b, f] if !b.is_empty() && !f.is_empty() => Ok(LeverSpec::TfStatic {
                    body: Some(b.to_string()),
                    frame: f.to_string(),
                }),
                _ => Err(Error::InvalidArgument(format!(
                    "{flag} tf-static: takes a frame, or BODY:FRAME (e.g. tf-static:imu_link or tf-static:base_link:imu_link), got `{s}`"
                ))),
            };
        }
        let bad = || {
            Error::InvalidArgument(format!(
                "{flag} takes three comma-separated numbers X,Y,Z or tf-static:[BODY:]FRAME, got `{s}`"
            ))
        };
        let v: Vec<f64> = s
            .split(',')
            .map(|x| x.trim().parse::<f64>())
            .collect::<std::result::Result<_, _>>()
            .map_err(|_| bad())?;
        <[f64; 3]>::try_from(v)
            .map(LeverSpec::Offset)
            .map_err(|_| bad())
    }

    /// As written on the command line, for messages.
    pub fn describe(&self) -> String {
        match self {
            LeverSpec::Offset(l) => format!("{},{},{}", l[0], l[1], l[2]),
            LeverSpec::TfStatic { body: None, frame } => format!("tf-static:{frame}"),
            LeverSpec::TfStatic {
                body: Some(b),
                frame,
            } => format!("tf-static:{b}:{frame}"),
        }
    }
}

fn split_name(spec: &str) -> (Option<String>, &str) {
    match spec.split_once('=') {
        Some((n, rest)) if !n.is_empty() && !n.contains('/') => (Some(n.to_string()), rest),
        _ => (None, spec),
    }
}

/// A full evaluation request.
#[derive(Debug, Clone, PartialEq)]
pub struct EvalConfig {
    /// The recording (needed when any input is a topic).
    pub recording: Option<PathBuf>,
    /// Further recordings of the same mission (e.g. one ROS 1 bag per sensor group), read together
    /// with `recording` as one ([`crate::sources::mission`]); empty for a single recording.
    pub more_recordings: Vec<PathBuf>,
    pub reference: NamedInput,
    pub estimates: Vec<NamedInput>,
    pub stamp: StampSource,
    pub origin: Option<[f64; 3]>,
    pub platform: Platform,
    /// `--eps-min`: sets both ε (the paper's reading).
    pub eps_min_m: Option<f64>,
    pub curvature_eps_m: Option<f64>,
    pub path_eps_m: Option<f64>,
    pub theta_max_rad: f64,
    pub dt_max_s: f64,
    pub windows_m: Vec<f64>,
    pub overlap: f64,
    pub lever_correction: LeverCorrection,
    pub lever_arm_m: f64,
    pub offset_method: OffsetMethod,
    pub max_offset_s: f64,
    pub grid_s: f64,
    /// Skip the search and apply this offset.
    pub time_offset_s: Option<f64>,
    /// Crop on the reference clock: absolute epoch seconds, or seconds from the reference's first
    /// sample when below 1e8 (no recording is that close to 1970).
    pub t_start: Option<f64>,
    pub t_end: Option<f64>,
    /// Δt_max of the curvature signatures (time offset and the lever-arm radii), seconds; `None`:
    /// `dt_max_s` with a platform, measured with `Platform::Auto`. `dt_max_s` stays the bound on gaps
    /// and standstills.
    pub curvature_dt_max_s: Option<f64>,
    /// `--export-aligned FILE`: write each estimate, shifted onto the reference clock, as TUM
    /// (see [`super::export::aligned_path`] for the names with several estimates).
    pub export_aligned: Option<PathBuf>,
    /// How `TrajectoryInput::TumFile` inputs are read: every text format (TUM, KITTI, EuRoC, CSV), picked
    /// per file unless forced.
    pub text: TextOptions,
    /// `--reference-lever`: the reference sensor relative to the common body point (body frame, m).
    pub reference_lever: Option<LeverSpec>,
    /// `--estimate-lever [NAME=]X,Y,Z|tf-static:[BODY:]FRAME`: estimate sensors relative to the common
    /// body point; `None` as name applies to every estimate without a named one.
    pub estimate_levers: Vec<(Option<String>, LeverSpec)>,
    /// `--metrics de,ape,rpe,kitti`: which metrics each estimate gets (evo's APE/RPE on the
    /// time-aligned estimate beside Drift Error).
    pub metrics: crate::metrics::standard::in_eval::MetricSet,
    /// `--offset-model`: the clock model fitted to the offset profile; `None`: chosen from it.
    pub offset_model: Option<crate::align::clock_model::OffsetModel>,
    /// `--offset-window`/`--offset-step` of the offset profile (`None`: from the data).
    pub offset_profile: crate::align::offset_profile::ProfileParams,
    /// Keep the estimates' orientations even when no metric reads them (an output that writes
    /// poses: the annotated recording). Not a user parameter: set by the command that writes.
    pub keep_orientations: bool,
}

impl EvalConfig {
    /// A request with the paper's defaults for `reference` and `estimates`.
    pub fn new(
        recording: Option<PathBuf>,
        reference: NamedInput,
        estimates: Vec<NamedInput>,
    ) -> Self {
        EvalConfig {
            recording,
            more_recordings: Vec::new(),
            reference,
            estimates,
            stamp: StampSource::Header,
            origin: None,
            platform: Platform::Auto,
            eps_min_m: None,
            curvature_eps_m: None,
            path_eps_m: None,
            theta_max_rad: std::f64::consts::FRAC_PI_2,
            dt_max_s: 2.0,
            windows_m: vec![5.0],
            overlap: 0.0,
            lever_correction: LeverCorrection::Fit,
            lever_arm_m: 0.1,
            offset_method: OffsetMethod::Auto,
            max_offset_s: 30.0,
            grid_s: 0.001,
            time_offset_s: None,
            t_start: None,
            t_end: None,
            curvature_dt_max_s: None,
            export_aligned: None,
            text: TextOptions::default(),
            reference_lever: None,
            estimate_levers: Vec::new(),
            metrics: Default::default(),
            offset_model: None,
            offset_profile: Default::default(),
            keep_orientations: false,
        }
    }

    /// Every recording of the mission: `recording` then `more_recordings` (empty without one).
    pub fn recordings(&self) -> Vec<PathBuf> {
        self.recording
            .iter()
            .chain(&self.more_recordings)
            .cloned()
            .collect()
    }

    /// Whether any parameter is left to be measured on the reference (`Platform::Auto` and not
    /// given).
    pub fn needs_auto(&self) -> bool {
        self.platform == Platform::Auto
            && (self.curvature_eps_m.or(self.eps_min_m).is_none()
                || self.path_eps_m.or(self.eps_min_m).is_none()
                || self.curvature_dt_max_s.is_none())
    }

    /// Names of the parameters `resolved` takes from `auto` (those not given).
    pub fn auto_parameter_names(&self) -> Vec<String> {
        if self.platform != Platform::Auto {
            return Vec::new();
        }
        let mut v = Vec::new();
        if self.curvature_eps_m.or(self.eps_min_m).is_none() {
            v.push("curvature_eps_m".to_string());
        }
        if self.path_eps_m.or(self.eps_min_m).is_none() {
            v.push("path_eps_m".to_string());
        }
        if self.curvature_dt_max_s.is_none() {
            v.push("curvature_dt_max_s".to_string());
        }
        v
    }

    /// This request with every parameter left to `Platform::Auto` set from `auto` (explicit values
    /// are kept as given).
    pub fn resolved(&self, auto: &AutoParams) -> EvalConfig {
        let mut c = self.clone();
        if self.platform != Platform::Auto {
            return c;
        }
        if c.curvature_eps_m.or(c.eps_min_m).is_none() {
            c.curvature_eps_m = Some(auto.curvature_eps_m);
        }
        if c.path_eps_m.or(c.eps_min_m).is_none() {
            c.path_eps_m = Some(auto.path_eps_m);
        }
        if c.curvature_dt_max_s.is_none() {
            c.curvature_dt_max_s = Some(auto.curvature_dt_max_s);
        }
        c
    }

    /// ε for curvature: `--curvature-eps`, else `--eps-min`, else the platform's.
    pub fn curvature_eps(&self) -> f64 {
        self.curvature_eps_m
            .or(self.eps_min_m)
            .unwrap_or(self.platform.eps_min_m())
    }

    /// ε for path lengths: `--path-eps`, else `--eps-min`, else the platform's.
    pub fn path_eps(&self) -> f64 {
        self.path_eps_m
            .or(self.eps_min_m)
            .unwrap_or(self.platform.eps_min_m())
    }

    /// Eq. (1)'s parameters.
    pub fn curvature_params(&self) -> CurvatureParams {
        CurvatureParams {
            eps_m: self.curvature_eps(),
            theta_max_rad: self.theta_max_rad,
            dt_max_s: self.curvature_dt_max_s.unwrap_or(self.dt_max_s),
        }
    }

    /// The time-offset search's parameters.
    pub fn offset_params(&self) -> OffsetParams {
        OffsetParams {
            max_offset_s: self.max_offset_s,
            grid_s: self.grid_s,
            curvature: self.curvature_params(),
            max_gap_s: Some(self.dt_max_s),
            ..OffsetParams::default()
        }
    }

    /// Drift Error parameters for one window size.
    pub fn drift_params(&self, window_m: f64) -> DriftParams {
        DriftParams {
            window_m,
            overlap: self.overlap,
            path_eps_m: self.path_eps(),
            dt_max_s: self.dt_max_s,
            lever_correction: self.lever_correction,
            lever_arm_m: self.lever_arm_m,
            curvature: self.curvature_params(),
        }
    }

    /// The lever of estimate `name`: its own `NAME=` entry, else the unnamed one.
    pub fn estimate_lever(&self, name: &str) -> Option<&LeverSpec> {
        let named = self
            .estimate_levers
            .iter()
            .find(|(n, _)| n.as_deref() == Some(name));
        named
            .or_else(|| self.estimate_levers.iter().find(|(n, _)| n.is_none()))
            .map(|(_, l)| l)
    }

    /// Every file the evaluation reads: the recording, the text trajectories, KITTI times. Outputs are
    /// checked against them ([`crate::output::OutputGuard`]).
    pub fn input_paths(&self) -> Vec<PathBuf> {
        let files = std::iter::once(&self.reference)
            .chain(&self.estimates)
            .filter_map(|i| match &i.input {
                TrajectoryInput::TumFile(p) => Some(p.clone()),
                TrajectoryInput::Topic(_) => None,
            });
        self.recording
            .iter()
            .cloned()
            .chain(files)
            .chain(self.text.kitti_times.iter().cloned())
            .collect()
    }

    /// The guard every output of this evaluation is checked with.
    pub fn output_guard(&self) -> crate::output::OutputGuard {
        crate::output::OutputGuard::new(self.input_paths())
    }

    /// Refuses the outputs the library writes itself (`--export-aligned`, one file per estimate) when
    /// one would overwrite an input.
    pub fn check_outputs(&self) -> Result<()> {
        let Some(file) = &self.export_aligned else {
            return Ok(());
        };
        let guard = self.output_guard();
        for e in &self.estimates {
            let path = super::export::aligned_path(file, &e.name, self.estimates.len());
            guard.check("--export-aligned", &path)?;
        }
        Ok(())
    }

    /// Checks every value; the error says which flag is wrong and what it accepts.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(Error::InvalidArgument(m));
        if self.estimates.is_empty() {
            return bad("give at least one --estimate TOPIC or --estimate-file FILE".into());
        }
        let needs_recording = std::iter::once(&self.reference)
            .chain(&self.estimates)
            .any(|i| matches!(i.input, TrajectoryInput::Topic(_)));
        if needs_recording && self.recording.is_none() {
            return bad("a topic was given but no RECORDING; pass the recording, or use --reference-file/--estimate-file".into());
        }
        let mut names: Vec<&str> = self.estimates.iter().map(|e| e.name.as_str()).collect();
        names.sort();
        if let Some(w) = names.windows(2).find(|w| w[0] == w[1]) {
            return bad(format!(
                "two estimates are named `{}`; name them with --estimate NAME=TOPIC",
                w[0]
            ));
        }
        // Every numeric value against the one parameter table (flag, value and range in the refusal).
        super::params::validate(self)?;
        if self.windows_m.is_empty() {
            return bad("--window needs at least one size in metres".into());
        }
        if let (Some(a), Some(b)) = (self.t_start, self.t_end) {
            if a >= b {
                return bad(format!("--t-start ({a}) must be before --t-end ({b})"));
            }
        }
        for (n, _) in &self.estimate_levers {
            if let Some(n) = n {
                if !self.estimates.iter().any(|e| &e.name == n) {
                    return bad(format!(
                        "--estimate-lever names `{n}`, which is no estimate; estimates: {}",
                        self.estimates
                            .iter()
                            .map(|e| e.name.as_str())
                            .collect::<Vec<_>>()
                            .join(", ")
                    ));
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_default_to_the_topic() {
        assert_eq!(NamedInput::topic("/estimate/odom").name, "estimate/odom");
        assert_eq!(NamedInput::topic("lio=/estimate/odom").name, "lio");
        assert_eq!(
            NamedInput::topic("/tf:odom:base_link").name,
            "tf/odom/base_link"
        );
        assert_eq!(NamedInput::file("runs/est.tum").name, "est");
    }

    #[test]
    fn eps_precedence() {
        let mut c = EvalConfig::new(
            None,
            NamedInput::file("r.tum"),
            vec![NamedInput::file("e.tum")],
        );
        c.platform = Platform::Legged;
        assert_eq!(c.curvature_eps(), 0.1);
        c.platform = Platform::Wheeled;
        assert_eq!(c.path_eps(), 0.3);
        c.eps_min_m = Some(1.0);
        c.path_eps_m = Some(0.5);
        assert_eq!((c.curvature_eps(), c.path_eps()), (1.0, 0.5));
    }
}
