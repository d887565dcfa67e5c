//! KITTI odometry poses: 12 whitespace-separated values a row, the first three rows of the 4×4 pose
//! matrix `[R | t]` (camera to world), one row per frame and no stamps. The stamps come from the
//! sequence's `times.txt` (one time in seconds a row) when given; without it frame `i` is stamped
//! `i · 0.1 s` (KITTI's 10 Hz), which is what evo assumes too.
//!
//! Hand-written: one line of numbers per pose, no maintained crate reads it.

use std::io::{BufRead, BufReader};
use std::path::Path;

use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};

use crate::error::{Error, Result};
use crate::sources::tum::parse_stamp_ns;
use crate::trajectory::rows::RowAudit;
use crate::trajectory::Trajectory;

/// Frame period assumed when no times file is given (KITTI records at 10 Hz), nanoseconds.
pub const KITTI_DEFAULT_PERIOD_NS: i64 = 100_000_000;

const HINT: &str = "expected KITTI rows of 12 numbers (a 3x4 pose matrix, row-major)";

/// Reads a KITTI pose file, stamped by `times` (a KITTI `times.txt`) when given, else `i · 0.1 s`.
pub fn read_kitti(path: &Path, times: Option<&Path>) -> Result<Trajectory> {
    read_kitti_audited(path, times).map(|(t, _)| t)
}

/// [`read_kitti`], and what became of every row ([`Trajectory::clean`]).
pub fn read_kitti_audited(path: &Path, times: Option<&Path>) -> Result<(Trajectory, RowAudit)> {
    let stamps = times.map(read_times).transpose()?;
    let mut traj = Trajectory::new(true);
    let mut row = 0usize;
    for_each_row(path, |i, v| {
        let bad = |detail: String| Error::Text {
            path: path.to_path_buf(),
            line: i + 1,
            detail,
            hint: HINT.into(),
        };
        let stamp = match &stamps {
            Some(s) => *s.get(row).ok_or_else(|| {
                bad(format!(
                    "pose {} has no time: the times file has only {} rows",
                    row + 1,
                    s.len()
                ))
            })?,
            None => row as i64 * KITTI_DEFAULT_PERIOD_NS,
        };
        row += 1;
        let (m, p) = matrix_of(v);
        if !p.iter().all(|x| x.is_finite()) || !m.iter().all(|x| x.is_finite()) {
            // Kept as a NaN row so that `clean` counts it as not finite.
            traj.push(stamp, Vector3::repeat(f64::NAN), None);
            return Ok(());
        }
        if m.iter().any(|x| x.abs() > 1.5) {
            // Not a rotation (its entries are within ±1): nalgebra's projection never ends on such a
            // matrix (a value of 7e17, found by fuzzing). Kept as a row out of range, which `clean`
            // counts and drops.
            traj.push(stamp, Vector3::repeat(f64::MAX), None);
            return Ok(());
        }
        // The matrices are rounded to 7 digits: project onto the nearest rotation, in bounded
        // iterations (`from_matrix` loops until it converges).
        let r = Rotation3::from_matrix_eps(&m, f64::EPSILON, 100, Rotation3::identity());
        traj.push(stamp, p, Some(UnitQuaternion::from_rotation_matrix(&r)));
        Ok(())
    })?;
    if let Some(s) = &stamps {
        if s.len() != row {
            return Err(Error::Text {
                path: path.to_path_buf(),
                line: 0,
                detail: format!("{row} poses but {} times in the times file", s.len()),
                hint: "pass the times.txt of the same sequence".into(),
            });
        }
    }
    let audit = traj.clean();
    Ok((traj, audit))
}

/// The rows of a KITTI pose file as written: the rotation part unprojected (evo computes with these
/// matrices, and its RPE over 100 m moves in the 6th decimal if they are made orthonormal), one entry
/// per row.
pub fn read_kitti_matrices(path: &Path) -> Result<Vec<(Matrix3<f64>, Vector3<f64>)>> {
    let mut out = Vec::new();
    for_each_row(path, |_, v| {
        out.push(matrix_of(v));
        Ok(())
    })?;
    Ok(out)
}

fn matrix_of(v: &[f64]) -> (Matrix3<f64>, Vector3<f64>) {
    (
        Matrix3::new(v[0], v[1], v[2], v[4], v[5], v[6], v[8], v[9], v[10]),
        Vector3::new(v[3], v[7], v[11]),
    )
}

/// Calls `f(line index, 12 values)` for every pose row; a row of another width is an error.
fn for_each_row(path: &Path, mut f: impl FnMut(usize, &[f64]) -> Result<()>) -> Result<()> {
    let file = crate::sources::input::open_text(path)?;
    for (i, line) in BufReader::new(file).lines().enumerate() {
        let line = line.map_err(|e| Error::io(path, e))?;
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let bad = |detail: String| Error::Text {
            path: path.to_path_buf(),
            line: i + 1,
            detail,
            hint: HINT.into(),
        };
        let v: Vec<f64> = line
            .split_whitespace()
            .map(|s| {
                s.parse::<f64>()
                    .map_err(|_| bad(format!("`{s}` is not a number")))
            })
            .collect::<Result<_>>()?;
        if v.len() != 12 {
            return Err(bad(format!("{} values on the line", v.len())));
        }
        f(i, &v)?;
    }
    Ok(())
}

/// Reads a KITTI `times.txt`: one time in seconds a row.
pub fn read_times(path: &Path) -> Result<Vec<i64>> {
    let file = crate::sources::input::open_text(path)?;
    let mut out = Vec::new();
    for (i, line) in BufReader::new(file).lines().enumerate() {
        let line = line.map_err(|e| Error::io(path, e))?;
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        out.push(parse_stamp_ns(line).ok_or_else(|| Error::Text {
            path: path.to_path_buf(),
            line: i + 1,
            detail: format!("`{line}` is not a time"),
            hint: "expected a KITTI times file: one time in seconds a row".into(),
        })?);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    #[test]
    fn reads_pose_rows_with_and_without_times() {
        let dir = tempfile::tempdir().unwrap();
        let poses = dir.path().join("00.txt");
        let mut f = std::fs::File::create(&poses).unwrap();
        writeln!(f, "1 0 0 1.5 0 1 0 -2 0 0 1 3").unwrap();
        writeln!(f, "0 -1 0 2 1 0 0 0 0 0 1 0").unwrap();
        drop(f);
        let t = read_kitti(&poses, None).unwrap();
        assert_eq!(t.stamps_ns, vec![0, 100_000_000]);
        assert_eq!(t.positions[0], Vector3::new(1.5, -2.0, 3.0));
        let yaw = t.orientations.as_ref().unwrap()[1].euler_angles().2;
        assert!((yaw - std::f64::consts::FRAC_PI_2).abs() < 1e-12);

        let times = dir.path().join("times.txt");
        std::fs::write(&times, "0.000000e+00\n1.037359e-01\n").unwrap();
        let t = read_kitti(&poses, Some(&times)).unwrap();
        assert_eq!(t.stamps_ns, vec![0, 103_735_900]);

        std::fs::write(&times, "0.0\n").unwrap();
        let e = read_kitti(&poses, Some(&times)).unwrap_err().to_string();
        assert!(e.contains("times file has only 1 rows"), "{e}");
    }

    #[test]
    fn wrong_width_is_a_clear_error() {
        let dir = tempfile::tempdir().unwrap();
        let poses = dir.path().join("00.txt");
        std::fs::write(&poses, "1 0 0 1.5 0 1 0 -2 0 0 1\n").unwrap();
        let e = read_kitti(&poses, None).unwrap_err().to_string();
        assert!(e.contains(":1: 11 values") && e.contains("KITTI"), "{e}");
    }
}
