//! What an evaluation is asked to do: its inputs, and its [`Parameters`] (defined once, with their
//! defaults and ranges, in the core's parameter table), with the rules that turn them into the
//! numbers the methods use.

use std::path::PathBuf;

use crate::align::auto_params::{auto_params, AutoParams};
use crate::align::curvature::CurvatureParams;
use crate::align::time_offset::OffsetParams;
use crate::error::{Error, Result};
use crate::metrics::drift_error::DriftParams;
use crate::params::LEVER_RANGE;
pub use crate::params::{Parameters, Platform};
use crate::sources::text::TextOptions;

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

/// The most estimates one evaluation takes.
pub const MAX_ESTIMATES: usize = 256;

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
    /// Every evaluation parameter (unset ones keep their defaults).
    pub params: Parameters,
    /// Δt_max of the curvature signatures (time offset and the lever-arm radii), seconds, once
    /// measured on the reference with `Platform::Auto` ([`Self::resolved`]); `None`: `dt_max` when
    /// given or with a platform. Not a parameter: `dt_max` stays the bound on gaps and standstills.
    pub curvature_dt_max_s: Option<f64>,
    /// `--export-aligned FILE`: write each estimate, shifted onto the reference clock, as TUM
    /// (see `eval::export::aligned_path` for the names with several estimates).
    pub export_aligned: Option<PathBuf>,
    /// How `TrajectoryInput::TumFile` inputs are read: every text format (TUM, KITTI, EuRoC, CSV), picked
    /// per file unless forced.
    pub text: TextOptions,
    /// `--reference-lever`: the reference sensor relative to the common body point (body frame, m).
    pub reference_lever: Option<LeverSpec>,
    /// `--estimate-lever [NAME=]X,Y,Z|tf-static:[BODY:]FRAME`: estimate sensors relative to the common
    /// body point; `None` as name applies to every estimate without a named one.
    pub estimate_levers: Vec<(Option<String>, LeverSpec)>,
    /// Keep the estimates' orientations even when no metric reads them (an output that writes
    /// poses: the annotated recording). Not a user parameter: set by the command that writes.
    pub keep_orientations: bool,
    /// Skip the signal searches and start the pose fit at this offset, seconds, when the estimate
    /// has orientations. Not a user parameter: the audit sets it for a pair of sources already on
    /// one clock (the audit's `chain` module), whose offset is known to be near 0.
    pub start_offset_s: Option<f64>,
}

impl EvalConfig {
    /// A request with every parameter at its default for `reference` and `estimates`.
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
            params: Parameters::default(),
            curvature_dt_max_s: None,
            export_aligned: None,
            text: TextOptions::default(),
            reference_lever: None,
            estimate_levers: Vec::new(),
            keep_orientations: false,
            start_offset_s: None,
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

    /// Whether parameters are left to be measured on the reference.
    fn measures(&self) -> bool {
        self.params.platform() == Platform::Auto
    }

    /// What `--platform auto` measures on the reference (`t` seconds, its positions): its noise and
    /// speed, and the parameters they give.
    pub fn measure(&self, t: &[f64], positions: &[nalgebra::Vector3<f64>]) -> AutoParams {
        let min_window_m = self
            .params
            .windows_m()
            .into_iter()
            .fold(f64::INFINITY, f64::min);
        auto_params(t, positions, min_window_m, self.params.dt_max_s())
    }

    /// Names of the parameters `resolved` takes from the data (those not given).
    pub fn auto_parameter_names(&self) -> Vec<String> {
        if !self.measures() {
            return Vec::new();
        }
        let p = &self.params;
        let mut v = Vec::new();
        if p.curvature_eps.or(p.eps_min).is_none() {
            v.push("curvature_eps_m".to_string());
        }
        if p.path_eps.or(p.eps_min).is_none() {
            v.push("path_eps_m".to_string());
        }
        if p.dt_max.is_none() {
            v.push("curvature_dt_max_s".to_string());
        }
        v
    }

    /// This request with every parameter left to `Platform::Auto` set from `auto` (explicit values
    /// are kept as given).
    pub fn resolved(&self, auto: &AutoParams) -> EvalConfig {
        let mut c = self.clone();
        if !self.measures() {
            return c;
        }
        let p = &mut c.params;
        if p.curvature_eps.or(p.eps_min).is_none() {
            p.curvature_eps = Some(auto.curvature_eps_m);
        }
        if p.path_eps.or(p.eps_min).is_none() {
            p.path_eps = Some(auto.path_eps_m);
        }
        if p.dt_max.is_none() {
            c.curvature_dt_max_s = Some(auto.curvature_dt_max_s);
        }
        c
    }

    /// Δt_max of the curvature signatures: measured, else `dt_max`.
    pub fn curvature_dt_max(&self) -> f64 {
        self.curvature_dt_max_s
            .unwrap_or_else(|| self.params.dt_max_s())
    }

    /// Eq. (1)'s parameters.
    pub fn curvature_params(&self) -> CurvatureParams {
        CurvatureParams {
            eps_m: self.params.curvature_eps_m(),
            theta_max_rad: self.params.theta_max_rad(),
            dt_max_s: self.curvature_dt_max(),
        }
    }

    /// Whether the pose fit refines the offset: searched by `auto` with `--offset-refine pose`
    /// (it reads the estimate's orientations, where it has them).
    pub fn pose_fit(&self) -> bool {
        self.params.time_offset.is_none()
            && self.params.offset_method() == crate::align::time_offset::OffsetMethod::Auto
            && self.params.offset_refine() == crate::align::auto_offset::OffsetRefine::Pose
    }

    /// The time-offset search's parameters.
    pub fn offset_params(&self) -> OffsetParams {
        OffsetParams {
            max_offset_s: self.params.max_offset_s(),
            grid_s: self.params.grid_s(),
            curvature: self.curvature_params(),
            max_gap_s: Some(self.params.dt_max_s()),
            ..OffsetParams::default()
        }
    }

    /// Drift Error parameters for one window size.
    pub fn drift_params(&self, window_m: f64) -> DriftParams {
        DriftParams {
            window_m,
            overlap: self.params.overlap(),
            path_eps_m: self.params.path_eps_m(),
            dt_max_s: self.params.dt_max_s(),
            lever_correction: self.params.lever_correction(),
            lever_arm_m: self.params.lever_arm_m(),
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
    /// one would overwrite an input or another of them.
    pub fn check_outputs(&self) -> Result<()> {
        self.claim_outputs(&mut self.output_guard())
    }

    /// Claims the outputs the library writes itself (`--export-aligned`, one file per estimate, whose
    /// names must map to distinct file names) in `guard`, beside the command's own.
    pub fn claim_outputs(&self, guard: &mut crate::output::OutputGuard) -> Result<()> {
        let Some(file) = &self.export_aligned else {
            return Ok(());
        };
        if self.estimates.len() > 1 {
            crate::output::names::file_stems(
                "estimates",
                self.estimates.iter().map(|e| e.name.as_str()),
                "name them with --estimate NAME=TOPIC",
            )?;
        }
        for e in &self.estimates {
            let path = super::export::aligned_path(file, &e.name, self.estimates.len());
            guard.claim("--export-aligned", &path)?;
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
        if self.estimates.len() > MAX_ESTIMATES {
            return bad(format!(
                "{} estimates; at most {MAX_ESTIMATES} in one evaluation",
                self.estimates.len()
            ));
        }
        // Every value against the one parameter table (flag, value and range in the refusal).
        self.params.validate()?;
        let levers = self.estimate_levers.iter().map(|(_, l)| l);
        for l in levers.chain(self.reference_lever.as_ref()) {
            if let LeverSpec::Offset(v) = l {
                for &x in v.iter() {
                    LEVER_RANGE.check("--reference-lever/--estimate-lever", x)?;
                }
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
        c.params.platform = Some(Platform::Legged);
        assert_eq!(c.params.curvature_eps_m(), 0.1);
        c.params.platform = Some(Platform::Wheeled);
        assert_eq!(c.params.path_eps_m(), 0.3);
        c.params.eps_min = Some(1.0);
        c.params.path_eps = Some(0.5);
        assert_eq!(
            (c.params.curvature_eps_m(), c.params.path_eps_m()),
            (1.0, 0.5)
        );
    }
}
