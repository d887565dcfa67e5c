//! Budgets of the offset search. The search allocates with its lag count and its grid length, which
//! the parameters (and the data's time span) set; [`check_search_size`] bounds them by
//! [`MEMORY_BUDGET_BYTES`], the fine search's work by [`FINE_WORK_BUDGET`] and the offset
//! profile's by [`PROFILE_WORK_BUDGET_S`] before anything is allocated, so no parameter can abort
//! the process or make it run for hours.

use super::{show_number, GRID_MIN_S, OFFSET_STEP_MIN_S};
use crate::align::offset_params::COARSE_GRID_S;
use crate::align::offset_profile::{window_and_step, ProfileParams, SEARCH_S};
use crate::error::{Error, Result};

/// Memory the offset search may take for its lags and grids.
pub const MEMORY_BUDGET_BYTES: u64 = 1 << 30;
/// Bytes per coarse lag or grid point (FFT buffers, correlation and overlap per lag).
const BYTES_PER_CELL: u64 = 64;
/// Multiply-adds the fine offset search may take (about a minute on one core at its ceiling).
pub const FINE_WORK_BUDGET: f64 = 2.0e10;
/// Seconds of signal the offset profile's windows may search in all (each window its own length
/// and the search range on both sides; about half a minute on one core at its ceiling).
pub const PROFILE_WORK_BUDGET_S: f64 = 2.0e6;

/// Lags of the coarse offset search for `max_offset_s`.
pub fn coarse_lags(max_offset_s: f64) -> u64 {
    2 * (max_offset_s / COARSE_GRID_S).floor() as u64 + 1
}

/// Refuses an offset search whose buffers or work would exceed the budgets, for trajectories that
/// span `span_s` seconds: the coarse grid and lags against [`MEMORY_BUDGET_BYTES`], the fine search
/// against [`FINE_WORK_BUDGET`], the offset profile's windows (`profile`, from the data where
/// unset) against [`PROFILE_WORK_BUDGET_S`]. The message says what to change.
pub fn check_search_size(
    max_offset_s: f64,
    grid_s: f64,
    profile: &ProfileParams,
    span_s: f64,
) -> Result<()> {
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
            floor.max(GRID_MIN_S)
        )));
    }
    let (window_s, step_s) = window_and_step(span_s.max(0.0), profile);
    let per_window_s = window_s.min(span_s.max(0.0)) + 2.0 * SEARCH_S;
    let searched_s = (span_s.max(0.0) / step_s).ceil() * per_window_s;
    if !searched_s.is_finite() || searched_s > PROFILE_WORK_BUDGET_S {
        let floor = span_s * per_window_s / PROFILE_WORK_BUDGET_S;
        return Err(Error::InvalidArgument(format!(
            "--offset-step {step_s}: the offset profile over {span_s:.0} s of data would search {searched_s:.1e} s of signal (budget {PROFILE_WORK_BUDGET_S:.0e} s); use --offset-step {} or more, a shorter --offset-window, or crop with --t-start/--t-end",
            show_number((10.0 * floor.max(OFFSET_STEP_MIN_S)).ceil() / 10.0)
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_defaults_fit_the_budgets_for_a_day() {
        assert!(check_search_size(30.0, 0.001, &ProfileParams::default(), 86_400.0).is_ok());
        assert!(check_search_size(86_400.0, 0.001, &ProfileParams::default(), 3_600.0).is_ok());
        assert!(check_search_size(30.0, 1e-4, &ProfileParams::default(), 36_000.0).is_err());
        assert!(check_search_size(30.0, 0.001, &ProfileParams::default(), 1e12).is_err());
    }

    #[test]
    fn a_fine_profile_step_fits_a_short_mission_not_a_long_one() {
        let step = |s| ProfileParams {
            window_s: None,
            step_s: Some(s),
        };
        assert!(check_search_size(30.0, 0.001, &step(0.1), 121.0).is_ok());
        assert!(check_search_size(30.0, 0.001, &step(0.001), 121.0).is_err());
        let e = check_search_size(30.0, 0.001, &step(0.1), 86_400.0)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("--offset-step 0.1:") && e.contains("use --offset-step 5.5 or more"),
            "{e}"
        );
    }
}
