//! Parameter sweeps (`trajdrift sweep`): the evaluation re-run over one parameter's values, in
//! parallel (rayon), each value a whole `eval` with that one flag changed on the trajectories read
//! once — so a row of the sweep equals the single run at that value. This is the paper's ε_min figure (DE and the discarded share
//! against ε) and its time-shift figure (DE against an applied Δt, each method's answer marked).
//!
//! What a row holds is computed by [`row_metrics`] alone (DE, and evo's APE and RPE point distance when
//! `--metrics` asks for them): a new metric is one field there
//! and one CSV column in [`Sweep::to_csv`].

use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::eval::config::EvalConfig;
use crate::eval::evaluate_loaded;
use crate::eval::inputs::load;
use crate::report::escape::csv_field;
use crate::report::json::{DriftErrorReport, EstimateReport};
use crate::sources::{Progress, Warning};

/// The parameter a sweep varies (each is the `eval` flag of the same name).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SweepParam {
    /// `--eps-min`: both ε (the paper's single ε_min).
    EpsMin,
    CurvatureEps,
    PathEps,
    /// `--window`: one window size per value.
    Window,
    LeverArm,
    Overlap,
    /// `--time-offset`: the applied Δt, no search.
    TimeOffset,
}

impl SweepParam {
    /// The name as on the command line (and in the CSV).
    pub fn as_str(self) -> &'static str {
        match self {
            SweepParam::EpsMin => "eps-min",
            SweepParam::CurvatureEps => "curvature-eps",
            SweepParam::PathEps => "path-eps",
            SweepParam::Window => "window",
            SweepParam::LeverArm => "lever-arm",
            SweepParam::Overlap => "overlap",
            SweepParam::TimeOffset => "time-offset",
        }
    }

    /// The axis label of the value.
    pub fn axis_label(self) -> &'static str {
        match self {
            SweepParam::EpsMin => "ε_min, curvature and path (m)",
            SweepParam::CurvatureEps => "ε of the curvature (m)",
            SweepParam::PathEps => "ε of the path lengths (m)",
            SweepParam::Window => "window w (m)",
            SweepParam::LeverArm => "lever arm a (m)",
            SweepParam::Overlap => "window overlap (fraction)",
            SweepParam::TimeOffset => "applied time offset Δt (s)",
        }
    }

    /// `config` with this parameter set to `v`, exactly as the `eval` flag would set it.
    pub fn apply(self, config: &EvalConfig, v: f64) -> EvalConfig {
        let mut c = config.clone();
        match self {
            SweepParam::EpsMin => c.params.eps_min = Some(v),
            SweepParam::CurvatureEps => c.params.curvature_eps = Some(v),
            SweepParam::PathEps => c.params.path_eps = Some(v),
            SweepParam::Window => c.params.window = Some(vec![v]),
            SweepParam::LeverArm => c.params.lever_arm = Some(v),
            SweepParam::Overlap => c.params.overlap = Some(v),
            SweepParam::TimeOffset => c.params.time_offset = Some(v),
        }
        c
    }
}

/// The most values a sweep takes.
pub const MAX_VALUES: usize = 10_000;

/// Parses `0.05,0.1,0.2` or `A:B:STEP` (A to B inclusive), duplicates dropped, at most
/// [`MAX_VALUES`]. Values are rounded to 1e-9 so that a generated 0.15 is the 0.15 a user would type.
pub fn parse_values(s: &str) -> Result<Vec<f64>> {
    let bad = |why: &str| {
        Error::InvalidArgument(format!(
            "--values `{s}`: {why}; give a list (0.05,0.1,0.2) or a range A:B:STEP (0.05:1:0.05)"
        ))
    };
    let num = |x: &str| x.trim().parse::<f64>().ok().filter(|v| v.is_finite());
    let values: Vec<f64> = if s.contains(':') {
        let parts: Vec<Option<f64>> = s.split(':').map(num).collect();
        let [Some(a), Some(b), Some(step)] = parts[..] else {
            return Err(bad("a range is three numbers A:B:STEP"));
        };
        if step <= 0.0 || b < a {
            return Err(bad("a range needs A ≤ B and STEP > 0"));
        }
        let n = ((b - a) / step + 1e-9).floor() as usize + 1;
        if n > MAX_VALUES {
            return Err(bad("more than 10000 values"));
        }
        (0..n)
            .map(|k| ((a + k as f64 * step) * 1e9).round() / 1e9)
            .collect()
    } else {
        if s.split(',').count() > MAX_VALUES {
            return Err(bad("more than 10000 values"));
        }
        s.split(',')
            .map(|x| num(x).ok_or_else(|| bad("not a number")))
            .collect::<Result<_>>()?
    };
    if values.is_empty() {
        return Err(bad("no value"));
    }
    // A value given twice is evaluated once.
    let mut unique: Vec<f64> = Vec::with_capacity(values.len());
    for v in values {
        if !unique.iter().any(|u| u.to_bits() == v.to_bits()) {
            unique.push(v);
        }
    }
    Ok(unique)
}

/// The numbers one (value, estimate, window size) contributes to the sweep.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RowMetrics {
    pub window_m: f64,
    pub windows: usize,
    pub de_median: Option<f64>,
    pub de_rmse: Option<f64>,
    pub discarded_fraction: f64,
    /// Δt applied by that run (the searched or the given one), seconds.
    pub applied_offset_s: f64,
    /// `ok`, `weak` or `given`.
    pub offset_status: crate::report::json::TimeOffsetStatus,
    /// evo's APE (SE(3), translation part) RMSE of that run, m (when `--metrics` asks for it).
    pub ape_rmse: Option<f64>,
    /// evo's RPE point distance over 1 m, RMSE, m (positions alone, so defined for every input).
    pub rpe_point_distance_1m_rmse: Option<f64>,
}

/// The metrics of a row, from one estimate's report at one window size.
pub fn row_metrics(e: &EstimateReport, d: &DriftErrorReport) -> RowMetrics {
    RowMetrics {
        window_m: d.window_m,
        windows: d.windows,
        de_median: d.median,
        de_rmse: d.rmse,
        discarded_fraction: d.discarded_fraction,
        applied_offset_s: e.time_offset.applied_s,
        offset_status: e.time_offset.status,
        ape_rmse: e
            .standard_metrics
            .as_ref()
            .and_then(|m| m.ape.as_ref())
            .map(|r| r.stats.rmse),
        rpe_point_distance_1m_rmse: e
            .standard_metrics
            .as_ref()
            .and_then(|m| m.rpe_point_distance_1m.as_ref())
            .map(|r| r.stats.rmse),
    }
}

/// One row of the sweep.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepRow {
    pub value: f64,
    pub estimate: String,
    /// `None` when the run at this value failed (see `error`).
    pub metrics: Option<RowMetrics>,
    pub error: Option<String>,
}

/// Each method's Δt for an estimate, from a run with the search (time-offset sweeps).
#[derive(Debug, Clone, PartialEq)]
pub struct MethodOffset {
    pub estimate: String,
    pub method: crate::align::time_offset::OffsetMethod,
    pub offset_s: f64,
}

/// A finished sweep.
#[derive(Debug, Clone, PartialEq)]
pub struct Sweep {
    pub param: SweepParam,
    pub rows: Vec<SweepRow>,
    pub method_offsets: Vec<MethodOffset>,
    /// What the read warns of (a recording cut short): said once, not per value.
    pub warnings: Vec<Warning>,
}

/// Runs the evaluation of `base` at every value of `param`, in parallel; `on_done` is called as each
/// value finishes (for a progress bar). A value whose run fails is a row with its error; the sweep
/// fails only when every value does.
pub fn run_sweep(
    base: &EvalConfig,
    param: SweepParam,
    values: &[f64],
    read: Progress<'_>,
    on_done: &(dyn Fn() + Sync),
) -> Result<Sweep> {
    base.validate()?;
    // Read once: no swept parameter changes what is read, only what is computed from it.
    let inputs = load(base, read)?;
    let evaluate = |c: &EvalConfig| evaluate_loaded(c, inputs.clone()).map(|(r, _)| r);
    let runs: Vec<(f64, Result<Vec<SweepRow>>)> = values
        .par_iter()
        .map(|&v| {
            let r = evaluate(&param.apply(base, v)).map(|report| {
                report
                    .estimates
                    .iter()
                    .flat_map(|e| {
                        e.drift_error.iter().map(move |d| SweepRow {
                            value: v,
                            estimate: e.name.clone(),
                            metrics: Some(row_metrics(e, d)),
                            error: None,
                        })
                    })
                    .collect()
            });
            on_done();
            (v, r)
        })
        .collect();
    if runs.iter().all(|(_, r)| r.is_err()) {
        if let Some((_, Err(e))) = runs.into_iter().next() {
            return Err(e);
        }
        return Err(Error::InvalidArgument(
            "a sweep needs at least one value".into(),
        ));
    }
    let mut rows = Vec::new();
    for (v, r) in runs {
        match r {
            Ok(mut rs) => rows.append(&mut rs),
            Err(e) => rows.push(SweepRow {
                value: v,
                estimate: String::new(),
                metrics: None,
                error: Some(e.to_string()),
            }),
        }
    }
    let method_offsets = if param == SweepParam::TimeOffset {
        let mut searched = base.clone();
        searched.params.time_offset = None;
        evaluate(&searched)?
            .estimates
            .iter()
            .flat_map(|e| {
                e.time_offset.methods.iter().filter_map(|m| {
                    m.offset_s.map(|dt| MethodOffset {
                        estimate: e.name.clone(),
                        method: m.method,
                        offset_s: dt,
                    })
                })
            })
            .collect()
    } else {
        Vec::new()
    };
    Ok(Sweep {
        param,
        rows,
        method_offsets,
        warnings: inputs.warnings,
    })
}

impl Sweep {
    /// `sweep.csv`: one row per value × estimate × window size; empty cells where undefined. Text
    /// cells (names, statuses, errors) through the CSV sink ([`csv_field`]: no formula, one line).
    pub fn to_csv(&self) -> Result<String> {
        let mut s = String::from("param,value,estimate,window_m,windows,de_median,de_rmse,discarded_fraction,applied_offset_s,offset_status,ape_rmse,rpe_point_distance_1m_rmse,error\n");
        let opt = |v: Option<f64>| v.map_or(String::new(), |x| x.to_string());
        for r in &self.rows {
            let m = r.metrics.as_ref();
            let cells = [
                self.param.as_str().to_string(),
                r.value.to_string(),
                csv_field(&r.estimate),
                opt(m.map(|m| m.window_m)),
                m.map_or(String::new(), |m| m.windows.to_string()),
                opt(m.and_then(|m| m.de_median)),
                opt(m.and_then(|m| m.de_rmse)),
                opt(m.map(|m| m.discarded_fraction)),
                opt(m.map(|m| m.applied_offset_s)),
                m.map_or(String::new(), |m| csv_field(&m.offset_status.to_string())),
                opt(m.and_then(|m| m.ape_rmse)),
                opt(m.and_then(|m| m.rpe_point_distance_1m_rmse)),
                r.error.as_deref().map_or(String::new(), csv_field),
            ];
            s.push_str(&cells.join(","));
            s.push('\n');
        }
        Ok(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_parse_as_list_and_range() {
        assert_eq!(parse_values("0.1,0.2, 0.5").unwrap(), vec![0.1, 0.2, 0.5]);
        let r = parse_values("0.05:0.25:0.05").unwrap();
        assert_eq!(r, vec![0.05, 0.1, 0.15, 0.2, 0.25]);
        assert_eq!(parse_values("-1:1:1").unwrap(), vec![-1.0, 0.0, 1.0]);
        for bad in ["", "a", "1:0:1", "0:1:0", "0:1", "1,x"] {
            assert!(parse_values(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn apply_sets_the_flag() {
        use crate::eval::config::NamedInput;
        let c = EvalConfig::new(None, NamedInput::topic("/r"), vec![NamedInput::topic("/e")]);
        assert_eq!(SweepParam::EpsMin.apply(&c, 0.3).params.eps_min, Some(0.3));
        assert_eq!(
            SweepParam::Window.apply(&c, 10.0).params.windows_m(),
            vec![10.0]
        );
        assert_eq!(
            SweepParam::TimeOffset.apply(&c, -0.2).params.time_offset,
            Some(-0.2)
        );
    }
}
