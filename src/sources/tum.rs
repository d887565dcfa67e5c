//! TUM trajectory text (`timestamp x y z qx qy qz qw`, seconds, `#` comments), the lingua franca of
//! evo and most SLAM papers. Read for either side of an evaluation; written by `--export-aligned`.
//!
//! Hand-written: the format is one whitespace-separated line per pose and no maintained crate reads it.

use std::io::{BufRead, BufReader, Write};
use std::path::Path;

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use crate::error::{Error, Result};
use crate::trajectory::rows::RowAudit;
use crate::trajectory::Trajectory;

/// Reads a TUM file. Lines with 4 values (`t x y z`) give a position-only trajectory; 8 values add the
/// orientation. Stamps are parsed as seconds and rounded to the nanosecond.
pub fn read_tum(path: &Path) -> Result<Trajectory> {
    read_tum_audited(path).map(|(t, _)| t)
}

/// [`read_tum`], and what became of every row ([`Trajectory::clean`]).
pub fn read_tum_audited(path: &Path) -> Result<(Trajectory, RowAudit)> {
    let mut t = read_tum_rows(path)?;
    let audit = t.clean();
    Ok((t, audit))
}

/// Every row of a TUM file in file order, unsorted, rows not finite included.
fn read_tum_rows(path: &Path) -> Result<Trajectory> {
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let mut traj: Option<Trajectory> = None;
    for (i, line) in BufReader::new(file).lines().enumerate() {
        let line = line.map_err(|e| Error::io(path, e))?;
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let bad = |detail: String| Error::TextFormat {
            path: path.to_path_buf(),
            line: i + 1,
            detail,
        };
        let vals: Vec<f64> = line
            .split(|c: char| c.is_whitespace() || c == ',')
            .filter(|s| !s.is_empty())
            .map(|s| {
                s.parse::<f64>()
                    .map_err(|_| bad(format!("`{s}` is not a number")))
            })
            .collect::<Result<_>>()?;
        if vals.len() != 8 && vals.len() != 4 {
            return Err(bad(format!("{} values on the line", vals.len())));
        }
        let t = traj.get_or_insert_with(|| Trajectory::new(vals.len() == 8));
        let stamp_ns = parse_stamp_ns(line).ok_or_else(|| bad("bad timestamp".into()))?;
        let p = Vector3::new(vals[1], vals[2], vals[3]);
        let q = (vals.len() == 8).then(|| {
            UnitQuaternion::from_quaternion(Quaternion::new(vals[7], vals[4], vals[5], vals[6]))
        });
        t.push(stamp_ns, p, q);
    }
    Ok(traj.unwrap_or_default())
}

/// Parses the first field of a TUM line as integer nanoseconds without going through `f64`, so that
/// `1718460000.123456789` keeps every digit.
pub(crate) fn parse_stamp_ns(line: &str) -> Option<i64> {
    let field = line.split(|c: char| c.is_whitespace() || c == ',').next()?;
    if field.contains(['e', 'E']) {
        let v: f64 = field.parse().ok()?;
        return Some((v * 1e9).round() as i64);
    }
    let (neg, field) = match field.strip_prefix('-') {
        Some(f) => (true, f),
        None => (false, field),
    };
    let (int, frac) = field.split_once('.').unwrap_or((field, ""));
    let secs: i64 = if int.is_empty() { 0 } else { int.parse().ok()? };
    let mut frac_ns: i64 = 0;
    let mut scale = 100_000_000;
    for (k, c) in frac.chars().enumerate() {
        let d = c.to_digit(10)? as i64;
        if k < 9 {
            frac_ns += d * scale;
            scale /= 10;
        } else if k == 9 && d >= 5 {
            frac_ns += 1;
            break;
        } else {
            break;
        }
    }
    let ns = secs.checked_mul(1_000_000_000)?.checked_add(frac_ns)?;
    Some(if neg { -ns } else { ns })
}

/// Writes `traj` as TUM (nanosecond stamps printed exactly; identity orientation when it has none).
pub fn write_tum<W: Write>(out: W, traj: &Trajectory) -> std::io::Result<()> {
    write_rows(out, traj, ' ')
}

/// Writes one `t x y z qx qy qz qw` row per sample with `sep` between the values: stamps printed exactly
/// as seconds with nine decimals, identity orientation when the trajectory has none. Shared by the TUM and
/// CSV writers.
pub(crate) fn write_rows<W: Write>(
    mut out: W,
    traj: &Trajectory,
    sep: char,
) -> std::io::Result<()> {
    for i in 0..traj.len() {
        let t = traj.stamps_ns[i];
        let p = traj.positions[i];
        let q = traj
            .orientations
            .as_ref()
            .map(|o| o[i])
            .unwrap_or_else(UnitQuaternion::identity);
        let sign = if t < 0 { "-" } else { "" };
        let a = t.unsigned_abs();
        write!(out, "{sign}{}.{:09}", a / 1_000_000_000, a % 1_000_000_000)?;
        for v in [p.x, p.y, p.z, q.i, q.j, q.k, q.w] {
            write!(out, "{sep}{v:.9}")?;
        }
        writeln!(out)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stamps_keep_every_digit() {
        assert_eq!(
            parse_stamp_ns("1718460000.123456789 0 0 0"),
            Some(1_718_460_000_123_456_789)
        );
        assert_eq!(parse_stamp_ns("12.5 0"), Some(12_500_000_000));
        assert_eq!(parse_stamp_ns("-0.25"), Some(-250_000_000));
        assert_eq!(parse_stamp_ns("1.5e9"), Some(1_500_000_000_000_000_000));
    }

    #[test]
    fn round_trip() {
        let mut t = Trajectory::new(true);
        t.push(
            1_718_460_000_000_000_001,
            Vector3::new(1.0, -2.0, 3.5),
            None,
        );
        t.push(
            1_718_460_000_100_000_001,
            Vector3::new(1.5, -2.0, 3.5),
            None,
        );
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.tum");
        write_tum(std::fs::File::create(&path).unwrap(), &t).unwrap();
        let back = read_tum(&path).unwrap();
        assert_eq!(back.stamps_ns, t.stamps_ns);
        assert_eq!(back.positions, t.positions);
    }
}
