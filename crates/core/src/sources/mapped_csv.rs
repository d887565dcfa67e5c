//! Generic CSV trajectories with a column mapping: `--csv t=t:us,x=px,y=py,z=pz,qx=qx,qy=qy,qz=qz,qw=qw`
//! names the column of each field and the time unit (s, ms, us, ns; seconds by default). Many datasets
//! ship their odometry this way (FoMo's `odom.csv` with microsecond stamps); EuRoC's ground truth is the
//! same reader with a fixed mapping.
//!
//! Parsing uses the `csv` crate; the first row is the header (a leading `#` is ignored) and the
//! delimiter (`,`, `;` or tab) is the most frequent one of the header row.

use std::io::{BufRead, BufReader};
use std::path::Path;

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use crate::error::{Error, Result};
use crate::sources::tum::parse_stamp_ns;
use crate::trajectory::rows::RowAudit;
use crate::trajectory::Trajectory;

/// The unit of a time column.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum TimeUnit {
    #[default]
    Seconds,
    Milliseconds,
    Microseconds,
    Nanoseconds,
}

impl TimeUnit {
    fn parse(s: &str) -> Option<Self> {
        Some(match s {
            "s" => TimeUnit::Seconds,
            "ms" => TimeUnit::Milliseconds,
            "us" | "µs" => TimeUnit::Microseconds,
            "ns" => TimeUnit::Nanoseconds,
            _ => return None,
        })
    }

    /// Nanoseconds per unit.
    fn ns(self) -> i64 {
        match self {
            TimeUnit::Seconds => 1_000_000_000,
            TimeUnit::Milliseconds => 1_000_000,
            TimeUnit::Microseconds => 1_000,
            TimeUnit::Nanoseconds => 1,
        }
    }

    /// Parses one cell to integer nanoseconds (integers stay exact, decimals in seconds keep every digit).
    fn to_ns(self, cell: &str) -> Option<i64> {
        if self == TimeUnit::Seconds {
            return parse_stamp_ns(cell);
        }
        if let Ok(v) = cell.parse::<i64>() {
            return v.checked_mul(self.ns());
        }
        let v: f64 = cell.parse().ok()?;
        v.is_finite().then(|| (v * self.ns() as f64).round() as i64)
    }
}

/// Which column holds a field: by header name, or by 0-based position (`#3`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Column {
    Name(String),
    Index(usize),
}

impl Column {
    fn parse(s: &str) -> Self {
        match s.strip_prefix('#').and_then(|i| i.parse().ok()) {
            Some(i) => Column::Index(i),
            None => Column::Name(s.to_string()),
        }
    }
}

/// Where each field of a pose is in a CSV file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CsvMapping {
    pub t: Column,
    pub time_unit: TimeUnit,
    /// x, y, z.
    pub position: [Column; 3],
    /// qx, qy, qz, qw (all four or none).
    pub orientation: Option<[Column; 4]>,
}

const SYNTAX: &str =
    "--csv takes t=COLUMN[:s|ms|us|ns],x=COLUMN,y=COLUMN,z=COLUMN[,qx=..,qy=..,qz=..,qw=..]";

impl CsvMapping {
    /// Parses `t=t:us,x=px,y=py,z=pz,qx=qx,qy=qy,qz=qz,qw=qw`. A column is a header name or `#INDEX`.
    pub fn parse(spec: &str) -> Result<Self> {
        let bad = |m: String| Error::InvalidArgument(format!("{m}; {SYNTAX}"));
        let mut fields: [Option<Column>; 8] = Default::default();
        let mut unit = TimeUnit::Seconds;
        const KEYS: [&str; 8] = ["t", "x", "y", "z", "qx", "qy", "qz", "qw"];
        for part in spec.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            let (key, col) = part
                .split_once('=')
                .ok_or_else(|| bad(format!("`{part}` is not FIELD=COLUMN")))?;
            let k = KEYS
                .iter()
                .position(|&x| x == key.trim())
                .ok_or_else(|| bad(format!("unknown field `{key}`")))?;
            let mut col = col.trim();
            if k == 0 {
                if let Some((c, u)) = col.rsplit_once(':') {
                    unit = TimeUnit::parse(u)
                        .ok_or_else(|| bad(format!("unknown time unit `{u}`")))?;
                    col = c;
                }
            }
            if col.is_empty() {
                return Err(bad(format!("`{key}` names no column")));
            }
            fields[k] = Some(Column::parse(col));
        }
        let [t, x, y, z, qx, qy, qz, qw] = fields;
        let need = |c: Option<Column>, k: &str| c.ok_or_else(|| bad(format!("`{k}` is missing")));
        let orientation = match (qx, qy, qz, qw) {
            (None, None, None, None) => None,
            (Some(a), Some(b), Some(c), Some(d)) => Some([a, b, c, d]),
            _ => return Err(bad("give all four of qx, qy, qz, qw, or none".into())),
        };
        Ok(CsvMapping {
            t: need(t, "t")?,
            time_unit: unit,
            position: [need(x, "x")?, need(y, "y")?, need(z, "z")?],
            orientation,
        })
    }

    /// EuRoC ground truth: `#timestamp [ns], p_RS_R_x, y, z, q_RS_w, x, y, z, ...` by position.
    pub fn euroc() -> Self {
        CsvMapping {
            t: Column::Index(0),
            time_unit: TimeUnit::Nanoseconds,
            position: [Column::Index(1), Column::Index(2), Column::Index(3)],
            orientation: Some([
                Column::Index(5),
                Column::Index(6),
                Column::Index(7),
                Column::Index(4),
            ]),
        }
    }

    /// The mapping used when none is given: columns named `t`/`time`/`timestamp` (seconds), `x`, `y`,
    /// `z` and, when all present, `qx`, `qy`, `qz`, `qw` — the layout `trajdrift export --format csv` writes.
    pub fn by_name(header: &[String]) -> Option<Self> {
        let find = |names: &[&str]| {
            header
                .iter()
                .find(|h| names.iter().any(|n| h.eq_ignore_ascii_case(n)))
                .map(|h| Column::Name(h.clone()))
        };
        let q = [find(&["qx"]), find(&["qy"]), find(&["qz"]), find(&["qw"])];
        Some(CsvMapping {
            t: find(&["t", "time", "timestamp"])?,
            time_unit: TimeUnit::Seconds,
            position: [find(&["x"])?, find(&["y"])?, find(&["z"])?],
            orientation: match q {
                [Some(a), Some(b), Some(c), Some(d)] => Some([a, b, c, d]),
                _ => None,
            },
        })
    }
}

/// The first row of a CSV file.
#[derive(Debug, Clone, PartialEq)]
pub struct CsvHeader {
    /// Column names, trimmed, a leading `#` dropped (empty names when the file has no header row).
    pub columns: Vec<String>,
    pub delimiter: u8,
    /// The first row holds data (every cell a number), not names.
    pub is_data: bool,
    /// The first row starts with `#` (the CSV reader then skips it as a comment).
    pub is_comment: bool,
}

/// Reads the first row of a CSV file and picks its delimiter.
pub fn read_header(path: &Path) -> Result<CsvHeader> {
    let file = crate::sources::input::open_text(path)?;
    let mut first = String::new();
    BufReader::new(file)
        .read_line(&mut first)
        .map_err(|e| Error::io(path, e))?;
    let delimiter = [b',', b';', b'\t']
        .into_iter()
        .max_by_key(|&d| first.bytes().filter(|&b| b == d).count())
        .unwrap_or(b',');
    let first = first.trim_start_matches('\u{feff}').trim();
    let cells: Vec<&str> = first
        .trim_start_matches('#')
        .split(delimiter as char)
        .map(str::trim)
        .collect();
    let is_data = !first.starts_with('#') && cells.iter().all(|c| c.parse::<f64>().is_ok());
    let columns = cells
        .iter()
        .map(|c| {
            if is_data {
                String::new()
            } else {
                c.to_string()
            }
        })
        .collect();
    Ok(CsvHeader {
        columns,
        delimiter,
        is_data,
        is_comment: first.starts_with('#'),
    })
}

/// Reads a CSV trajectory with `mapping`. Rows whose position is not finite are skipped; stamps are
/// sorted and deduplicated like every source.
pub fn read_mapped_csv(path: &Path, mapping: &CsvMapping) -> Result<Trajectory> {
    read_mapped_csv_audited(path, mapping).map(|(t, _)| t)
}

/// [`read_mapped_csv`], and what became of every row ([`Trajectory::clean`]).
///
/// Three steps: the header is read and the mapping resolved to column indices (a mapping the file
/// cannot satisfy fails before any row is read), then every record becomes one pose.
pub fn read_mapped_csv_audited(
    path: &Path,
    mapping: &CsvMapping,
) -> Result<(Trajectory, RowAudit)> {
    let head = read_header(path)?;
    let cols = ResolvedColumns::of(path, mapping, &head.columns)?;
    let file = crate::sources::input::open_text(path)?;
    let mut reader = csv::ReaderBuilder::new()
        .delimiter(head.delimiter)
        .has_headers(!head.is_data && !head.is_comment)
        .flexible(true)
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .from_reader(file);
    let mut traj = Trajectory::new(cols.q.is_some());
    let mut record = csv::StringRecord::new();
    loop {
        let more = reader.read_record(&mut record).map_err(|e| Error::Text {
            path: path.to_path_buf(),
            line: e.position().map_or(0, |p| p.line() as usize),
            detail: e.to_string(),
            hint: "expected a CSV file".into(),
        })?;
        if !more {
            break;
        }
        let (stamp, p, q) = cols.pose(path, mapping.time_unit, &record)?;
        traj.push(stamp, p, q);
    }
    let audit = traj.clean();
    Ok((traj, audit))
}

/// The column index of every field of a [`CsvMapping`] in one file.
struct ResolvedColumns {
    t: usize,
    p: [usize; 3],
    q: Option<[usize; 4]>,
}

impl ResolvedColumns {
    /// Finds each mapped column in `header` (by name, a name followed by ` [unit]`, or index); a
    /// column the header lacks is an error naming the field, the column and the columns there are.
    fn of(path: &Path, mapping: &CsvMapping, header: &[String]) -> Result<ResolvedColumns> {
        let resolve = |field: &str, c: &Column| -> Result<usize> {
            let found = match c {
                Column::Index(i) => (*i < header.len()).then_some(*i),
                Column::Name(n) => header.iter().position(|h| {
                    h == n || h.split_once(" [").is_some_and(|(stem, _)| stem.trim() == n)
                }),
            };
            found.ok_or_else(|| Error::Text {
                path: path.to_path_buf(),
                line: 1,
                detail: format!(
                    "the CSV mapping puts {field} in column {}, which the header does not have (columns: {})",
                    match c {
                        Column::Name(n) => format!("`{n}`"),
                        Column::Index(i) => format!("#{i}"),
                    },
                    header.join(", ")
                ),
                hint: format!("fix the mapping: {SYNTAX}"),
            })
        };
        Ok(ResolvedColumns {
            t: resolve("t", &mapping.t)?,
            p: [
                resolve("x", &mapping.position[0])?,
                resolve("y", &mapping.position[1])?,
                resolve("z", &mapping.position[2])?,
            ],
            q: match &mapping.orientation {
                Some(q) => Some([
                    resolve("qx", &q[0])?,
                    resolve("qy", &q[1])?,
                    resolve("qz", &q[2])?,
                    resolve("qw", &q[3])?,
                ]),
                None => None,
            },
        })
    }

    /// The pose of one record: its stamp in `unit`, position and orientation; a missing cell or one
    /// that is not a number is an error naming the line and the column.
    #[inline]
    fn pose(
        &self,
        path: &Path,
        unit: TimeUnit,
        record: &csv::StringRecord,
    ) -> Result<(i64, Vector3<f64>, Option<UnitQuaternion<f64>>)> {
        let line = record.position().map_or(0, |p| p.line() as usize);
        let bad = |detail: String| Error::Text {
            path: path.to_path_buf(),
            line,
            detail,
            hint: "check the file and the --csv mapping".into(),
        };
        let cell = |i: usize| -> Result<&str> {
            record
                .get(i)
                .ok_or_else(|| bad(format!("the row has no column #{i}")))
        };
        let num = |i: usize| -> Result<f64> {
            let c = cell(i)?;
            c.parse::<f64>()
                .map_err(|_| bad(format!("`{c}` in column #{i} is not a number")))
        };
        let c = cell(self.t)?;
        let stamp = unit
            .to_ns(c)
            .ok_or_else(|| bad(format!("`{c}` in column #{} is not a time", self.t)))?;
        let p = Vector3::new(num(self.p[0])?, num(self.p[1])?, num(self.p[2])?);
        let q = match self.q {
            Some([x, y, z, w]) => Some(UnitQuaternion::from_quaternion(Quaternion::new(
                num(w)?,
                num(x)?,
                num(y)?,
                num(z)?,
            ))),
            None => None,
        };
        Ok((stamp, p, q))
    }
}

/// Writes `traj` as CSV with the header `t,x,y,z,qx,qy,qz,qw` (seconds, stamps printed exactly;
/// identity orientation when it has none), which [`CsvMapping::by_name`] reads back without a mapping.
pub fn write_csv<W: std::io::Write>(mut out: W, traj: &Trajectory) -> std::io::Result<()> {
    writeln!(out, "t,x,y,z,qx,qy,qz,qw")?;
    crate::sources::tum::write_rows(out, traj, ',')
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mapping_syntax() {
        let m = CsvMapping::parse("t=t:us,x=px,y=py,z=pz,qx=qx,qy=qy,qz=qz,qw=qw").unwrap();
        assert_eq!(m.time_unit, TimeUnit::Microseconds);
        assert_eq!(m.position[0], Column::Name("px".into()));
        assert!(m.orientation.is_some());
        let m = CsvMapping::parse("t=#0:ns,x=#1,y=#2,z=#3").unwrap();
        assert_eq!(m.t, Column::Index(0));
        assert!(m.orientation.is_none());
        for bad in [
            "x=a,y=b,z=c",
            "t=t:days,x=a,y=b,z=c",
            "t=t,x=a,y=b,z=c,qx=d",
            "t",
        ] {
            let e = CsvMapping::parse(bad).unwrap_err().to_string();
            assert!(e.contains("--csv takes"), "{bad}: {e}");
        }
    }

    #[test]
    fn reads_microseconds_and_names_a_missing_column() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("odom.csv");
        std::fs::write(
            &path,
            "t,px,py,pz,qx,qy,qz,qw\n1700000000000001,1,2,3,0,0,0,1\n1700000000100001,2,2,3,0,0,0,1\n",
        )
        .unwrap();
        let m = CsvMapping::parse("t=t:us,x=px,y=py,z=pz,qx=qx,qy=qy,qz=qz,qw=qw").unwrap();
        let t = read_mapped_csv(&path, &m).unwrap();
        assert_eq!(
            t.stamps_ns,
            vec![1_700_000_000_000_001_000, 1_700_000_000_100_001_000]
        );
        assert_eq!(t.positions[1], Vector3::new(2.0, 2.0, 3.0));

        let m = CsvMapping::parse("t=t:us,x=pos_x,y=py,z=pz").unwrap();
        let e = read_mapped_csv(&path, &m).unwrap_err().to_string();
        assert!(!e.contains('\n'), "{e}");
        assert!(
            e.contains("odom.csv:1:") && e.contains("`pos_x`") && e.contains("columns: t, px"),
            "{e}"
        );
    }

    #[test]
    fn export_round_trips_without_a_mapping() {
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
        let path = dir.path().join("t.csv");
        write_csv(std::fs::File::create(&path).unwrap(), &t).unwrap();
        let head = read_header(&path).unwrap();
        let back = read_mapped_csv(&path, &CsvMapping::by_name(&head.columns).unwrap()).unwrap();
        assert_eq!(back.stamps_ns, t.stamps_ns);
        assert_eq!(back.positions, t.positions);
    }

    #[test]
    fn units_convert_exactly() {
        assert_eq!(TimeUnit::Milliseconds.to_ns("1500"), Some(1_500_000_000));
        assert_eq!(TimeUnit::Microseconds.to_ns("2.5"), Some(2_500));
        assert_eq!(TimeUnit::Seconds.to_ns("1.000000001"), Some(1_000_000_001));
        assert_eq!(TimeUnit::Nanoseconds.to_ns("x"), None);
    }
}
