//! The JSON report: the machine-readable result of an evaluation, with every parameter beside it.
//!
//! `schema_version` is bumped on any breaking change; `schemas/report.schema.json` describes it. Times in
//! `per_window` and `excluded_intervals` are absolute seconds on the reference clock.

use serde::{Deserialize, Serialize};

use crate::trajectory::rows::RowAudit;

use crate::align::time_offset::OffsetMethod;
use crate::diag::Warning;
use crate::metrics::drift_error::DriftWindow;
use crate::metrics::lever::LeverCorrection;
use crate::params::Platform;
use crate::sources::StampSource;

/// Current report layout version.
pub const SCHEMA_VERSION: u32 = 1;

/// The whole report.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Report {
    pub schema_version: u32,
    pub tool: Tool,
    pub input: Input,
    pub parameters: Parameters,
    pub reference: TopicReport,
    pub estimates: Vec<EstimateReport>,
    /// Warnings the user must see (exit code 3).
    pub warnings: Vec<Warning>,
}

/// Which program wrote the report.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Tool {
    pub name: String,
    pub version: String,
}

impl Default for Tool {
    fn default() -> Self {
        Tool {
            name: "trajdrift".into(),
            version: env!("CARGO_PKG_VERSION").into(),
        }
    }
}

/// The evaluated input.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Input {
    /// The recording (or the reference text file when there is no recording).
    pub path: String,
    pub bytes: u64,
}

/// Every parameter that shaped the numbers.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Parameters {
    pub platform: Platform,
    pub curvature_eps_m: f64,
    pub path_eps_m: f64,
    pub theta_max_rad: f64,
    pub dt_max_s: f64,
    pub windows_m: Vec<f64>,
    pub overlap: f64,
    pub lever_arm_m: f64,
    pub lever_correction: LeverCorrection,
    pub max_offset_s: f64,
    pub grid_s: f64,
    pub offset_method: OffsetMethod,
    /// The offset given with `--time-offset`, if any.
    pub time_offset_s: Option<f64>,
    pub stamp: StampSource,
    pub origin: Option<[f64; 3]>,
    /// The crop, absolute seconds on the reference clock.
    pub t_start: Option<f64>,
    pub t_end: Option<f64>,
    /// Δt_max of the curvature signatures, seconds (`dt_max_s` bounds gaps and standstills).
    #[serde(default)]
    pub curvature_dt_max_s: Option<f64>,
    /// σ of the reference's white position noise, measured, metres.
    #[serde(default)]
    pub reference_noise_m: Option<f64>,
    /// What `--platform auto` chose and from what (absent with a platform).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub auto: Option<AutoParameters>,
}

/// The parameters measured on the reference (`--platform auto`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AutoParameters {
    /// The parameters taken from the data (the others were given).
    pub chosen: Vec<String>,
    /// σ they came from, metres.
    pub reference_noise_m: Option<f64>,
    /// Mean and 10th percentile of the reference's speed while moving, m/s.
    pub mean_speed_mps: Option<f64>,
    pub slow_speed_mps: Option<f64>,
    /// The rules, in words.
    pub rules: String,
}

/// The reference side.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TopicReport {
    /// Topic, or the text file it came from.
    pub topic: String,
    #[serde(rename = "type")]
    pub type_name: String,
    pub samples: usize,
    /// ENU origin of a geodetic (NavSatFix) topic: latitude °, longitude °, height m.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub geodetic_origin: Option<[f64; 3]>,
    /// Samples dropped as invalid (NO_FIX, NaN) or with a repeated stamp.
    pub dropped_samples: u64,
    /// Rows read, dropped per reason, stamps going back.
    #[serde(default)]
    pub rows: RowAudit,
}

/// One estimate's results.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EstimateReport {
    pub name: String,
    pub topic: String,
    #[serde(rename = "type")]
    pub type_name: String,
    pub samples: usize,
    pub dropped_samples: u64,
    /// Rows read, dropped per reason, stamps going back.
    #[serde(default)]
    pub rows: RowAudit,
    pub time_offset: TimeOffsetReport,
    pub drift_error: Vec<DriftErrorReport>,
    /// Known extrinsics applied (`--estimate-lever`/`--reference-lever`): the estimate was moved onto
    /// the reference's body point before curvature, alignment and Drift Error.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub extrinsics: Option<ExtrinsicsReport>,
    /// evo's APE/RPE (and KITTI drift) on the time-aligned estimate (`--metrics`).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub standard_metrics: Option<crate::metrics::standard::in_eval::StandardMetrics>,
}

/// The lever arms used to move an estimate onto the reference's point of the body.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ExtrinsicsReport {
    /// Estimate sensor relative to the common body point, body frame, metres (0 when not given).
    pub estimate_lever_m: [f64; 3],
    /// Reference sensor relative to the common body point, body frame, metres (0 when not given).
    pub reference_lever_m: [f64; 3],
    /// `estimate − reference`: every estimate position p became p − R·moved_by_body_m.
    pub moved_by_body_m: [f64; 3],
    /// What used the moved trajectory: `curvature, time_offset, drift_error`.
    pub applied_before: String,
}

/// The clock offset: what each method found and what was applied.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct TimeOffsetReport {
    /// The method whose answer is reported (`given` when `--time-offset` was used).
    pub method: OffsetSource,
    /// Its offset, seconds (t_est + offset = reference clock).
    pub offset_s: f64,
    /// The offset applied before Drift Error (0 when the search was weak and none was given).
    pub applied_s: f64,
    pub correlation: Option<f64>,
    pub confidence: Option<f64>,
    /// `ok`, `weak` or `given`.
    pub status: TimeOffsetStatus,
    /// Every method that ran.
    pub methods: Vec<OffsetMethodReport>,
    /// Why this answer was applied (or none).
    #[serde(default)]
    pub reason: Option<String>,
    /// v·(Δt_signed-curvature − Δt_speed) when both were confident and disagreed, metres.
    #[serde(default)]
    pub implied_lever_arm_m: Option<f64>,
    /// The drift of a linear fit over the offset profile, ppm (positive: the estimate's clock runs
    /// fast, Δt shrinks with time), and its standard error (see [`crate::align::clock_model`]).
    #[serde(default)]
    pub drift_measured_ppm: Option<f64>,
    #[serde(default)]
    pub drift_sigma_ppm: Option<f64>,
    /// The drift applied: set only when `model` is `linear`.
    #[serde(default)]
    pub drift_ppm: Option<f64>,
    /// Linear: the reference time (absolute seconds) at which `offset_s` holds, so that
    /// Δt(t) = offset_s − drift_ppm·10⁻⁶·(t − t_mid).
    #[serde(default)]
    pub t_mid: Option<f64>,
    /// The smallest drift the mission resolves, ppm: a drift below it is not declared
    /// ([`crate::align::clock_model::ClockModel::drift_resolution_ppm`]).
    #[serde(default)]
    pub drift_resolution_ppm: Option<f64>,
    /// The clock model applied to the estimate's stamps (`constant`, `linear`, `piecewise`).
    #[serde(default)]
    pub model: Option<crate::align::clock_model::OffsetModel>,
    /// Why that model, in one sentence.
    #[serde(default)]
    pub model_reason: Option<String>,
    /// Standard error of the headline `offset_s`, seconds (constant: the whole mission's; linear: at
    /// the profile's mid-time; piecewise: the longest segment's).
    #[serde(default)]
    pub sigma_s: Option<f64>,
    /// What the pose fit's headline σ was made of: the final fit's jackknife and formal σ, the
    /// profile windows' σ for the same parameter, a hidden drift, and how they were combined
    /// ([`crate::align::pose_model::SigmaParts`]). Absent when the pose fit did not give the σ.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sigma_parts: Option<crate::align::pose_model::SigmaParts>,
    /// Piecewise: the segments of constant offset, absolute seconds on the reference clock.
    #[serde(default)]
    pub segments: Vec<OffsetSegmentReport>,
    /// The offset profile: Δt over sliding windows, window centres absolute seconds on the reference
    /// clock.
    #[serde(default)]
    pub profile: Vec<OffsetProfilePoint>,
    /// Window and step of the profile, seconds.
    #[serde(default)]
    pub profile_window_s: Option<f64>,
    #[serde(default)]
    pub profile_step_s: Option<f64>,
    /// The pose fit's lever: the estimate's sensor relative to the reference's point, in the
    /// estimate's body frame (x forward, y left, z up), metres, fitted alongside Δt; and its σ (the
    /// jackknife over windows). Absent when the pose fit did not run.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fitted_lever_m: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fitted_lever_sigma_m: Option<[f64; 3]>,
    /// Whether the pose fit could tell a forward lever from Δt (false at a nearly constant speed,
    /// where a sensor Δx ahead looks Δx/v early: Δt's variance grew beyond
    /// [`crate::align::pose_fit::INSEPARABLE_VIF`] times when the lever was fitted). Absent when
    /// the pose fit did not run.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fitted_forward_separable: Option<bool>,
}

/// Whether the applied clock offset can be trusted.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TimeOffsetStatus {
    /// A confident search: the offset (and its clock model) was applied.
    Ok,
    /// No confident peak: nothing was applied (`applied_s` 0), a warning says so.
    #[default]
    Weak,
    /// Given with `--time-offset`: applied as given, not searched.
    Given,
}

impl TimeOffsetStatus {
    /// As written in the report.
    pub fn as_str(self) -> &'static str {
        match self {
            TimeOffsetStatus::Ok => "ok",
            TimeOffsetStatus::Weak => "weak",
            TimeOffsetStatus::Given => "given",
        }
    }
}

/// How one search method fared.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MethodStatus {
    /// A clear, unique peak.
    Ok,
    /// A flat or ambiguous peak.
    Weak,
    /// The method could not run on these data (`error` says why).
    Failed,
}

impl MethodStatus {
    /// As written in the report.
    pub fn as_str(self) -> &'static str {
        match self {
            MethodStatus::Ok => "ok",
            MethodStatus::Weak => "weak",
            MethodStatus::Failed => "failed",
        }
    }
}

impl From<crate::align::time_offset::OffsetStatus> for MethodStatus {
    fn from(s: crate::align::time_offset::OffsetStatus) -> Self {
        match s {
            crate::align::time_offset::OffsetStatus::Ok => MethodStatus::Ok,
            crate::align::time_offset::OffsetStatus::Weak => MethodStatus::Weak,
        }
    }
}

/// Where a reported offset came from: a search method, or the user (`given`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum OffsetSource {
    /// `--time-offset`.
    Given,
    #[default]
    Auto,
    Speed,
    SignedCurvature,
    Curvature,
    /// `auto`'s answer refined by the pose fit (see [`crate::align::pose_fit`]).
    Pose,
}

impl From<OffsetMethod> for OffsetSource {
    fn from(m: OffsetMethod) -> Self {
        match m {
            OffsetMethod::Auto => OffsetSource::Auto,
            OffsetMethod::Speed => OffsetSource::Speed,
            OffsetMethod::SignedCurvature => OffsetSource::SignedCurvature,
            OffsetMethod::Curvature => OffsetSource::Curvature,
            OffsetMethod::Pose => OffsetSource::Pose,
        }
    }
}

impl OffsetSource {
    /// As written in the report.
    pub fn as_str(self) -> &'static str {
        self.method().map_or("given", |m| m.as_str())
    }

    /// The search method, unless the offset was given.
    pub fn method(self) -> Option<OffsetMethod> {
        match self {
            OffsetSource::Given => None,
            OffsetSource::Auto => Some(OffsetMethod::Auto),
            OffsetSource::Speed => Some(OffsetMethod::Speed),
            OffsetSource::SignedCurvature => Some(OffsetMethod::SignedCurvature),
            OffsetSource::Curvature => Some(OffsetMethod::Curvature),
            OffsetSource::Pose => Some(OffsetMethod::Pose),
        }
    }
}

/// The words of the typed statuses, as the report writes them.
macro_rules! display_as_str {
    ($($t:ty),*) => {$(
        impl std::fmt::Display for $t {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.pad(self.as_str())
            }
        }
    )*};
}
display_as_str!(TimeOffsetStatus, MethodStatus, OffsetSource);

/// One segment of a piecewise clock model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OffsetSegmentReport {
    pub t_start: f64,
    pub t_end: f64,
    pub offset_s: f64,
    pub sigma_s: f64,
}

/// One window of the offset profile.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OffsetProfilePoint {
    pub t: f64,
    pub offset_s: f64,
    pub sigma_s: f64,
    pub correlation: f64,
}

/// One time-offset method's answer.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OffsetMethodReport {
    pub method: OffsetMethod,
    pub offset_s: Option<f64>,
    pub correlation: Option<f64>,
    pub confidence: Option<f64>,
    /// `ok`, `weak`, or `failed` (then `error` says why).
    pub status: MethodStatus,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub error: Option<String>,
    /// ρ − ρ₂: the peak over the best NCC outside its main lobe.
    #[serde(default)]
    pub margin: Option<f64>,
    /// Share of the overlap where both signals are defined.
    #[serde(default)]
    pub defined_fraction: Option<f64>,
}

/// Drift Error at one window size.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DriftErrorReport {
    pub window_m: f64,
    pub lever_correction: LeverCorrection,
    pub windows: usize,
    pub dropped_windows: usize,
    pub rmse: Option<f64>,
    pub mean: Option<f64>,
    pub median: Option<f64>,
    pub std: Option<f64>,
    pub q1: Option<f64>,
    pub q3: Option<f64>,
    pub p95: Option<f64>,
    pub min: Option<f64>,
    pub max: Option<f64>,
    /// Share of samples skipped by the ε-decimation of path lengths.
    pub discarded_fraction: f64,
    /// Rotation in place (the reference still, the estimate sweeping an arc): excluded, [start, end] s.
    pub excluded_intervals: Vec<[f64; 2]>,
    pub per_window: Vec<DriftWindow>,
    /// `fit` correction only: the fitted path scale s of L_est = s·(L_ref − d·Δψ) (1.02 = estimate 2 %
    /// long); null for other corrections.
    #[serde(default)]
    pub scale: Option<f64>,
    /// `fit` correction only: the fitted lateral lever arm d, metres; > 0 = the estimate sensor to the
    /// LEFT of the reference point (body x forward, y left, z up); 0 when the windows turn too little to
    /// tell; null for other corrections.
    #[serde(default)]
    pub lateral_lever_m: Option<f64>,
}
