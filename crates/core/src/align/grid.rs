//! Resampling an irregular, gappy signal onto a regular time grid by linear interpolation.
//!
//! The curvature signature (and the speed profile) are defined only at some samples, at the rate of
//! their sensor. The paper's step 2 compares two of them on a common grid of step δt: every grid point
//! is a multiple of δt of the signal's own clock, so two signals resampled with the same step are in
//! phase and a lag of k grid points is a time shift of exactly k·δt. A grid point is *defined* only
//! when it lies between two defined samples that are at most `max_gap_s` apart: a gap in the signal
//! (a standstill, a GNSS outage, a discontinuity) stays a gap and is never bridged by interpolation.

/// A signal on the regular grid t = n·step, n = `first_index`, `first_index + 1`, …, with a mask.
#[derive(Debug, Clone, PartialEq)]
pub struct RegularSignal {
    /// Index n of the first grid point (its time is `first_index as f64 * step`).
    pub first_index: i64,
    /// The grid step δt, seconds.
    pub step: f64,
    /// The interpolated value at each grid point (0 where the mask is 0).
    pub values: Vec<f64>,
    /// 1 where the value is defined, 0 where it is not.
    pub mask: Vec<f64>,
}

impl RegularSignal {
    /// Number of grid points.
    pub fn len(&self) -> usize {
        self.values.len()
    }

    /// True when the grid has no point.
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// Time of grid point `i` (0-based in `values`), seconds.
    pub fn time(&self, i: usize) -> f64 {
        (self.first_index + i as i64) as f64 * self.step
    }

    /// Number of defined grid points.
    pub fn defined_count(&self) -> usize {
        self.mask.iter().filter(|&&m| m > 0.5).count()
    }
}

/// The grid indices n (t = n·step) of the first and last grid point inside `[t_first, t_last]`, or
/// `None` when no grid point falls in it or the inputs are not finite and positive.
pub fn grid_span(t_first: f64, t_last: f64, step: f64) -> Option<(i64, i64)> {
    if !(step > 0.0 && t_first.is_finite() && t_last.is_finite()) {
        return None;
    }
    // A tiny tolerance so that a sample exactly on a grid point is not lost to rounding.
    let tol = 1e-9;
    let first = (t_first / step - tol).ceil() as i64;
    let last = (t_last / step + tol).floor() as i64;
    (last >= first).then_some((first, last))
}

/// Resamples `(times[k], values[k])` onto the `len` grid points t = n·step, n = `first_index`…, by
/// linear interpolation between the two samples around each grid point. Non-finite samples are
/// ignored; `times` must be non-decreasing. A grid point is undefined (mask 0, value 0) outside the
/// samples' span or when its two neighbouring samples are more than `max_gap_s` apart.
pub fn resample_on_grid(
    times: &[f64],
    values: &[f64],
    step: f64,
    first_index: i64,
    len: usize,
    max_gap_s: f64,
) -> RegularSignal {
    read_grid(
        &LazyGrid::new(times, values, step, max_gap_s),
        first_index,
        len,
    )
}

/// The `len` points from grid index `first_index` of `grid`, held whole (outside the samples' span
/// every point is undefined).
fn read_grid(grid: &LazyGrid<'_>, first_index: i64, len: usize) -> RegularSignal {
    let mut out = RegularSignal {
        first_index,
        step: grid.step,
        values: vec![0.0; len],
        mask: vec![0.0; len],
    };
    grid.read(
        first_index - grid.first_index,
        &mut out.values,
        &mut out.mask,
    );
    out
}

/// Writes the resampling of finite samples (`times` non-decreasing, as long as `values`) at the grid
/// points n = `first_index`, `first_index + 1`, … into `out` (values, mask; as long as each other):
/// value and 1 where defined, 0 and 0 where not. Grid point n is at time n·step − `shift_s` of the
/// samples' clock (a grid on a clock `shift_s` ahead). The first sample is found by bisection, so
/// that a long signal read block by block costs each block its own length only.
pub fn resample_into(
    (times, values): (&[f64], &[f64]),
    (step, shift_s): (f64, f64),
    first_index: i64,
    (out_v, out_m): (&mut [f64], &mut [f64]),
    max_gap_s: f64,
) {
    out_v.fill(0.0);
    out_m.fill(0.0);
    if times.is_empty() || step.is_nan() || step <= 0.0 {
        return;
    }
    // Grid times rise monotonically, so one cursor walks the samples once; it starts at the last
    // sample at or before the first grid time.
    let tol = 1e-9 * step;
    let first_t = first_index as f64 * step - shift_s;
    let mut k = times.partition_point(|&x| x <= first_t).saturating_sub(1);
    for (i, (v, m)) in out_v.iter_mut().zip(out_m.iter_mut()).enumerate() {
        let t = (first_index + i as i64) as f64 * step - shift_s;
        while k + 1 < times.len() && times[k + 1] <= t {
            k += 1;
        }
        let (t0, v0) = (times[k], values[k]);
        if (t - t0).abs() <= tol {
            (*v, *m) = (v0, 1.0);
            continue;
        }
        if t < t0 || k + 1 >= times.len() {
            continue;
        }
        let (t1, v1) = (times[k + 1], values[k + 1]);
        let gap = t1 - t0;
        if gap > max_gap_s || gap <= 0.0 {
            continue;
        }
        let w = (t - t0) / gap;
        (*v, *m) = (v0 + w * (v1 - v0), 1.0);
    }
}

/// A signal on a regular grid read a block at a time, so that a long one need not be held whole:
/// the masked cross-correlation ([`crate::align::xcorr::masked_ncc_blocks`]) reads its inputs this
/// way.
pub trait GridBlocks {
    /// Number of grid points.
    fn len(&self) -> usize;

    /// Writes the values (0 where undefined) and the mask (1 or 0) of points `start`,
    /// `start + 1`, … (0-based; points outside `0..len()` are undefined) into `values` and `mask`,
    /// which are as long as each other.
    fn read(&self, start: i64, values: &mut [f64], mask: &mut [f64]);

    /// True when the grid has no point.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Number of defined points, read in blocks.
    fn defined_count(&self) -> usize {
        const BLOCK: usize = 1 << 14;
        let (mut v, mut m) = (vec![0.0; BLOCK], vec![0.0; BLOCK]);
        (0..self.len())
            .step_by(BLOCK)
            .map(|s| {
                let n = BLOCK.min(self.len() - s);
                self.read(s as i64, &mut v[..n], &mut m[..n]);
                m[..n].iter().filter(|&&x| x > 0.5).count()
            })
            .sum()
    }
}

/// Values and a mask held whole (values where the mask is 0 are read as 0).
#[derive(Debug, Clone, Copy)]
pub struct MaskedSlices<'a> {
    /// Values.
    pub values: &'a [f64],
    /// 1 where the value is defined, 0 where not.
    pub mask: &'a [f64],
}

impl GridBlocks for MaskedSlices<'_> {
    fn len(&self) -> usize {
        self.values.len().min(self.mask.len())
    }

    fn read(&self, start: i64, values: &mut [f64], mask: &mut [f64]) {
        let n = self.len() as i64;
        for (i, (v, m)) in values.iter_mut().zip(mask.iter_mut()).enumerate() {
            let j = start + i as i64;
            (*v, *m) = if (0..n).contains(&j) && self.mask[j as usize] > 0.5 {
                (self.values[j as usize], 1.0)
            } else {
                (0.0, 0.0)
            };
        }
    }
}

/// The resampling of samples onto every grid point of their span (what [`resample`] returns),
/// computed where it is read.
#[derive(Debug, Clone)]
pub struct LazyGrid<'a> {
    times: std::borrow::Cow<'a, [f64]>,
    values: std::borrow::Cow<'a, [f64]>,
    /// Index n of the first grid point (its time is `first_index as f64 * step`).
    pub first_index: i64,
    len: usize,
    step: f64,
    shift_s: f64,
    max_gap_s: f64,
}

impl<'a> LazyGrid<'a> {
    /// The grid of [`resample`]`(times, values, step, max_gap_s)`; the samples are borrowed, or
    /// copied without their non-finite entries when there are any.
    pub fn new(times: &'a [f64], values: &'a [f64], step: f64, max_gap_s: f64) -> Self {
        Self::shifted(times, values, step, max_gap_s, 0.0)
    }

    /// [`LazyGrid::new`] of the samples at `times + shift_s` (without a shifted copy of the times).
    pub fn shifted(
        times: &'a [f64],
        values: &'a [f64],
        step: f64,
        max_gap_s: f64,
        shift_s: f64,
    ) -> Self {
        use std::borrow::Cow;
        let n = times.len().min(values.len());
        let (times, values) = if (0..n).all(|k| times[k].is_finite() && values[k].is_finite()) {
            (Cow::Borrowed(&times[..n]), Cow::Borrowed(&values[..n]))
        } else {
            let (t, v): (Vec<f64>, Vec<f64>) = times
                .iter()
                .zip(values)
                .filter(|(t, v)| t.is_finite() && v.is_finite())
                .unzip();
            (Cow::Owned(t), Cow::Owned(v))
        };
        let span = match (times.first(), times.last()) {
            (Some(&lo), Some(&hi)) => grid_span(lo + shift_s, hi + shift_s, step),
            _ => None,
        };
        let (first_index, len) = span.map_or((0, 0), |(a, b)| (a, (b - a + 1) as usize));
        LazyGrid {
            times,
            values,
            first_index,
            len,
            step,
            shift_s,
            max_gap_s,
        }
    }
}

impl GridBlocks for LazyGrid<'_> {
    fn len(&self) -> usize {
        self.len
    }

    fn read(&self, start: i64, values: &mut [f64], mask: &mut [f64]) {
        let n = values.len().min(mask.len()) as i64;
        let (values, mask) = (&mut values[..n as usize], &mut mask[..n as usize]);
        values.fill(0.0);
        mask.fill(0.0);
        // Only the points inside 0..len are resampled.
        let lo = start.max(0);
        let hi = (start + n).min(self.len as i64);
        if lo >= hi {
            return;
        }
        let (a, b) = ((lo - start) as usize, (hi - start) as usize);
        resample_into(
            (&self.times, &self.values),
            (self.step, self.shift_s),
            self.first_index + lo,
            (&mut values[a..b], &mut mask[a..b]),
            self.max_gap_s,
        );
    }
}

/// Resamples onto every grid point t = n·step inside the samples' span (see [`resample_on_grid`]).
/// Returns an empty signal when there is no finite sample or no grid point in the span.
pub fn resample(times: &[f64], values: &[f64], step: f64, max_gap_s: f64) -> RegularSignal {
    let grid = LazyGrid::new(times, values, step, max_gap_s);
    read_grid(&grid, grid.first_index, grid.len())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_signal_is_reproduced_and_gaps_are_masked() {
        // v = 2t sampled at 0, 0.1, …, 1.0, then a 3 s gap, then 4.0 … 5.0.
        let mut t: Vec<f64> = (0..=10).map(|i| i as f64 * 0.1).collect();
        t.extend((0..=10).map(|i| 4.0 + i as f64 * 0.1));
        let v: Vec<f64> = t.iter().map(|t| 2.0 * t).collect();
        let g = resample(&t, &v, 0.01, 2.0);
        assert_eq!(g.first_index, 0);
        assert_eq!(g.len(), 501);
        for i in 0..g.len() {
            let ti = g.time(i);
            let inside = ti <= 1.0 + 1e-9 || ti >= 4.0 - 1e-9;
            assert_eq!(g.mask[i] > 0.5, inside, "t = {ti}");
            if inside {
                assert!((g.values[i] - 2.0 * ti).abs() < 1e-9);
            }
        }
        // With a max gap of 5 s the gap is bridged.
        assert_eq!(resample(&t, &v, 0.01, 5.0).defined_count(), 501);
    }

    #[test]
    fn a_lazy_grid_reads_what_resample_holds() {
        // Irregular times with a gap and a non-finite sample; read in blocks that straddle both
        // ends and the gap, with and without a shift of the clock.
        let mut t: Vec<f64> = (0..300)
            .map(|i| 0.013 + i as f64 * 0.037 + 0.01 * (i as f64).sin())
            .collect();
        t.extend((0..200).map(|i| 14.0 + i as f64 * 0.05));
        let mut v: Vec<f64> = t.iter().map(|t| (0.3 * t).sin()).collect();
        v[17] = f64::NAN;
        for shift in [0.0, 0.1234, -3.0] {
            let shifted: Vec<f64> = t.iter().map(|x| x + shift).collect();
            let whole = resample(&shifted, &v, 0.02, 0.5);
            let lazy = LazyGrid::shifted(&t, &v, 0.02, 0.5, shift);
            assert_eq!(lazy.first_index, whole.first_index);
            assert_eq!(lazy.len(), whole.len());
            assert_eq!(lazy.defined_count(), whole.defined_count());
            let (mut bv, mut bm) = (vec![0.0; 97], vec![0.0; 97]);
            for start in (-50..whole.len() as i64 + 50).step_by(97) {
                lazy.read(start, &mut bv, &mut bm);
                for (i, (&x, &m)) in bv.iter().zip(&bm).enumerate() {
                    let j = start + i as i64;
                    let (wx, wm) = if (0..whole.len() as i64).contains(&j) {
                        (whole.values[j as usize], whole.mask[j as usize])
                    } else {
                        (0.0, 0.0)
                    };
                    assert_eq!(m, wm, "shift {shift}, point {j}");
                    assert!(
                        (x - wx).abs() < 1e-12,
                        "shift {shift}, point {j}: {x} vs {wx}"
                    );
                }
            }
        }
    }

    #[test]
    fn grid_points_are_multiples_of_the_step() {
        let g = resample(&[0.013, 0.5], &[1.0, 1.0], 0.1, 1.0);
        assert_eq!(g.first_index, 1);
        assert_eq!(g.len(), 5);
        assert!(g.mask.iter().all(|&m| m == 1.0));
        assert!(resample(&[], &[], 0.1, 1.0).is_empty());
        assert!(resample(&[0.01, 0.02], &[1.0, 1.0], 0.1, 1.0).is_empty());
    }
}
