//! What happened to every row (message, text line) read for a trajectory: how many were read, how
//! many were dropped and why, how many came with a stamp going back (kept, sorted into place). The
//! report and the table say it, so `807 rows, 803 samples` is never a mystery.

use nalgebra::Vector3;

use super::Trajectory;

/// A coordinate beyond this (metres, or degrees before the ENU conversion) is not a position on
/// Earth or near it: the row is dropped as out of range rather than turning path lengths into inf.
pub const MAX_COORDINATE: f64 = 1.0e9;

/// Rows of one trajectory, by what became of them.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct RowAudit {
    /// Rows read (messages on the topic, data lines of the file).
    pub read: u64,
    /// Dropped: a coordinate NaN or infinite, or an invalid fix (NO_FIX).
    pub not_finite: u64,
    /// Dropped: a coordinate beyond [`MAX_COORDINATE`].
    pub out_of_range: u64,
    /// Dropped: the stamp repeats an earlier row's (the first is kept).
    pub duplicate_stamp: u64,
    /// Dropped: a TF chain sample at a time some edge of the chain has no transform for.
    #[serde(default)]
    pub outside_tf_span: u64,
    /// Kept: the stamp is earlier than the previous row's (sorted into place).
    pub stamp_going_back: u64,
}

impl RowAudit {
    /// Rows dropped, all reasons.
    pub fn dropped(&self) -> u64 {
        self.not_finite + self.out_of_range + self.duplicate_stamp + self.outside_tf_span
    }

    /// Adds `other`'s counts.
    pub fn add(&mut self, other: &RowAudit) {
        self.read += other.read;
        self.not_finite += other.not_finite;
        self.out_of_range += other.out_of_range;
        self.duplicate_stamp += other.duplicate_stamp;
        self.outside_tf_span += other.outside_tf_span;
        self.stamp_going_back += other.stamp_going_back;
    }

    /// `807 rows read, 4 dropped (4 duplicate stamp)`, or `None` when nothing happened worth saying.
    ///
    /// ```
    /// use trajdrift_core::trajectory::rows::RowAudit;
    /// let a = RowAudit { read: 807, duplicate_stamp: 4, ..Default::default() };
    /// assert_eq!(a.describe().unwrap(), "807 rows read, 4 dropped (4 duplicate stamp)");
    /// ```
    pub fn describe(&self) -> Option<String> {
        if self.dropped() == 0 && self.stamp_going_back == 0 {
            return None;
        }
        let reasons: Vec<String> = [
            (self.not_finite, "not finite"),
            (self.out_of_range, "out of range"),
            (self.duplicate_stamp, "duplicate stamp"),
            (self.outside_tf_span, "outside the TF span"),
        ]
        .iter()
        .filter(|(n, _)| *n > 0)
        .map(|(n, what)| format!("{n} {what}"))
        .collect();
        let mut s = format!("{} rows read, {} dropped", self.read, self.dropped());
        if !reasons.is_empty() {
            s.push_str(&format!(" ({})", reasons.join(", ")));
        }
        if self.stamp_going_back > 0 {
            s.push_str(&format!(
                ", {} with a stamp going back (kept, sorted)",
                self.stamp_going_back
            ));
        }
        Some(s)
    }
}

/// Whether a position is usable: finite and within [`MAX_COORDINATE`]; `Err` says why not.
fn usable(p: &Vector3<f64>) -> Result<(), bool> {
    if !p.iter().all(|v| v.is_finite()) {
        Err(false)
    } else if p.iter().any(|v| v.abs() > MAX_COORDINATE) {
        Err(true)
    } else {
        Ok(())
    }
}

/// Whether a position is usable: finite and within [`MAX_COORDINATE`] (the rows
/// [`Trajectory::clean`] keeps; evo's readers, which keep the rows in file order, drop the others by
/// it too).
pub fn usable_position(p: &Vector3<f64>) -> bool {
    usable(p).is_ok()
}

impl Trajectory {
    /// Makes the trajectory usable and says what it took: counts stamps going back (file order),
    /// drops positions not finite or out of range, sorts by stamp and drops repeated stamps.
    /// `audit.read` is set to the rows held before.
    pub fn clean(&mut self) -> RowAudit {
        let mut audit = RowAudit {
            read: self.len() as u64,
            ..RowAudit::default()
        };
        audit.stamp_going_back = self.stamps_ns.windows(2).filter(|w| w[1] < w[0]).count() as u64;
        let keep: Vec<bool> = self
            .positions
            .iter()
            .map(|p| match usable(p) {
                Ok(()) => true,
                Err(false) => {
                    audit.not_finite += 1;
                    false
                }
                Err(true) => {
                    audit.out_of_range += 1;
                    false
                }
            })
            .collect();
        if keep.iter().any(|k| !k) {
            self.retain(&keep);
        }
        audit.duplicate_stamp = self.sort_dedup() as u64;
        audit
    }

    /// Keeps the samples whose `keep` is true.
    fn retain(&mut self, keep: &[bool]) {
        let mut i = 0;
        self.stamps_ns.retain(|_| (keep[i], i += 1).0);
        let mut i = 0;
        self.positions.retain(|_| (keep[i], i += 1).0);
        if let Some(o) = self.orientations.as_mut() {
            let mut i = 0;
            o.retain(|_| (keep[i], i += 1).0);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_every_reason() {
        let mut t = Trajectory::new(false);
        for (s, x) in [
            (3, 0.0),
            (1, 1.0),
            (1, 2.0),
            (2, f64::NAN),
            (4, 1e300),
            (5, 0.5),
        ] {
            t.push(s, Vector3::new(x, 0.0, 0.0), None);
        }
        let a = t.clean();
        assert_eq!(
            a,
            RowAudit {
                read: 6,
                not_finite: 1,
                out_of_range: 1,
                duplicate_stamp: 1,
                outside_tf_span: 0,
                stamp_going_back: 1,
            }
        );
        assert_eq!(t.stamps_ns, vec![1, 3, 5]);
    }
}
