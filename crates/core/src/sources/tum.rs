//! TUM trajectory text (`timestamp x y z qx qy qz qw`, seconds, `#` comments), the lingua franca of
//! evo and most SLAM papers. Read for either side of an evaluation; written by `--export-aligned`.
//!
//! Hand-written: the format is one whitespace-separated line per pose and no maintained crate reads it.

use std::io::{Read, Write};
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

/// Bytes read at once: large enough that read calls cost nothing, small enough that memory does not
/// grow with the file (a whole-file read would double the peak memory of a million-pose evaluation).
const CHUNK: usize = 1 << 20;

/// [`read_tum_rows`], reading the orientation columns only when `orientation` is true (a metric on
/// positions alone then reads a million rows faster and keeps half the memory).
///
/// The file is read in chunks of `CHUNK` bytes and every whole line is parsed straight from the
/// chunk as bytes (no line copy, no UTF-8 pass: fields are ASCII numbers, anything else is reported
/// as not a number); a partial last line moves to the front of the buffer for the next read.
pub fn read_tum_rows_with(path: &Path, orientation: bool) -> Result<Trajectory> {
    let (mut traj, quats) = read_rows(path, orientation, false)?;
    traj.orientations = quats.map(TumOrientations::into_quaternions);
    Ok(traj)
}

/// [`read_tum_rows_with`], the orientations apart and kept as the file's decimal digits when every
/// row allows ([`DecimalQuaternions`]: half the memory of a million quaternions).
pub fn read_tum_rows_compact(
    path: &Path,
    orientation: bool,
) -> Result<(Trajectory, Option<TumOrientations>)> {
    read_rows(path, orientation, true)
}

/// Reads the rows: the trajectory without orientations, and the orientations (decimal digits when
/// `compact` and every row allows).
fn read_rows(
    path: &Path,
    orientation: bool,
    compact: bool,
) -> Result<(Trajectory, Option<TumOrientations>)> {
    let mut file = crate::sources::input::open_text(path)?;
    let mut rows = RowReader {
        path,
        orientation,
        compact,
        line: 0,
        traj: None,
        quats: None,
    };
    let mut buf = vec![0u8; CHUNK];
    let mut filled = 0usize;
    loop {
        if filled == buf.len() {
            buf.resize(buf.len() * 2, 0); // a line longer than the buffer
        }
        let n = read_some(&mut file, &mut buf[filled..]).map_err(|e| Error::io(path, e))?;
        filled += n;
        let end = match (n, memchr::memrchr(b'\n', &buf[..filled])) {
            (0, _) => filled,
            (_, Some(i)) => i + 1,
            (_, None) => continue,
        };
        rows.lines(&buf[..end])?;
        buf.copy_within(end..filled, 0);
        filled -= end;
        if n == 0 {
            return Ok((rows.traj.unwrap_or_default(), rows.quats));
        }
    }
}

/// The orientations of a TUM file.
#[derive(Debug, Clone, PartialEq)]
pub enum TumOrientations {
    /// As written (`qx qy qz qw` decimals with one number of fraction digits, at most 9).
    Decimal(DecimalQuaternions),
    /// Parsed.
    Quaternions(Vec<UnitQuaternion<f64>>),
}

impl TumOrientations {
    /// The unit quaternions.
    pub fn into_quaternions(self) -> Vec<UnitQuaternion<f64>> {
        match self {
            TumOrientations::Decimal(d) => (0..d.digits.len()).map(|i| d.get(i)).collect(),
            TumOrientations::Quaternions(q) => q,
        }
    }

    /// Appends a row's orientation: its plain fields (see [`Field`]) when it has them, and the parsed
    /// quaternion; the first row that does not fit the digits turns them into quaternions.
    fn push(
        &mut self,
        fields: Option<[Option<(bool, u64, usize)>; 4]>,
        q: impl FnOnce() -> UnitQuaternion<f64>,
    ) {
        if let TumOrientations::Decimal(d) = self {
            match fields.and_then(|f| d.encode(f)) {
                Some(e) => return d.digits.push(e),
                None => *self = TumOrientations::Quaternions(self.clone().into_quaternions()),
            }
        }
        if let TumOrientations::Quaternions(v) = self {
            v.push(q());
        }
    }
}

/// Quaternions as the file's decimals: each component `±m / 10^frac` (sign in the lowest bit, so
/// `-0.0` stays), one `frac` for the file. [`DecimalQuaternions::get`] gives the very quaternion the
/// parser gives (same division, same normalisation) from 16 bytes a row instead of 32.
#[derive(Debug, Clone, PartialEq)]
pub struct DecimalQuaternions {
    /// `qx qy qz qw` of each row, `m << 1 | negative`.
    pub digits: Vec<[u32; 4]>,
    /// Fraction digits of every component.
    pub frac: usize,
}

impl DecimalQuaternions {
    /// The unit quaternion of row `i`.
    pub fn get(&self, i: usize) -> UnitQuaternion<f64> {
        let v = self.digits[i].map(|e| decimal(e & 1 == 1, u64::from(e >> 1), self.frac));
        UnitQuaternion::from_quaternion(Quaternion::new(v[3], v[0], v[1], v[2]))
    }

    /// The row's digits, when all four fit and have the file's fraction digits.
    fn encode(&self, fields: [Option<(bool, u64, usize)>; 4]) -> Option<[u32; 4]> {
        let mut out = [0u32; 4];
        for (o, f) in out.iter_mut().zip(fields) {
            let (neg, m, _) = f.filter(|f| f.2 == self.frac && f.1 < 1 << 31)?;
            *o = (m as u32) << 1 | u32::from(neg);
        }
        Some(out)
    }
}

/// `±m / 10^frac` as the parser computes it (Clinger's fast path: exact operands, one correctly
/// rounded division), for `m ≤ 2^53` and `frac ≤ 22`.
fn decimal(neg: bool, m: u64, frac: usize) -> f64 {
    const POW10: [f64; 23] = [
        1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
        1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
    ];
    // The sign set without a branch (it would wait for the division).
    f64::from_bits((m as f64 / POW10[frac]).to_bits() | u64::from(neg) << 63)
}

/// One `read`, retried when interrupted.
fn read_some(file: &mut impl Read, buf: &mut [u8]) -> std::io::Result<usize> {
    loop {
        match file.read(buf) {
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            r => return r,
        }
    }
}

/// The state of a TUM read: the trajectory so far and the line number for errors.
struct RowReader<'p> {
    path: &'p Path,
    orientation: bool,
    /// Keep orientations as decimal digits while every row allows.
    compact: bool,
    line: usize,
    traj: Option<Trajectory>,
    quats: Option<TumOrientations>,
}

impl RowReader<'_> {
    /// Parses every line of `bytes` (whole lines; the last may lack its newline at the end of file).
    fn lines(&mut self, bytes: &[u8]) -> Result<()> {
        let mut start = 0;
        for nl in memchr::memchr_iter(b'\n', bytes) {
            self.row(&bytes[start..nl])?;
            start = nl + 1;
        }
        if start < bytes.len() {
            self.row(&bytes[start..])?;
        }
        Ok(())
    }

    /// Parses one line: 4 values (`t x y z`) or 8 (with `qx qy qz qw`); comments and blank lines
    /// skipped. Scanning the fields ([`RowReader::scan`]) and storing them ([`RowReader::store`])
    /// are apart: the first is the byte work, the second decides what the trajectory keeps.
    fn row(&mut self, line: &[u8]) -> Result<()> {
        self.line += 1;
        let line = line.trim_ascii();
        if line.is_empty() || line[0] == b'#' {
            return Ok(());
        }
        // Filled in place, not returned: moving the 264 bytes out through a `Result` cost 2 % of a
        // TUM read (measured with callgrind on two million rows).
        let mut fields = RowFields {
            vals: [0.0f64; 8],
            plain: [None; 8],
            n: 0,
            stamp_ns: None,
        };
        self.scan(line, &mut fields)?;
        self.store(&fields)
    }

    /// The error of the current line.
    #[cold]
    fn bad(&self, detail: String) -> Error {
        Error::TextFormat {
            path: self.path.to_path_buf(),
            line: self.line,
            detail,
        }
    }

    /// Scans the fields of a non-empty line: the stamp, up to 8 values and their plain digits.
    /// Inlined into [`RowReader::row`]: it runs once per line of files of millions of lines.
    #[inline]
    fn scan(&self, line: &[u8], row: &mut RowFields) -> Result<()> {
        let decimal_quats = matches!(self.quats, Some(TumOrientations::Decimal(_)));
        let mut k = 0usize;
        while let Some(f) = next_field(line, &mut k, self.orientation || row.n < 4) {
            let n = row.n;
            if n == 0 {
                row.stamp_ns = Some(f.stamp_ns());
            }
            // The stamp's double is not used, nor an orientation's while the digits are kept: a plain
            // field is a number without the division (it is computed from the digits if needed).
            let v = match f.plain {
                Some(_) if n == 0 => Some(0.0),
                Some((_, m, frac)) if n >= 4 && decimal_quats && m <= 1 << 53 && frac <= 22 => {
                    Some(0.0)
                }
                _ => f.value(),
            }
            .ok_or_else(|| {
                self.bad(format!(
                    "`{}` is not a number",
                    String::from_utf8_lossy(f.text)
                ))
            })?;
            if n < 8 {
                row.vals[n] = v;
                row.plain[n] = f.plain;
            }
            row.n += 1;
        }
        Ok(())
    }

    /// Appends a scanned row: checks its width, picks how orientations are kept at the first row
    /// (decimal digits or quaternions) and pushes the position and the orientation.
    #[inline]
    fn store(&mut self, row: &RowFields) -> Result<()> {
        let (vals, plain, n) = (&row.vals, &row.plain, row.n);
        if n != 8 && n != 4 {
            return Err(self.bad(format!("{n} values on the line")));
        }
        let with_q = n == 8 && self.orientation;
        if self.traj.is_none() {
            self.quats = with_q.then(|| match plain[4] {
                Some((_, _, frac)) if self.compact && frac <= 9 => {
                    TumOrientations::Decimal(DecimalQuaternions {
                        digits: Vec::new(),
                        frac,
                    })
                }
                _ => TumOrientations::Quaternions(Vec::new()),
            });
        }
        let stamp_ns = match row.stamp_ns.flatten() {
            Some(s) => s,
            None => return Err(self.bad("bad timestamp".into())),
        };
        let t = self.traj.get_or_insert_with(|| Trajectory::new(false));
        let p = Vector3::new(vals[1], vals[2], vals[3]);
        // Rows not finite are kept: `Trajectory::clean` counts and drops them (`read_tum`), and
        // evo's readers keep them too (`read_tum_rows`).
        t.push(stamp_ns, p, None);
        if let Some(quats) = self.quats.as_mut() {
            // The parsed quaternion, needed only once the digits are given up.
            let q = || {
                let v = |k: usize| match plain[k] {
                    Some((neg, m, frac)) if m <= 1 << 53 && frac <= 22 => decimal(neg, m, frac),
                    _ => vals[k],
                };
                match with_q {
                    true => {
                        UnitQuaternion::from_quaternion(Quaternion::new(v(7), v(4), v(5), v(6)))
                    }
                    false => UnitQuaternion::identity(),
                }
            };
            let fields = with_q.then(|| [plain[4], plain[5], plain[6], plain[7]]);
            quats.push(fields, q);
        }
        Ok(())
    }
}

/// The fields of one line as scanned: the values (0 where only the digits are needed), the plain
/// digits of each (see [`Field`]), how many fields the line has and its stamp.
struct RowFields {
    vals: [f64; 8],
    plain: [Option<(bool, u64, usize)>; 8],
    /// Fields on the line (may exceed 8: an error reported by [`RowReader::store`]).
    n: usize,
    /// `None` for no field; `Some(None)` for a stamp that does not parse.
    stamp_ns: Option<Option<i64>>,
}

/// One field of a line, scanned once: its text and, when it is a plain decimal (`-12.345678`, at
/// most 19 digits), its digits as an integer and the number of fraction digits.
struct Field<'a> {
    text: &'a [u8],
    /// (negative, digits, fraction digits).
    plain: Option<(bool, u64, usize)>,
}

impl Field<'_> {
    /// The number. Hand-written fast path (Clinger's): digits below 2^53 over 10^k are two exact
    /// doubles and one correctly rounded division, the same double `str::parse` gives, at a fraction
    /// of the time (it matters at millions of rows); anything else goes to `str::parse`.
    fn value(&self) -> Option<f64> {
        match self.plain {
            Some((neg, m, frac)) if m <= 1 << 53 && frac <= 22 => Some(decimal(neg, m, frac)),
            _ => std::str::from_utf8(self.text).ok()?.parse().ok(),
        }
    }

    /// The field as a stamp in nanoseconds without a detour through `f64` ([`parse_stamp_ns`] for
    /// anything but a plain non-negative decimal with at most 9 fraction digits).
    fn stamp_ns(&self) -> Option<i64> {
        match self.plain {
            Some((false, m, frac)) if frac <= 9 => i64::try_from(m)
                .ok()?
                .checked_mul(10i64.pow(9 - frac as u32)),
            _ => parse_stamp_ns(std::str::from_utf8(self.text).ok()?),
        }
    }
}

/// Field separators: spaces, tabs, commas (and a CR left by a CRLF line).
fn is_sep(c: u8) -> bool {
    c == b' ' || c == b'\t' || c == b',' || c == b'\r'
}

/// The digits of `b` from `i`: (their value, wrapping past 19 digits; the index after them).
///
/// Eight bytes at a time while the line has them (SWAR, as simdjson and fast_float do: two masks find
/// how many leading bytes are digits, three multiplications add them up), byte by byte at its end.
/// Hand-written: the crates that do this parse a whole float, and the caller needs the digits.
fn digits(b: &[u8], mut i: usize) -> (u64, usize) {
    const POW10: [u64; 9] = [
        1,
        10,
        100,
        1_000,
        10_000,
        100_000,
        1_000_000,
        10_000_000,
        100_000_000,
    ];
    const ZEROS: u64 = 0x3030_3030_3030_3030;
    const HIGH: u64 = 0xF0F0_F0F0_F0F0_F0F0;
    let mut m = 0u64;
    while let Some(chunk) = b.get(i..i + 8) {
        let w = u64::from_le_bytes(chunk.try_into().unwrap_or([0; 8]));
        // A byte is a digit when its high nibble is 3 before and after adding 6; a carry out of a
        // byte only disturbs the bytes after the first non-digit, which are not counted.
        let not_digit =
            ((w & HIGH) ^ ZEROS) | ((w.wrapping_add(0x0606_0606_0606_0606) & HIGH) ^ ZEROS);
        let c = (not_digit.trailing_zeros() / 8) as usize;
        if c == 0 {
            return (m, i);
        }
        // The c digits moved to the top bytes (zeros before them), then summed pairwise.
        let v = (w.wrapping_sub(ZEROS)) << (8 * (8 - c));
        let v = (v.wrapping_mul(10) + (v >> 8)) & 0x00FF_00FF_00FF_00FF;
        let v = (v.wrapping_mul(100) + (v >> 16)) & 0x0000_FFFF_0000_FFFF;
        let v = (v.wrapping_mul(10_000) + (v >> 32)) & 0xFFFF_FFFF;
        m = m.wrapping_mul(POW10[c]).wrapping_add(v);
        i += c;
        if c < 8 {
            return (m, i);
        }
    }
    while let Some(d) = b.get(i).map(|c| c.wrapping_sub(b'0')).filter(|&d| d < 10) {
        m = m.wrapping_mul(10).wrapping_add(u64::from(d));
        i += 1;
    }
    (m, i)
}

/// The index of the first separator of `b` from `i` (or its length). Eight bytes at a time over bytes
/// that cannot be separators (all above `,`: digits, `.`, `-`, letters), as fields mostly are.
fn field_end(b: &[u8], mut i: usize) -> usize {
    while let Some(chunk) = b.get(i..i + 8) {
        let w = u64::from_le_bytes(chunk.try_into().unwrap_or([0; 8]));
        // The high bit of each byte below 0x2D (exact up to the first such byte; non-ASCII bytes,
        // never separators, are not flagged).
        let low = w.wrapping_sub(0x2D2D_2D2D_2D2D_2D2D) & !w & 0x8080_8080_8080_8080;
        if low != 0 {
            i += (low.trailing_zeros() / 8) as usize;
            break;
        }
        i += 8;
    }
    while i < b.len() && !is_sep(b[i]) {
        i += 1;
    }
    i
}

/// The next field of `line` from byte `k` (fields are runs between spaces, tabs and commas); with
/// `parse` false the field is only delimited (its value reads as 0).
fn next_field<'a>(b: &'a [u8], k: &mut usize, parse: bool) -> Option<Field<'a>> {
    while *k < b.len() && is_sep(b[*k]) {
        *k += 1;
    }
    if *k == b.len() {
        return None;
    }
    let start = *k;
    let mut plain = None;
    if parse {
        // [sign] integer digits [. fraction digits], nothing else before the separator.
        let neg = b[start] == b'-';
        let int_start = start + usize::from(neg || b[start] == b'+');
        let (int, mut i) = digits(b, int_start);
        let int_digits = i - int_start;
        let (mut fraction, mut frac) = (0, 0);
        if b.get(i) == Some(&b'.') {
            let (f, end) = digits(b, i + 1);
            (fraction, frac) = (f, end - i - 1);
            i = end;
        }
        let n = int_digits + frac;
        if (i == b.len() || is_sep(b[i])) && n > 0 && n <= 19 {
            // At most 19 digits: `int · 10^frac + fraction` fits in a u64.
            plain = Some((neg, int * 10u64.pow(frac as u32) + fraction, frac));
        }
        *k = i;
    }
    *k = field_end(b, *k);
    Some(Field {
        text: &b[start..*k],
        plain: plain.or((!parse).then_some((false, 0, 0))),
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
                    123456789012345678 0.1234567890123456789 nan inf 1. 12345678901234567890123 \
                    .5 -.5 00012.50 9999999999999999999 1234567890.1234567891 -0.000000001";
        let mut k = 0;
        while let Some(f) = next_field(line.as_bytes(), &mut k, true) {
            let want: Option<f64> = std::str::from_utf8(f.text).unwrap().parse().ok();
            assert_eq!(
                f.value().map(f64::to_bits),
                want.map(f64::to_bits),
                "{}",
                String::from_utf8_lossy(f.text)
            );
        }
        let mut k = 0;
        let f = next_field(b" .,1x", &mut k, true).unwrap();
        assert_eq!((f.text, f.value()), (&b"."[..], None));
        let f = next_field(b" .,1x", &mut k, true).unwrap();
        assert_eq!((f.text, f.value()), (&b"1x"[..], None));
        for (s, ns) in [
            ("1700000000.010000", Some(1_700_000_000_010_000_000)),
            ("12", Some(12_000_000_000)),
            ("-1.5", Some(-1_500_000_000)),
            ("1718460000.123456789", Some(1_718_460_000_123_456_789)),
        ] {
            let mut k = 0;
            assert_eq!(
                next_field(s.as_bytes(), &mut k, true).unwrap().stamp_ns(),
                ns,
                "{s}"
            );
        }
    }

    #[test]
    fn random_decimals_equal_std_parse() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let digit =
            |rng: &mut rand_chacha::ChaCha8Rng| char::from(b'0' + rng.random_range(0..10u8));
        for _ in 0..20_000 {
            let mut s = String::new();
            if rng.random_bool(0.3) {
                s.push('-');
            }
            (0..rng.random_range(0..14)).for_each(|_| s.push(digit(&mut rng)));
            if rng.random_bool(0.8) {
                s.push('.');
                (0..rng.random_range(0..14)).for_each(|_| s.push(digit(&mut rng)));
            }
            let line = format!("{s} {s},{s}");
            let mut k = 0;
            while let Some(f) = next_field(line.as_bytes(), &mut k, true) {
                let want: Option<f64> = s.parse().ok();
                assert_eq!(f.value().map(f64::to_bits), want.map(f64::to_bits), "{s}");
                assert_eq!(f.stamp_ns(), parse_stamp_ns(&s), "{s}");
            }
        }
    }

    #[test]
    fn decimal_orientations_equal_parsed_ones() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("q.tum");
        let rows = "1.0 0 0 0 -0.000000000 0.000000000 0.707106781 0.707106781\n\
                    2.0 1 2 3 0.182574186 -0.365148372 0.547722558 0.730296743\n";
        for (extra, decimal) in [
            ("", true),
            ("3.0 1 2 3 0.5 0.5 0.5 0.5\n", false),
            ("3.0 1 2 3 0.100000000 12345678.123456789 1e-3 0.2\n", false),
        ] {
            std::fs::write(&path, format!("{rows}{extra}")).unwrap();
            let (t, q) = read_tum_rows_compact(&path, true).unwrap();
            let q = q.unwrap();
            assert_eq!(matches!(q, TumOrientations::Decimal(_)), decimal);
            let want = read_tum_rows_with(&path, true).unwrap();
            let bits = |v: &[UnitQuaternion<f64>]| -> Vec<[u64; 4]> {
                v.iter()
                    .map(|q| q.coords.as_slice().to_vec())
                    .map(|c| [0, 1, 2, 3].map(|k| c[k].to_bits()))
                    .collect()
            };
            assert_eq!(t.stamps_ns, want.stamps_ns);
            assert_eq!(
                bits(&q.into_quaternions()),
                bits(&want.orientations.unwrap())
            );
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
