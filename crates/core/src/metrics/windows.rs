//! Cutting the reference into windows of w metres of travelled path (step 3 of the paper).
//!
//! A window is a run of consecutive vertices of the reference's ε-decimated polyline
//! ([`super::decimate::DecimatedPath`]) that has just reached `window_m` of counted path. Windows follow each
//! other without overlap by default; with an overlap fraction β the next window starts at the first
//! vertex (1 − β)·w of path after the previous start. The trailing partial window (less than w of path
//! left) is dropped silently, and so are windows outside the estimate's time span. A window that overlaps a
//! blocked interval (a reference or estimate gap longer than Δt_max) is dropped and counted, and the next window
//! starts at the first vertex after that interval: there is no trusted path across it.

use super::decimate::DecimatedPath;
use crate::error::{Error, Result};

/// One window, as vertex indices into the reference's decimated polyline.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathWindow {
    /// First vertex.
    pub start: usize,
    /// Last vertex (the first one at least `window_m` of path after `start`).
    pub end: usize,
    /// Time of the first vertex, seconds.
    pub t_start: f64,
    /// Time of the last vertex, seconds.
    pub t_end: f64,
}

/// The windows of a reference path, and how many were dropped for crossing a blocked interval.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct WindowLayout {
    /// Kept windows, in time order.
    pub windows: Vec<PathWindow>,
    /// Windows dropped because they overlap a blocked interval.
    pub dropped: usize,
}

/// Intervals `[t_i, t_{i+1}]` between consecutive samples more than `dt_max_s` apart.
pub fn gaps(times: &[f64], dt_max_s: f64) -> Vec<[f64; 2]> {
    times
        .windows(2)
        .filter(|w| w[1] - w[0] > dt_max_s)
        .map(|w| [w[0], w[1]])
        .collect()
}

/// Lays out windows of `window_m` metres of path on `path` with overlap fraction `overlap` in [0, 1).
/// Windows lie inside the time `span` (the first starts at the first vertex at or after `span[0]`;
/// none is counted dropped for the span). `blocked` are sorted time intervals no window may overlap.
pub fn path_windows(
    path: &DecimatedPath<'_>,
    window_m: f64,
    overlap: f64,
    span: [f64; 2],
    blocked: &[[f64; 2]],
) -> Result<WindowLayout> {
    if !(window_m.is_finite() && window_m > 0.0) {
        return Err(Error::InvalidArgument(format!(
            "window length {window_m} m: must be a positive number of metres"
        )));
    }
    if !(0.0..1.0).contains(&overlap) {
        return Err(Error::InvalidArgument(format!(
            "window overlap {overlap}: must be a fraction in [0, 1)"
        )));
    }
    let (t, s) = (&path.t, &path.s);
    let m = t.len();
    let mut layout = WindowLayout::default();
    let mut start = t.partition_point(|&x| x < span[0]);
    while start + 1 < m {
        let target = s[start] + window_m;
        let end = start + 1 + s[start + 1..].partition_point(|&x| x < target);
        if end >= m || t[end] > span[1] {
            break; // the trailing partial window
        }
        let (t0, t1) = (t[start], t[end]);
        // The blocked interval reaching furthest among those overlapping (t0, t1).
        let hit = blocked
            .iter()
            .filter(|b| b[0] < t1 && b[1] > t0)
            .map(|b| b[1])
            .fold(None, |acc: Option<f64>, e| {
                Some(acc.map_or(e, |a| a.max(e)))
            });
        if let Some(resume) = hit {
            layout.dropped += 1;
            let next = t.partition_point(|&x| x < resume);
            start = next.max(start + 1);
            continue;
        }
        layout.windows.push(PathWindow {
            start,
            end,
            t_start: t0,
            t_end: t1,
        });
        let step = (1.0 - overlap) * window_m;
        let next = start + 1 + s[start + 1..].partition_point(|&x| x < s[start] + step);
        start = next.max(start + 1);
    }
    Ok(layout)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    const ALL: [f64; 2] = [f64::NEG_INFINITY, f64::INFINITY];

    fn line(n: usize) -> (Vec<f64>, Vec<Vector3<f64>>) {
        (0..n)
            .map(|i| (i as f64, Vector3::new(i as f64, 0.0, 0.0)))
            .unzip()
    }

    #[test]
    fn disjoint_windows_drop_the_tail() {
        let (t, p) = line(23); // 22 m
        let path = DecimatedPath::new(&t, &p, 0.5, &[]);
        let l = path_windows(&path, 5.0, 0.0, ALL, &[]).unwrap();
        let spans: Vec<_> = l.windows.iter().map(|w| (w.start, w.end)).collect();
        assert_eq!(spans, vec![(0, 5), (5, 10), (10, 15), (15, 20)]);
        assert_eq!(l.dropped, 0);
    }

    #[test]
    fn overlap_and_gaps() {
        let (t, p) = line(23);
        let path = DecimatedPath::new(&t, &p, 0.5, &[]);
        let l = path_windows(&path, 5.0, 0.6, ALL, &[]).unwrap();
        assert_eq!(l.windows[1].start, 2);
        let l = path_windows(&path, 5.0, 0.0, ALL, &[[7.0, 8.0]]).unwrap();
        let spans: Vec<_> = l.windows.iter().map(|w| (w.start, w.end)).collect();
        assert_eq!(spans, vec![(0, 5), (8, 13), (13, 18)]);
        assert_eq!(l.dropped, 1);
        let l = path_windows(&path, 5.0, 0.0, [1.5, 17.0], &[]).unwrap();
        let spans: Vec<_> = l.windows.iter().map(|w| (w.start, w.end)).collect();
        assert_eq!(spans, vec![(2, 7), (7, 12), (12, 17)]);
        assert!(path_windows(&path, 5.0, 1.0, ALL, &[]).is_err());
        assert!(path_windows(&path, 0.0, 0.0, ALL, &[]).is_err());
    }
}
