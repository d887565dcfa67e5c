//! The trajectory: what every source produces and every method consumes.
//!
//! Stamps are kept as integer nanoseconds (the recording's own resolution, so that a shifted stamp can be
//! written back exactly); the maths work on `f64` seconds relative to a common origin `t0`, which keeps
//! sub-microsecond resolution over missions of days.

pub mod extrinsics;
pub mod rows;
pub(crate) mod tf_compose;

use nalgebra::{UnitQuaternion, Vector3};

/// A time-ordered sequence of positions, with orientations when the source carries them.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Trajectory {
    /// Sample stamps in nanoseconds (Unix epoch for ROS stamps), strictly increasing after [`Trajectory::sort_dedup`].
    pub stamps_ns: Vec<i64>,
    /// Positions in metres, in the source's frame.
    pub positions: Vec<Vector3<f64>>,
    /// Orientations (body to frame), one per sample, when the source has them.
    pub orientations: Option<Vec<UnitQuaternion<f64>>>,
}

impl Trajectory {
    /// An empty trajectory that will hold orientations when `with_orientation` is true.
    pub fn new(with_orientation: bool) -> Self {
        Trajectory {
            stamps_ns: Vec::new(),
            positions: Vec::new(),
            orientations: with_orientation.then(Vec::new),
        }
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.stamps_ns.len()
    }

    /// True when there is no sample.
    pub fn is_empty(&self) -> bool {
        self.stamps_ns.is_empty()
    }

    /// Appends a sample. `orientation` is ignored when the trajectory holds none; when it holds some and
    /// none is given, the identity is stored.
    pub fn push(
        &mut self,
        stamp_ns: i64,
        position: Vector3<f64>,
        orientation: Option<UnitQuaternion<f64>>,
    ) {
        self.stamps_ns.push(stamp_ns);
        self.positions.push(position);
        if let Some(o) = self.orientations.as_mut() {
            o.push(orientation.unwrap_or_else(UnitQuaternion::identity));
        }
    }

    /// Sorts samples by stamp (stable) and drops samples whose stamp repeats the previous one.
    /// Returns the number of samples dropped. Recorders write out of order around chunk boundaries and
    /// some drivers publish the same stamp twice; every method needs strictly increasing time.
    pub fn sort_dedup(&mut self) -> usize {
        let n = self.len();
        if self.stamps_ns.windows(2).all(|w| w[0] < w[1]) {
            // Already in order (the usual case): no index or copy the size of the trajectory.
            return 0;
        }
        let mut idx: Vec<usize> = (0..n).collect();
        idx.sort_by_key(|&i| self.stamps_ns[i]);
        let mut keep: Vec<usize> = Vec::with_capacity(n);
        for i in idx {
            if keep
                .last()
                .is_some_and(|&j| self.stamps_ns[j] == self.stamps_ns[i])
            {
                continue;
            }
            keep.push(i);
        }
        let dropped = n - keep.len();
        self.stamps_ns = keep.iter().map(|&i| self.stamps_ns[i]).collect();
        self.positions = keep.iter().map(|&i| self.positions[i]).collect();
        if let Some(o) = self.orientations.as_ref() {
            let sorted = keep.iter().map(|&i| o[i]).collect();
            self.orientations = Some(sorted);
        }
        dropped
    }

    /// Stamps in seconds relative to `t0_ns`.
    pub fn times_s(&self, t0_ns: i64) -> Vec<f64> {
        self.stamps_ns
            .iter()
            .map(|&t| (t - t0_ns) as f64 * 1e-9)
            .collect()
    }

    /// Keeps the samples whose stamp lies in `[start_ns, end_ns]`.
    pub fn crop(&mut self, start_ns: Option<i64>, end_ns: Option<i64>) {
        let keep: Vec<bool> = self
            .stamps_ns
            .iter()
            .map(|&t| start_ns.is_none_or(|s| t >= s) && end_ns.is_none_or(|e| t <= e))
            .collect();
        let mut k = keep.iter();
        self.stamps_ns.retain(|_| *k.next().unwrap_or(&false));
        let mut k = keep.iter();
        self.positions.retain(|_| *k.next().unwrap_or(&false));
        if let Some(o) = self.orientations.as_mut() {
            let mut k = keep.iter();
            o.retain(|_| *k.next().unwrap_or(&false));
        }
    }

    /// Returns a copy with every stamp shifted by `offset_ns` (the estimate's stamps become t + Δt).
    pub fn shifted(&self, offset_ns: i64) -> Trajectory {
        let mut t = self.clone();
        for s in &mut t.stamps_ns {
            *s += offset_ns;
        }
        t
    }

    /// Applies `p ↦ R p + t` to every position (and `q ↦ R q` to orientations).
    pub fn transformed(
        &self,
        rotation: &UnitQuaternion<f64>,
        translation: &Vector3<f64>,
    ) -> Trajectory {
        let mut t = self.clone();
        for p in &mut t.positions {
            *p = rotation * *p + translation;
        }
        if let Some(o) = t.orientations.as_mut() {
            for q in o {
                *q = rotation * *q;
            }
        }
        t
    }

    /// First and last stamp, if any.
    pub fn span_ns(&self) -> Option<(i64, i64)> {
        Some((*self.stamps_ns.first()?, *self.stamps_ns.last()?))
    }

    /// The typical sampling period, seconds: the median interval between consecutive stamps,
    /// taken on the integer stamps by selection (the upper of the two middle intervals for an even
    /// count, as [`crate::stats::median_step`] on seconds); `None` with fewer than two samples.
    /// Gaps and jitter barely move it.
    ///
    /// ```
    /// use trajdrift_core::trajectory::Trajectory;
    /// use nalgebra::Vector3;
    /// let mut t = Trajectory::new(false);
    /// for ns in [0, 100_000_000, 200_000_000, 1_200_000_000] {
    ///     t.push(ns, Vector3::zeros(), None);
    /// }
    /// assert_eq!(t.median_period_s(), Some(0.1));
    /// assert_eq!(Trajectory::new(false).median_period_s(), None);
    /// ```
    pub fn median_period_s(&self) -> Option<f64> {
        let mut d: Vec<i64> = self.stamps_ns.windows(2).map(|w| w[1] - w[0]).collect();
        if d.is_empty() {
            return None;
        }
        let k = d.len() / 2;
        Some(*d.select_nth_unstable(k).1 as f64 * 1e-9)
    }
}
