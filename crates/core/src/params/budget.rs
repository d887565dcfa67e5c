//! Budgets of the offset search. The search allocates with its lag count and its grid length, which
//! the parameters (and the data's time span) set; [`check_search_size`] bounds them by
//! [`MEMORY_BUDGET_BYTES`] and the fine search's work by [`FINE_WORK_BUDGET`] before anything is
//! allocated, so no parameter can abort the process or make it run for hours.

use super::GRID_MIN_S;
use crate::align::offset_params::COARSE_GRID_S;
use crate::error::{Error, Result};

/// Memory the offset search may take for its lags and grids.
pub const MEMORY_BUDGET_BYTES: u64 = 1 << 30;
/// Bytes per coarse lag or grid point (FFT buffers, correlation and overlap per lag).
const BYTES_PER_CELL: u64 = 64;
/// Multiply-adds the fine offset search may take (about a minute on one core at its ceiling).
pub const FINE_WORK_BUDGET: f64 = 2.0e10;

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
            floor.max(GRID_MIN_S)
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_defaults_fit_the_budgets_for_a_day() {
        assert!(check_search_size(30.0, 0.001, 86_400.0).is_ok());
        assert!(check_search_size(86_400.0, 0.001, 3_600.0).is_ok());
        assert!(check_search_size(30.0, 1e-4, 36_000.0).is_err());
        assert!(check_search_size(30.0, 0.001, 1e12).is_err());
    }
}
