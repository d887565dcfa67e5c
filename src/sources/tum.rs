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

/// [`read_tum`], and what became of every row ([`Trajectory::clean`]: sorted, repeated stamps and rows
/// not finite dropped and counted).
pub fn read_tum_audited(path: &Path) -> Result<(Trajectory, RowAudit)> {
    let mut t = read_tum_rows(path)?;
    let audit = t.clean();
    Ok((t, audit))
}

/// Reads a TUM file but keeps the rows as written (no sorting, repeated stamps and rows not finite
/// kept): evo's readers do so, and `trajdrift ape`/`rpe` must pair the same poses to give its numbers.
pub fn read_tum_rows(path: &Path) -> Result<Trajectory> {
    read_tum_rows_with(path, true)
}

/// [`read_tum_rows`], reading the orientation columns only when `orientation` is true (a metric on
/// positions alone then reads a million rows faster and keeps half the memory).
pub fn read_tum_rows_with(path: &Path, orientation: bool) -> Result<Trajectory> {
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let mut reader = BufReader::with_capacity(1 << 16, file);
    let mut traj: Option<Trajectory> = None;
    // One reused line buffer and a fixed array of fields: files of millions of poses are read at the
    // speed of the number parsing, without an allocation per line.
    let mut buf = String::new();
    let mut i = 0usize;
    loop {
        buf.clear();
        if reader.read_line(&mut buf).map_err(|e| Error::io(path, e))? == 0 {
            break;
        }
        i += 1;
        let line = buf.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let bad = |detail: String| Error::TextFormat {
            path: path.to_path_buf(),
            line: i,
            detail,
        };
        let mut vals = [0.0f64; 8];
        let mut n = 0usize;
        let mut stamp_ns = None;
        let mut k = 0usize;
        while let Some(f) = next_field(line, &mut k, orientation || n < 4) {
            let v = f
                .value()
                .ok_or_else(|| bad(format!("`{}` is not a number", f.text)))?;
            if n == 0 {
                stamp_ns = Some(f.stamp_ns());
            }
            if n < 8 {
                vals[n] = v;
            }
            n += 1;
        }
        if n != 8 && n != 4 {
            return Err(bad(format!("{n} values on the line")));
        }
        let t = traj.get_or_insert_with(|| Trajectory::new(n == 8 && orientation));
        let stamp_ns = stamp_ns
            .flatten()
            .ok_or_else(|| bad("bad timestamp".into()))?;
        let p = Vector3::new(vals[1], vals[2], vals[3]);
        let q = (n == 8 && orientation).then(|| {
            UnitQuaternion::from_quaternion(Quaternion::new(vals[7], vals[4], vals[5], vals[6]))
        });
        t.push(stamp_ns, p, q);
    }
    Ok(traj.unwrap_or_default())
}

/// One field of a line, scanned once: its text and, when it is a plain decimal (`-12.345678`, at
/// most 19 digits), its digits as an integer and the number of fraction digits.
struct Field<'a> {
    text: &'a str,
    /// (negative, digits, fraction digits).
    plain: Option<(bool, u64, usize)>,
}

impl Field<'_> {
    /// The number. Hand-written fast path (Clinger's): digits below 2^53 over 10^k are two exact
    /// doubles and one correctly rounded division, the same double `str::parse` gives, at a fraction
    /// of the time (it matters at millions of rows); anything else goes to `str::parse`.
    fn value(&self) -> Option<f64> {
        const POW10: [f64; 23] = [
            1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
            1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
        ];
        match self.plain {
            Some((neg, m, frac)) if m <= 1 << 53 && frac < POW10.len() => {
                let v = m as f64 / POW10[frac];
                Some(if neg { -v } else { v })
            }
            _ => self.text.parse().ok(),
        }
    }

    /// The field as a stamp in nanoseconds without a detour through `f64` ([`parse_stamp_ns`] for
    /// anything but a plain non-negative decimal with at most 9 fraction digits).
    fn stamp_ns(&self) -> Option<i64> {
        match self.plain {
            Some((false, m, frac)) if frac <= 9 => i64::try_from(m)
                .ok()?
                .checked_mul(10i64.pow(9 - frac as u32)),
            _ => parse_stamp_ns(self.text),
        }
    }
}

/// The next field of `line` from byte `k` (fields are runs between spaces, tabs and commas); with
/// `parse` false the field is only delimited (its value reads as 0).
fn next_field<'a>(line: &'a str, k: &mut usize, parse: bool) -> Option<Field<'a>> {
    let b = line.as_bytes();
    let sep = |c: u8| c == b' ' || c == b'\t' || c == b',' || c == b'\r';
    while *k < b.len() && sep(b[*k]) {
        *k += 1;
    }
    if *k == b.len() {
        return None;
    }
    let start = *k;
    if !parse {
        while *k < b.len() && !sep(b[*k]) {
            *k += 1;
        }
        return Some(Field {
            text: &line[start..*k],
            plain: Some((false, 0, 0)),
        });
    }
    let neg = b[*k] == b'-';
    if neg || b[*k] == b'+' {
        *k += 1;
    }
    let (mut m, mut digits, mut frac, mut dot, mut plain) = (0u64, 0usize, 0usize, false, true);
    while *k < b.len() && !sep(b[*k]) {
        match b[*k] {
            c @ b'0'..=b'9' if digits < 19 => {
                m = m * 10 + u64::from(c - b'0');
                digits += 1;
                frac += usize::from(dot);
            }
            b'.' if !dot => dot = true,
            _ => plain = false,
        }
        *k += 1;
    }
    // Separators are ASCII: both ends are char boundaries.
    Some(Field {
        text: &line[start..*k],
        plain: (plain && digits > 0).then_some((neg, m, frac)),
    })
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
    fn fast_numbers_equal_std_parse() {
        let line = "0 -0.5 1311868164.363181 0.123456789 -12.000001 +3.25 1.5e3 1e-7 \
                    123456789012345678 0.1234567890123456789 nan inf 1. 12345678901234567890123";
        let mut k = 0;
        while let Some(f) = next_field(line, &mut k, true) {
            let want: Option<f64> = f.text.parse().ok();
            assert_eq!(
                f.value().map(f64::to_bits),
                want.map(f64::to_bits),
                "{}",
                f.text
            );
        }
        let mut k = 0;
        let f = next_field(" .,1x", &mut k, true).unwrap();
        assert_eq!((f.text, f.value()), (".", None));
        let f = next_field(" .,1x", &mut k, true).unwrap();
        assert_eq!((f.text, f.value()), ("1x", None));
        for (s, ns) in [
            ("1700000000.010000", Some(1_700_000_000_010_000_000)),
            ("12", Some(12_000_000_000)),
            ("-1.5", Some(-1_500_000_000)),
            ("1718460000.123456789", Some(1_718_460_000_123_456_789)),
        ] {
            let mut k = 0;
            assert_eq!(next_field(s, &mut k, true).unwrap().stamp_ns(), ns, "{s}");
        }
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
