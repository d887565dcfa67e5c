//! The audit's result: per source its clock against the reference, lever arm, rate, gaps, coverage,
//! Drift Error and APE; every pair's offset; the closure of every triple; the clock domains. Its JSON
//! form is described by `schemas/audit.schema.json`; `restamp --audit FILE` reads it back.
//!
//! Times are absolute seconds on the reference's clock. Offsets follow the report's convention: for a
//! pair (A, B), `offset_s` maps B's stamps onto A's clock (t_B + Δt_AB = t_A); a source's `clock` is
//! its pair with the reference.

use serde::{Deserialize, Serialize};

use crate::align::clock_model::OffsetModel;
use crate::clock::ClockCorrection;
use crate::diag::Warning;
use crate::report::json::{
    OffsetProfilePoint, OffsetSegmentReport, OffsetSource, Report, TimeOffsetReport,
    TimeOffsetStatus, Tool,
};
use crate::sources::StampSource;

/// What the `kind` field of an audit says.
pub const AUDIT_KIND: &str = "trajdrift.audit";
/// Layout version of the audit JSON.
pub const AUDIT_SCHEMA_VERSION: u32 = 1;

/// The whole audit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AuditReport {
    /// Always `AUDIT_KIND` (`trajdrift.audit`).
    pub kind: String,
    pub schema_version: u32,
    pub tool: Tool,
    /// The recordings as given, and the files they hold.
    pub inputs: Vec<String>,
    pub files: Vec<String>,
    /// The reference's name (one of `sources`).
    pub reference: String,
    /// Which stamp was read (header or log); `restamp` maps the same one.
    pub stamp: StampSource,
    /// The reference first, then every other source.
    pub sources: Vec<SourceAudit>,
    /// Every pair of sources that overlap in time (the reference's pairs included).
    pub pairs: Vec<PairOffset>,
    /// Every triple whose three pairs were measured.
    pub closure: Vec<Closure>,
    /// Sources grouped by clock; the reference's domain first.
    pub domains: Vec<Domain>,
    /// Sources a curator must look at, and why.
    pub out_of_line: Vec<OutOfLine>,
    /// Warnings the user must see (exit code 3): a clock that is not constant, a failed closure, a
    /// weak offset, a truncated file.
    pub warnings: Vec<Warning>,
    /// The evaluation of every source against the reference, whole (`trajdrift eval`'s report):
    /// methods, profiles, Drift Error windows, APE and RPE.
    pub evaluation: Report,
}

/// One source.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SourceAudit {
    pub name: String,
    pub topic: String,
    #[serde(rename = "type")]
    pub type_name: String,
    /// The file the topic came from, when it came from one file of several.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub file: Option<String>,
    /// True for the reference.
    pub reference: bool,
    pub samples: usize,
    /// Median sample rate, Hz.
    pub rate_hz: Option<f64>,
    pub gaps: Gaps,
    pub coverage: Coverage,
    /// The clock against the reference (the reference's own: constant 0).
    pub clock: Clock,
    /// The sensor's position relative to the reference point, metres, in the source's body frame (x
    /// forward, y left, z up): `null` where the data cannot tell (see `lever`).
    pub lever_m: Option<[Option<f64>; 3]>,
    /// How the lever was found and how well.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub lever: Option<LeverFit>,
    /// Drift Error RMSE at the first window size, and that size (the full statistics are in
    /// `evaluation`).
    pub de_rmse: Option<f64>,
    pub de_window_m: Option<f64>,
    /// evo's APE (SE(3) alignment, translation part) RMSE on the clock-corrected source, metres.
    pub ape_rmse_m: Option<f64>,
    /// The name of its clock domain.
    pub domain: String,
}

/// Gaps in a source's stream: intervals longer than `threshold_s` (5 median periods, at least 0.5 s).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Gaps {
    pub threshold_s: f64,
    pub count: usize,
    pub longest_s: f64,
    pub total_s: f64,
}

/// When a source has data, on the reference clock (its stamps mapped by its clock).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Coverage {
    pub t_start: f64,
    pub t_end: f64,
    /// Share of the reference's span covered, gaps left out.
    pub fraction_of_reference: f64,
}

/// A clock against the reference: the model the evaluation chose, its offset and σ.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Clock {
    pub model: OffsetModel,
    /// Headline Δt (constant: the mission's; linear: at `t_mid`; piecewise: the longest segment's).
    pub offset_s: f64,
    /// Its standard error, seconds: the evaluation's σ (what every χ² and 3σ test of the audit uses).
    pub sigma_s: Option<f64>,
    /// Linear: the drift applied, ppm (> 0: the source's clock runs fast); and its σ. A pair's
    /// piecewise clock measured through the reference may carry one too, common to its segments.
    pub drift_ppm: Option<f64>,
    #[serde(default)]
    pub drift_sigma_ppm: Option<f64>,
    /// Linear (or a piecewise clock with a drift): when Δt = `offset_s`, absolute seconds.
    #[serde(default)]
    pub t_mid: Option<f64>,
    /// The least drift the windows tell from a constant clock, ppm: a `constant` clock may hide a
    /// drift below it (its σ adds a drift measured beyond 2σ but below the resolution).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub drift_resolution_ppm: Option<f64>,
    /// Constant: one segment over the overlap; piecewise: each segment; linear: none.
    pub segments: Vec<OffsetSegmentReport>,
    /// `ok`, `weak` (nothing applied, `offset_s` is the weak peak) or `given`.
    pub status: TimeOffsetStatus,
    /// The method applied (`speed`, `signed-curvature`, …), or `reference` for the reference's own.
    #[serde(default)]
    pub method: ClockMethod,
    /// The offset measured on sliding windows (for the figures).
    #[serde(default)]
    pub profile: Vec<OffsetProfilePoint>,
}

impl Clock {
    /// The reference's own clock.
    pub fn reference(t_start: f64, t_end: f64) -> Clock {
        Clock {
            model: OffsetModel::Constant,
            offset_s: 0.0,
            sigma_s: Some(0.0),
            drift_ppm: None,
            drift_sigma_ppm: None,
            t_mid: None,
            drift_resolution_ppm: None,
            segments: vec![OffsetSegmentReport {
                t_start,
                t_end,
                offset_s: 0.0,
                sigma_s: 0.0,
            }],
            status: TimeOffsetStatus::Given,
            method: ClockMethod::Reference,
            profile: Vec::new(),
        }
    }

    /// From an evaluation's time offset; a constant model gets one segment over `span`.
    pub fn from_time_offset(o: &TimeOffsetReport, span: (f64, f64)) -> Clock {
        let model = o.model.unwrap_or(OffsetModel::Constant);
        let segments = match model {
            OffsetModel::Piecewise => o.segments.clone(),
            OffsetModel::Linear => Vec::new(),
            OffsetModel::Constant => vec![OffsetSegmentReport {
                t_start: span.0,
                t_end: span.1,
                offset_s: o.offset_s,
                sigma_s: o.sigma_s.unwrap_or(f64::NAN),
            }],
        };
        Clock {
            model,
            offset_s: o.offset_s,
            sigma_s: o.sigma_s,
            drift_ppm: o.drift_ppm,
            drift_sigma_ppm: o.drift_sigma_ppm,
            t_mid: o.t_mid,
            drift_resolution_ppm: o.drift_resolution_ppm,
            segments,
            status: o.status,
            method: o.method.into(),
            profile: o.profile.clone(),
        }
    }

    /// True when the offset is one constant.
    pub fn is_constant(&self) -> bool {
        self.model == OffsetModel::Constant
    }

    /// The time offset this clock stands for, in the evaluation's own terms: what
    /// [`ClockCorrection::from_report`] turns into the one clock correction.
    pub fn time_offset(&self) -> TimeOffsetReport {
        let applied = if self.status == TimeOffsetStatus::Weak {
            0.0
        } else {
            self.offset_s
        };
        TimeOffsetReport {
            offset_s: self.offset_s,
            applied_s: applied,
            status: self.status,
            model: Some(self.model),
            drift_ppm: self.drift_ppm,
            t_mid: self.t_mid,
            sigma_s: self.sigma_s,
            segments: if self.model == OffsetModel::Piecewise {
                self.segments.clone()
            } else {
                Vec::new()
            },
            ..Default::default()
        }
    }

    /// The one clock correction ([`crate::clock`]) of this clock.
    pub fn correction(&self) -> ClockCorrection {
        let mut o = self.time_offset();
        if o.status == TimeOffsetStatus::Given {
            // A given clock is applied as the model says (the reference's is 0).
            o.status = TimeOffsetStatus::Ok;
        }
        ClockCorrection::from_report(&o)
    }

    /// Δt at `t` (absolute seconds, reference clock) and its σ there: a linear model's σ grows with
    /// the distance from `t_mid` by the drift's σ; a piecewise model's is its segment's.
    pub fn at(&self, t: f64) -> Option<(f64, f64)> {
        let sigma = self.sigma_s.unwrap_or(f64::NAN);
        match self.model {
            OffsetModel::Constant => Some((self.offset_s, sigma)),
            OffsetModel::Linear => {
                let dt = self.correction().offset_at_s(t)?;
                let grow = match (self.drift_sigma_ppm, self.t_mid) {
                    (Some(ds), Some(mid)) => ds * 1e-6 * (t - mid),
                    _ => 0.0,
                };
                Some((dt, sigma.hypot(grow)))
            }
            OffsetModel::Piecewise => {
                let n = self.segments.len();
                // A pair's clock measured through the reference may add one drift to every
                // segment ([`super::chain`]); the evaluation's piecewise clocks have none.
                let drift = match (self.drift_ppm, self.t_mid) {
                    (Some(d), Some(mid)) => -d * 1e-6 * (t - mid),
                    _ => 0.0,
                };
                self.segments
                    .iter()
                    .enumerate()
                    .find(|(i, s)| (*i == 0 || t >= s.t_start) && (i + 1 == n || t < s.t_end))
                    .map(|(_, s)| (s.offset_s + drift, s.sigma_s))
            }
        }
    }

    /// Times (absolute seconds) where the model changes: piecewise segment boundaries.
    pub fn breaks(&self) -> Vec<f64> {
        if self.model != OffsetModel::Piecewise {
            return Vec::new();
        }
        self.segments.iter().skip(1).map(|s| s.t_start).collect()
    }
}

/// Where a clock came from: the reference's own, or an evaluation's offset method (its
/// [`OffsetSource`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ClockMethod {
    Reference,
    Given,
    #[default]
    Auto,
    Speed,
    SignedCurvature,
    Curvature,
    /// `auto` refined by the pose fit.
    Pose,
}

impl From<OffsetSource> for ClockMethod {
    fn from(s: OffsetSource) -> Self {
        match s {
            OffsetSource::Given => ClockMethod::Given,
            OffsetSource::Auto => ClockMethod::Auto,
            OffsetSource::Speed => ClockMethod::Speed,
            OffsetSource::SignedCurvature => ClockMethod::SignedCurvature,
            OffsetSource::Curvature => ClockMethod::Curvature,
            OffsetSource::Pose => ClockMethod::Pose,
        }
    }
}

/// How a lever arm was found.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum LeverMethod {
    /// The evaluation's pose fit: the 3-D lever fitted together with Δt from the source's
    /// orientation, each window of the mission its own similarity to the reference's frame.
    PoseFit,
    /// From positions alone: lateral from the Drift Error's lever fit, forward from the lead of
    /// curvature over speed.
    Positions,
}

/// A lever arm fit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LeverFit {
    pub method: LeverMethod,
    /// x forward, y left, z up, metres; `null` where not observable.
    pub lever_m: [Option<f64>; 3],
    /// Their standard errors (jackknife over windows for `pose-fit`).
    pub sigma_m: [Option<f64>; 3],
    /// `pose-fit`: Δt fitted together with the lever, seconds, and its σ.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub dt_s: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub dt_sigma_s: Option<f64>,
    /// False when the path cannot separate a forward lever from Δt (a nearly constant speed: a sensor
    /// Δx ahead looks Δx/v early).
    pub forward_separable: bool,
    /// Windows used, and why the fit says what it says, in one sentence.
    #[serde(default)]
    pub windows: usize,
    pub note: String,
}

/// The offset between two sources.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PairOffset {
    /// A and B by name: `offset_s` maps B's stamps onto A's clock.
    pub a: String,
    pub b: String,
    pub clock: Clock,
    /// Seconds both have data.
    pub overlap_s: f64,
    /// How the pair was measured.
    #[serde(default)]
    pub measured: PairMeasurement,
}

/// How a pair's clock was measured.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PairMeasurement {
    /// B's stamps against A's as read (the reference's pairs, and a pair one of whose sources has no
    /// confident clock against the reference).
    #[default]
    Direct,
    /// Both sources' stamps mapped onto the reference's clock first, the residual between them
    /// measured and the two clocks added back ([`super::chain`]).
    ThroughReference,
}

/// The closure of a triple: Δt_AB + Δt_BC − Δt_AC, which is 0 when the three measurements agree.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Closure {
    pub sources: [String; 3],
    /// The residual at the piece of the mission where it is largest in units of its σ, seconds.
    pub residual_s: f64,
    pub sigma_s: f64,
    /// Σ (residual/σ)² over the pieces between clock changes, its degrees of freedom and p-value.
    pub chi2: f64,
    pub dof: usize,
    pub p_value: f64,
    /// p ≥ 0.0027 (3σ).
    pub consistent: bool,
}

/// A clock domain: sources on the same clock (within 3σ, no relative drift or step).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Domain {
    pub name: String,
    pub sources: Vec<String>,
    /// True for the reference's domain (its clock is the reference's: Δt 0 by definition).
    pub reference: bool,
    /// The domain's clock against the reference: that of its most precise member (the reference's:
    /// constant 0). `restamp` maps the domain's messages by it.
    pub clock: Clock,
}

/// Why a source is out of line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum OutOfLineReason {
    /// Its pairs break the closure of the triples it is in (and only those).
    Closure,
    /// Its measurement with one other source breaks the closure of the triples holding both (and only
    /// those): that pair's offset is off, not the source's clock.
    PairClosure,
    /// Its clock is not constant against the reference (a drift or a step).
    ClockNotConstant,
    /// No confident offset against the reference.
    WeakOffset,
}

/// A source a curator must look at.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OutOfLine {
    pub source: String,
    pub reason: OutOfLineReason,
    /// One sentence with the numbers.
    pub detail: String,
}

/// Clocks for the tests of the audit's judges (closure, chains, domains).
#[cfg(test)]
pub(crate) mod examples {
    use super::{Clock, ClockMethod};
    use crate::align::clock_model::OffsetModel;
    use crate::report::json::{OffsetSegmentReport, TimeOffsetStatus};

    /// A constant clock (no segments: a constant's value is its offset).
    pub fn constant(offset_s: f64, sigma_s: f64) -> Clock {
        Clock {
            model: OffsetModel::Constant,
            offset_s,
            sigma_s: Some(sigma_s),
            drift_ppm: None,
            drift_sigma_ppm: None,
            t_mid: None,
            drift_resolution_ppm: None,
            segments: Vec::new(),
            status: TimeOffsetStatus::Ok,
            method: ClockMethod::Pose,
            profile: Vec::new(),
        }
    }

    /// A clock stepping from `before` to `after` at `at` over [0, 1000] s.
    pub fn stepping(before: f64, after: f64, at: f64, sigma_s: f64) -> Clock {
        let seg = |t_start, t_end, offset_s| OffsetSegmentReport {
            t_start,
            t_end,
            offset_s,
            sigma_s,
        };
        Clock {
            model: OffsetModel::Piecewise,
            segments: vec![seg(0.0, at, before), seg(at, 1000.0, after)],
            ..constant(after, sigma_s)
        }
    }

    /// A clock drifting `drift_ppm` about `t_mid` (its drift's σ 0.1 ppm).
    pub fn linear(offset_s: f64, drift_ppm: f64, t_mid: f64, sigma_s: f64) -> Clock {
        Clock {
            model: OffsetModel::Linear,
            drift_ppm: Some(drift_ppm),
            drift_sigma_ppm: Some(0.1),
            t_mid: Some(t_mid),
            ..constant(offset_s, sigma_s)
        }
    }
}
