//! The clock correction applied to an estimate's stamps, as the report states it.
//!
//! Drift Error, `--export-aligned` and the annotated recording's aligned channel all move the
//! estimate's stamps onto the reference clock, and must agree to the nanosecond. So the correction is
//! built from the report's own numbers (`applied_s`, `model`, `drift_ppm`, `t_mid`, `segments`:
//! absolute seconds) and applied in integer nanoseconds on the absolute clocks, with no time origin
//! that one of them could choose differently: a reader of the JSON report can redo it exactly.

use crate::align::clock_model::OffsetModel;
use crate::metrics::standard::poses::Poses;
use crate::report::json::{TimeOffsetReport, TimeOffsetStatus};
use crate::trajectory::Trajectory;

/// How an estimate's stamps move onto the reference clock.
#[derive(Debug, Clone, PartialEq)]
pub enum ClockCorrection {
    /// Every stamp by Δt_ns = round(applied_s·10⁹).
    Constant { dt_ns: i64 },
    /// Δt(t) = offset_s − drift_ppm·10⁻⁶·(t − t_mid), t on the reference clock.
    Linear {
        offset_s: f64,
        drift_ppm: f64,
        t_mid_ns: i64,
    },
    /// A constant offset per segment [t_start, t_end) of the reference clock (the first and the last
    /// open-ended); a stamp no segment takes (a backward step repeated it) maps nowhere.
    Piecewise { segments: Vec<(i64, i64, f64)> },
}

/// Seconds to whole nanoseconds.
fn ns(seconds: f64) -> i64 {
    (seconds * 1e9).round() as i64
}

impl ClockCorrection {
    /// The correction the report applied: its clock model when the search was confident and chose a
    /// linear or piecewise one, else the constant `applied_s`.
    pub fn from_report(o: &TimeOffsetReport) -> ClockCorrection {
        let constant = ClockCorrection::Constant {
            dt_ns: ns(o.applied_s),
        };
        if o.status != TimeOffsetStatus::Ok {
            return constant;
        }
        match (o.model, o.drift_ppm, o.t_mid) {
            (Some(OffsetModel::Linear), Some(drift_ppm), Some(t_mid)) => ClockCorrection::Linear {
                offset_s: o.offset_s,
                drift_ppm,
                t_mid_ns: ns(t_mid),
            },
            (Some(OffsetModel::Piecewise), ..) if !o.segments.is_empty() => {
                ClockCorrection::Piecewise {
                    segments: o
                        .segments
                        .iter()
                        .map(|s| (ns(s.t_start), ns(s.t_end), s.offset_s))
                        .collect(),
                }
            }
            _ => constant,
        }
    }

    /// Where the estimate stamp `stamp` (ns) lands on the reference clock; `None` where no segment of
    /// a piecewise model takes it, or out of the i64 range.
    pub fn stamp(&self, stamp: i64) -> Option<i64> {
        match self {
            ClockCorrection::Constant { dt_ns } => stamp.checked_add(*dt_ns),
            ClockCorrection::Linear {
                offset_s,
                drift_ppm,
                t_mid_ns,
            } => {
                // One fixed-point step: Δt varies by ppm·10⁻⁶ of a second per second.
                let t = stamp.checked_add(ns(*offset_s))?;
                let dt = offset_s - drift_ppm * 1e-6 * (t - t_mid_ns) as f64 * 1e-9;
                stamp.checked_add(ns(dt))
            }
            ClockCorrection::Piecewise { segments } => {
                let n = segments.len();
                segments
                    .iter()
                    .enumerate()
                    .find_map(|(i, &(start, end, offset_s))| {
                        let t = stamp.checked_add(ns(offset_s))?;
                        let after_start = i == 0 || t >= start;
                        let before_end = i + 1 == n || t < end;
                        (after_start && before_end).then_some(t)
                    })
            }
        }
    }

    /// Where `stamp` lands when a recording's stamps arrive in order (a copy that keeps every
    /// message, `trajdrift restamp`), `last` the previous landing on the same channel. Like
    /// [`Self::stamp`], except for a piecewise model where [`Self::stamp`] has no single answer: a
    /// stamp that two segments take (a backward step repeated a stretch of stamps) goes to the one
    /// that lands nearest `last` (time runs on continuously: a copy before the step lands beside the
    /// previous message, a copy after it beyond the step), and a stamp no segment
    /// takes (a forward step skipped it) goes by the segment it lands nearest to. So every stamp
    /// maps; `None` only out of the i64 range.
    pub fn stamp_in_stream(&self, stamp: i64, last: &mut Option<i64>) -> Option<i64> {
        let out = match self {
            ClockCorrection::Piecewise { segments } if !segments.is_empty() => {
                let n = segments.len();
                let mut taking: Vec<i64> = Vec::new();
                let mut nearest: Option<(i64, i64)> = None;
                for (i, &(start, end, offset_s)) in segments.iter().enumerate() {
                    let t = stamp.checked_add(ns(offset_s))?;
                    let after_start = i == 0 || t >= start;
                    let before_end = i + 1 == n || t < end;
                    if after_start && before_end {
                        taking.push(t);
                    }
                    let miss = if after_start { t - end } else { start - t };
                    if nearest.is_none_or(|(m, _)| miss < m) {
                        nearest = Some((miss, t));
                    }
                }
                match (taking.as_slice(), *last) {
                    ([], _) => nearest.map(|(_, t)| t),
                    ([one], _) => Some(*one),
                    (many, Some(prev)) => many
                        .iter()
                        .copied()
                        .min_by_key(|&t| (t - prev).unsigned_abs()),
                    (many, None) => many.first().copied(),
                }
            }
            _ => self.stamp(stamp),
        };
        if out.is_some() {
            *last = out;
        }
        out
    }

    /// The offset Δt (seconds) the correction gives at `t_s`, seconds on the reference clock: what a
    /// figure draws as the model; `None` where a piecewise model has no segment.
    pub fn offset_at_s(&self, t_s: f64) -> Option<f64> {
        let t = ns(t_s);
        match self {
            ClockCorrection::Constant { dt_ns } => Some(*dt_ns as f64 * 1e-9),
            ClockCorrection::Linear {
                offset_s,
                drift_ppm,
                t_mid_ns,
            } => Some(offset_s - drift_ppm * 1e-6 * (t - t_mid_ns) as f64 * 1e-9),
            ClockCorrection::Piecewise { segments } => {
                let n = segments.len();
                segments
                    .iter()
                    .enumerate()
                    .find(|&(i, &(start, end, _))| {
                        (i == 0 || t >= start) && (i + 1 == n || t < end)
                    })
                    .map(|(_, &(_, _, offset_s))| offset_s)
            }
        }
    }

    /// Whether every stamp moves by the same offset.
    pub fn is_constant(&self) -> bool {
        matches!(self, ClockCorrection::Constant { .. })
    }

    /// Poses for evo's metrics (stamps in seconds on the estimate's clock) on the reference clock,
    /// each stamp mapped like [`Self::stamp`] maps its nanoseconds; poses mapped nowhere, or not after
    /// the previous one, are dropped (as [`Self::apply`] drops them). A path paired by index (no
    /// stamps) is returned as it is.
    pub fn apply_to_poses(&self, poses: Poses) -> Poses {
        let Some(stamps) = &poses.stamps_s else {
            return poses;
        };
        let mut keep: Vec<u32> = Vec::with_capacity(stamps.len());
        let mut mapped: Vec<f64> = Vec::with_capacity(stamps.len());
        let mut last = i64::MIN;
        for (i, &t) in stamps.iter().enumerate() {
            let Some(stamp) = self.stamp(ns(t)) else {
                continue;
            };
            if stamp <= last {
                continue;
            }
            last = stamp;
            keep.push(i as u32);
            // The same shift as the nanoseconds, added to the stamp as read (no rounding of it).
            mapped.push(t + (stamp - ns(t)) as f64 * 1e-9);
        }
        let mut out = poses.select(&keep);
        out.stamps_s = Some(mapped);
        out
    }

    /// `trajectory` (stamps on the estimate's clock) on the reference clock; samples mapped nowhere,
    /// or not after the previous one (a backward clock step repeats a stretch of stamps), are dropped.
    pub fn apply(&self, trajectory: &Trajectory) -> Trajectory {
        if let ClockCorrection::Constant { dt_ns } = self {
            return trajectory.shifted(*dt_ns);
        }
        let mut out = Trajectory::new(trajectory.orientations.is_some());
        for (i, (&t, p)) in trajectory
            .stamps_ns
            .iter()
            .zip(&trajectory.positions)
            .enumerate()
        {
            let Some(stamp) = self.stamp(t) else {
                continue;
            };
            if out.stamps_ns.last().is_some_and(|&last| stamp <= last) {
                continue;
            }
            out.push(stamp, *p, trajectory.orientations.as_ref().map(|o| o[i]));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::json::OffsetSegmentReport;

    fn report(model: OffsetModel) -> TimeOffsetReport {
        TimeOffsetReport {
            status: TimeOffsetStatus::Ok,
            offset_s: 0.5,
            applied_s: 0.5,
            model: Some(model),
            ..Default::default()
        }
    }

    #[test]
    fn a_linear_drift_grows_with_the_distance_from_t_mid() {
        let c = ClockCorrection::from_report(&TimeOffsetReport {
            drift_ppm: Some(100.0),
            t_mid: Some(1000.0),
            ..report(OffsetModel::Linear)
        });
        // At t_mid Δt is offset_s; 1000 s later it is 0.1 s smaller (estimate clock fast).
        assert_eq!(c.stamp(999_500_000_000), Some(1_000_000_000_000));
        assert_eq!(c.stamp(1_999_500_000_000), Some(1_999_900_000_000));
    }

    #[test]
    fn a_step_maps_each_stamp_by_its_segment() {
        let seg = |a: f64, b: f64, o: f64| OffsetSegmentReport {
            t_start: a,
            t_end: b,
            offset_s: o,
            sigma_s: 0.001,
        };
        // The estimate's clock stepped back 1 s at reference time 10 s: Δt 0, then 1 s. Its stamps
        // 9–10 s occur twice; each maps to where the first occurrence belongs, and `apply` drops the
        // repeat (not after the previous sample).
        let back = ClockCorrection::from_report(&TimeOffsetReport {
            segments: vec![seg(0.0, 10.0, 0.0), seg(10.0, 20.0, 1.0)],
            ..report(OffsetModel::Piecewise)
        });
        assert_eq!(back.stamp(5_000_000_000), Some(5_000_000_000));
        assert_eq!(back.stamp(9_500_000_000), Some(9_500_000_000));
        assert_eq!(back.stamp(12_000_000_000), Some(13_000_000_000));
        let mut t = Trajectory::new(false);
        for s in [9.0, 9.5, 9.9, 9.2, 9.6, 10.5] {
            t.push((s * 1e9) as i64, nalgebra::Vector3::zeros(), None);
        }
        let stamps: Vec<i64> = back.apply(&t).stamps_ns;
        assert_eq!(
            stamps,
            [9_000_000_000, 9_500_000_000, 9_900_000_000, 11_500_000_000]
        );
        // Stepped forward instead (Δt 1 s, then 0): stamps 9–10 s never occur, and map nowhere.
        let forward = ClockCorrection::from_report(&TimeOffsetReport {
            segments: vec![seg(0.0, 10.0, 1.0), seg(10.0, 20.0, 0.0)],
            ..report(OffsetModel::Piecewise)
        });
        assert_eq!(forward.stamp(9_500_000_000), None);
    }

    #[test]
    fn a_stream_keeps_every_stamp_across_a_step() {
        let seg = |a: f64, b: f64, o: f64| OffsetSegmentReport {
            t_start: a,
            t_end: b,
            offset_s: o,
            sigma_s: 0.001,
        };
        // Stepped back 1 s at 10 s: 9.0–9.9 then 9.2–… again; each copy lands in its own segment
        // (9.45 arriving late, before the step, stays in the first).
        let back = ClockCorrection::from_report(&TimeOffsetReport {
            segments: vec![seg(0.0, 10.0, 0.0), seg(10.0, 20.0, 1.0)],
            ..report(OffsetModel::Piecewise)
        });
        let mut last = None;
        let got: Vec<i64> = [9.0, 9.5, 9.9, 9.2, 9.6, 10.5]
            .iter()
            .map(|s| back.stamp_in_stream((s * 1e9) as i64, &mut last).unwrap())
            .collect();
        assert_eq!(
            got,
            [
                9_000_000_000,
                9_500_000_000,
                9_900_000_000,
                10_200_000_000,
                10_600_000_000,
                11_500_000_000
            ]
        );
        let mut last = None;
        let got: Vec<i64> = [9.5, 9.45, 9.6]
            .iter()
            .map(|s| back.stamp_in_stream((s * 1e9) as i64, &mut last).unwrap())
            .collect();
        assert_eq!(got, [9_500_000_000, 9_450_000_000, 9_600_000_000]);
        // Stepped forward: stamps 9–10 s never came, a late one maps by the nearest segment.
        let forward = ClockCorrection::from_report(&TimeOffsetReport {
            segments: vec![seg(0.0, 10.0, 1.0), seg(10.0, 20.0, 0.0)],
            ..report(OffsetModel::Piecewise)
        });
        let mut last = None;
        assert_eq!(
            forward.stamp_in_stream(9_100_000_000, &mut last),
            Some(10_100_000_000)
        );
        assert_eq!(
            forward.stamp_in_stream(8_000_000_000, &mut last),
            Some(9_000_000_000)
        );
        // Other models: as `stamp`.
        let c = ClockCorrection::Constant { dt_ns: 5 };
        assert_eq!(c.stamp_in_stream(10, &mut None), Some(15));
    }

    #[test]
    fn weak_or_constant_is_the_applied_offset() {
        let weak = TimeOffsetReport {
            status: TimeOffsetStatus::Weak,
            applied_s: 0.0,
            drift_ppm: Some(100.0),
            t_mid: Some(1000.0),
            ..report(OffsetModel::Linear)
        };
        assert_eq!(
            ClockCorrection::from_report(&weak),
            ClockCorrection::Constant { dt_ns: 0 }
        );
        assert_eq!(
            ClockCorrection::from_report(&report(OffsetModel::Constant)),
            ClockCorrection::Constant { dt_ns: 500_000_000 }
        );
    }
}
