//! Every numeric `eval` parameter in one table: its flag, range, default and meaning. Flags, batch
//! manifests and presets are all checked against it ([`validate`], called by
//! [`crate::eval::config::EvalConfig::validate`]), so a value is refused the same way wherever it was
//! written: naming the flag, the value and the range (a usage error, exit 2). NaN and infinities are
//! never in range.
//!
//! The offset search allocates with its lag count and its grid length, which a flag (and the data's
//! time span) set; [`check_search_size`] bounds them by [`MEMORY_BUDGET_BYTES`] and the fine search's
//! work by [`FINE_WORK_BUDGET`] before anything is allocated, so no flag can abort the process or
//! make it run for hours.
//!
//! Meant to grow into the single parameter model (issue 14): a manifest or preset key is the flag
//! without its dashes (`--max-offset` → `max_offset`), see [`ParamSpec::key`].

use crate::error::{Error, Result};
use crate::eval::config::EvalConfig;

/// One end of a range.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Bound {
    /// The value itself is allowed.
    Inclusive(f64),
    /// Only values strictly beyond it.
    Exclusive(f64),
}

/// A numeric parameter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParamSpec {
    /// The `eval` flag, e.g. `--grid`.
    pub flag: &'static str,
    pub min: Bound,
    pub max: Bound,
    /// The default, when there is a fixed one (`None`: measured, or off).
    pub default: Option<f64>,
    pub unit: &'static str,
    pub help: &'static str,
}

/// Coarse step of the offset search, seconds ([`crate::align::time_offset::OffsetParams`]'s default).
const COARSE_GRID_S: f64 = 0.02;

/// Every numeric `eval` parameter.
pub const PARAMS: &[ParamSpec] = &[
    ParamSpec {
        flag: "--eps-min",
        min: Bound::Exclusive(0.0),
        max: Bound::Inclusive(1000.0),
        default: None,
        unit: "m",
        help: "ε for curvature and path length (default: by --platform)",
    },
    ParamSpec {
        flag: "--curvature-eps",
        min: Bound::Exclusive(0.0),
        max: Bound::Inclusive(1000.0),
        default: None,
        unit: "m",
        help: "ε of the curvature signature",
    },
    ParamSpec {
        flag: "--path-eps",
        min: Bound::Exclusive(0.0),
        max: Bound::Inclusive(1000.0),
        default: None,
        unit: "m",
        help: "ε of the path-length decimation",
    },
    ParamSpec {
        flag: "--theta-max",
        min: Bound::Exclusive(0.0),
        max: Bound::Inclusive(std::f64::consts::PI),
        default: Some(std::f64::consts::FRAC_PI_2),
        unit: "rad",
        help: "turning angles above it are discontinuities",
    },
    ParamSpec {
        flag: "--dt-max",
        min: Bound::Exclusive(0.0),
        max: Bound::Inclusive(86_400.0),
        default: Some(2.0),
        unit: "s",
        help: "a chord slower than this is a gap or a standstill",
    },
    ParamSpec {
        flag: "--window",
        min: Bound::Exclusive(0.0),
        max: Bound::Inclusive(1.0e6),
        default: Some(5.0),
        unit: "m",
        help: "Drift Error window, metres of reference path",
    },
    ParamSpec {
        flag: "--overlap",
        min: Bound::Inclusive(0.0),
        max: Bound::Exclusive(1.0),
        default: Some(0.0),
        unit: "",
        help: "window overlap fraction",
    },
    ParamSpec {
        flag: "--lever-arm",
        min: Bound::Inclusive(0.0),
        max: Bound::Inclusive(100.0),
        default: Some(0.1),
        unit: "m",
        help: "bound a of the paper's lever-arm correction",
    },
    ParamSpec {
        flag: "--max-offset",
        min: Bound::Exclusive(0.0),
        max: Bound::Inclusive(86_400.0),
        default: Some(30.0),
        unit: "s",
        help: "largest clock offset searched",
    },
    ParamSpec {
        flag: "--grid",
        min: Bound::Inclusive(1.0e-4),
        max: Bound::Inclusive(COARSE_GRID_S),
        default: Some(0.001),
        unit: "s",
        help: "fine step of the offset search",
    },
    ParamSpec {
        flag: "--offset-window",
        min: Bound::Exclusive(0.0),
        max: Bound::Inclusive(86_400.0),
        default: None,
        unit: "s",
        help: "window of the offset profile (default: from the data)",
    },
    ParamSpec {
        flag: "--offset-step",
        min: Bound::Exclusive(0.0),
        max: Bound::Inclusive(86_400.0),
        default: None,
        unit: "s",
        help: "step of the offset profile (default: half the window)",
    },
    ParamSpec {
        flag: "--time-offset",
        min: Bound::Inclusive(-1.0e10),
        max: Bound::Inclusive(1.0e10),
        default: None,
        unit: "s",
        help: "offset applied instead of searched",
    },
    ParamSpec {
        flag: "--t-start",
        min: Bound::Inclusive(-1.0e10),
        max: Bound::Inclusive(1.0e10),
        default: None,
        unit: "s",
        help: "crop start (epoch, or from the first reference sample)",
    },
    ParamSpec {
        flag: "--t-end",
        min: Bound::Inclusive(-1.0e10),
        max: Bound::Inclusive(1.0e10),
        default: None,
        unit: "s",
        help: "crop end",
    },
    ParamSpec {
        flag: "--origin latitude",
        min: Bound::Inclusive(-90.0),
        max: Bound::Inclusive(90.0),
        default: None,
        unit: "°",
        help: "ENU origin latitude",
    },
    ParamSpec {
        flag: "--origin longitude",
        min: Bound::Inclusive(-180.0),
        max: Bound::Inclusive(180.0),
        default: None,
        unit: "°",
        help: "ENU origin longitude",
    },
    ParamSpec {
        flag: "--origin height",
        min: Bound::Inclusive(-1.0e4),
        max: Bound::Inclusive(1.0e5),
        default: None,
        unit: "m",
        help: "ENU origin ellipsoidal height",
    },
    ParamSpec {
        flag: "--reference-lever/--estimate-lever",
        min: Bound::Inclusive(-1000.0),
        max: Bound::Inclusive(1000.0),
        default: None,
        unit: "m",
        help: "sensor lever arm component",
    },
];

/// Memory the offset search may take for its lags and grids.
pub const MEMORY_BUDGET_BYTES: u64 = 1 << 30;
/// Bytes per coarse lag or grid point (FFT buffers, correlation and overlap per lag).
const BYTES_PER_CELL: u64 = 64;
/// Multiply-adds the fine offset search may take (about a minute on one core at its ceiling).
pub const FINE_WORK_BUDGET: f64 = 2.0e10;

impl ParamSpec {
    /// The key in manifests and presets: the flag without `--`, `-` written `_`.
    pub fn key(&self) -> String {
        self.flag.trim_start_matches("--").replace('-', "_")
    }

    /// The range as text, e.g. `(0, 86400] s`.
    pub fn range_text(&self) -> String {
        let (open, lo) = match self.min {
            Bound::Inclusive(v) => ('[', v),
            Bound::Exclusive(v) => ('(', v),
        };
        let (close, hi) = match self.max {
            Bound::Inclusive(v) => (']', v),
            Bound::Exclusive(v) => (')', v),
        };
        format!("{open}{}, {}{close} {}", show(lo), show(hi), self.unit)
            .trim_end()
            .to_string()
    }

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

    /// `v`, or the refusal naming the flag, the value and the range.
    pub fn check(&self, v: f64) -> Result<f64> {
        if self.contains(v) {
            return Ok(v);
        }
        Err(Error::InvalidArgument(format!(
            "{} {}: out of range; expected a finite value in {} ({})",
            self.flag,
            show(v),
            self.range_text(),
            self.help
        )))
    }
}

/// A value as a person reads it: plain for everyday magnitudes, scientific beyond.
fn show(v: f64) -> String {
    if v == 0.0 || !v.is_finite() || (1e-3..1e6).contains(&v.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// The spec of `flag`.
///
/// # Panics
/// When `flag` is not in [`PARAMS`] (a programming error, caught by the tests).
pub fn spec(flag: &str) -> &'static ParamSpec {
    PARAMS
        .iter()
        .find(|p| p.flag == flag)
        .unwrap_or_else(|| panic!("{flag} is not in the parameter table"))
}

/// Checks `v` against the spec of `flag`.
pub fn check(flag: &str, v: f64) -> Result<f64> {
    spec(flag).check(v)
}

/// Checks every numeric value of `c` against [`PARAMS`], and the offset search's lag count against the
/// memory budget.
pub fn validate(c: &EvalConfig) -> Result<()> {
    let opt = |flag: &str, v: Option<f64>| v.map(|v| check(flag, v)).transpose();
    opt("--eps-min", c.eps_min_m)?;
    opt("--curvature-eps", c.curvature_eps_m)?;
    opt("--path-eps", c.path_eps_m)?;
    check("--theta-max", c.theta_max_rad)?;
    check("--dt-max", c.dt_max_s)?;
    opt("--dt-max", c.curvature_dt_max_s)?;
    for &w in &c.windows_m {
        check("--window", w)?;
    }
    check("--overlap", c.overlap)?;
    check("--lever-arm", c.lever_arm_m)?;
    check("--max-offset", c.max_offset_s)?;
    check("--grid", c.grid_s)?;
    opt("--offset-window", c.offset_profile.window_s)?;
    opt("--offset-step", c.offset_profile.step_s)?;
    opt("--time-offset", c.time_offset_s)?;
    opt("--t-start", c.t_start)?;
    opt("--t-end", c.t_end)?;
    if let Some([lat, lon, h]) = c.origin {
        check("--origin latitude", lat)?;
        check("--origin longitude", lon)?;
        check("--origin height", h)?;
    }
    let levers = c.estimate_levers.iter().map(|(_, l)| l);
    for l in levers.chain(c.reference_lever.as_ref()) {
        if let crate::eval::config::LeverSpec::Offset(v) = l {
            for &x in v.iter() {
                check("--reference-lever/--estimate-lever", x)?;
            }
        }
    }
    Ok(())
}

/// Lags of the coarse offset search for `max_offset_s`.
pub fn coarse_lags(max_offset_s: f64) -> u64 {
    2 * (max_offset_s / COARSE_GRID_S).floor() as u64 + 1
}

/// Refuses an offset search whose buffers or work would exceed the budgets, for trajectories that
/// span `span_s` seconds: the coarse grid and lags against [`MEMORY_BUDGET_BYTES`], the fine search
/// against [`FINE_WORK_BUDGET`]. The message says what to change.
pub fn check_search_size(max_offset_s: f64, grid_s: f64, span_s: f64) -> Result<()> {
    let points = (span_s.max(0.0) / COARSE_GRID_S).ceil();
    let cells = points + coarse_lags(max_offset_s) as f64;
    let bytes = cells * BYTES_PER_CELL as f64;
    if !bytes.is_finite() || bytes > MEMORY_BUDGET_BYTES as f64 {
        return Err(Error::InvalidArgument(format!(
            "the offset search over {span_s:.0} s of data with --max-offset {max_offset_s} would need {:.1} GiB (budget {} GiB); crop with --t-start/--t-end, lower --max-offset, or give --time-offset",
            bytes / (1u64 << 30) as f64,
            MEMORY_BUDGET_BYTES >> 30
        )));
    }
    let fine_lags = 2.0 * (2.0 * COARSE_GRID_S / grid_s).round() + 1.0;
    let work = fine_lags * span_s.max(0.0) / grid_s;
    if !work.is_finite() || work > FINE_WORK_BUDGET {
        let floor = (4.0 * COARSE_GRID_S * span_s / FINE_WORK_BUDGET).sqrt();
        return Err(Error::InvalidArgument(format!(
            "--grid {grid_s}: the fine offset search over {span_s:.0} s of data would take {work:.1e} steps (budget {FINE_WORK_BUDGET:.0e}); use --grid {:.1e} or more, or crop with --t-start/--t-end",
            floor.max(spec("--grid").range_min())
        )));
    }
    Ok(())
}

impl ParamSpec {
    fn range_min(&self) -> f64 {
        match self.min {
            Bound::Inclusive(v) | Bound::Exclusive(v) => v,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_default_is_in_its_range_and_nan_inf_are_not() {
        for p in PARAMS {
            if let Some(d) = p.default {
                assert!(p.contains(d), "{}", p.flag);
            }
            for v in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                assert!(!p.contains(v), "{} {v}", p.flag);
            }
        }
        assert_eq!(spec("--max-offset").key(), "max_offset");
    }

    #[test]
    fn refusal_names_flag_value_and_range() {
        let e = check("--grid", 1e-9).unwrap_err().to_string();
        assert!(
            e.contains("--grid 1e-9") && e.contains("[1e-4, 0.02] s"),
            "{e}"
        );
        let e = check("--overlap", 1.0).unwrap_err().to_string();
        assert!(e.contains("[0, 1)"), "{e}");
    }

    #[test]
    fn the_defaults_fit_the_budgets_for_a_day() {
        assert!(check_search_size(30.0, 0.001, 86_400.0).is_ok());
        assert!(check_search_size(86_400.0, 0.001, 3_600.0).is_ok());
        assert!(check_search_size(30.0, 1e-4, 36_000.0).is_err());
        assert!(check_search_size(30.0, 0.001, 1e12).is_err());
    }
}
