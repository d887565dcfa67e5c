//! EuRoC MAV ground truth (`state_groundtruth_estimate0/data.csv`): `#timestamp [ns], p_RS_R_x [m],
//! p_RS_R_y, p_RS_R_z, q_RS_w [], q_RS_x, q_RS_y, q_RS_z, v_RS_R_x, ...` — read by position like evo
//! does, with the generic CSV reader.

use std::path::Path;

use crate::error::{Error, Result};
use crate::sources::mapped_csv::{read_header, read_mapped_csv_audited, CsvMapping};
use crate::trajectory::rows::RowAudit;
use crate::trajectory::Trajectory;

/// True when the header row is EuRoC's (`p_RS_R_x` among the columns).
pub fn is_euroc_header(columns: &[String]) -> bool {
    columns.iter().any(|c| c.starts_with("p_RS_R_x"))
}

/// Reads a EuRoC ground-truth CSV: nanosecond stamps, position, orientation (w first in the file).
pub fn read_euroc(path: &Path) -> Result<Trajectory> {
    read_euroc_audited(path).map(|(t, _)| t)
}

/// [`read_euroc`], and what became of every row.
pub fn read_euroc_audited(path: &Path) -> Result<(Trajectory, RowAudit)> {
    let head = read_header(path)?;
    if head.columns.len() < 8 {
        return Err(Error::Text {
            path: path.to_path_buf(),
            line: 1,
            detail: format!("{} columns", head.columns.len()),
            hint: "expected EuRoC ground truth: #timestamp [ns], p_RS_R_x, p_RS_R_y, p_RS_R_z, q_RS_w, q_RS_x, q_RS_y, q_RS_z, ...".into(),
        });
    }
    read_mapped_csv_audited(path, &CsvMapping::euroc())
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    #[test]
    fn reads_nanoseconds_and_w_first() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("data.csv");
        std::fs::write(
            &path,
            "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z [], v_RS_R_x [m s^-1]\n\
             1403715524907143168,0.5,1.9,0.9,0.0,0.0,0.0,1.0,0.1\n\
             1403715524912143104,0.6,1.9,0.9,1.0,0.0,0.0,0.0,0.1\n",
        )
        .unwrap();
        assert!(is_euroc_header(&read_header(&path).unwrap().columns));
        let t = read_euroc(&path).unwrap();
        assert_eq!(t.stamps_ns[0], 1_403_715_524_907_143_168);
        assert_eq!(t.positions[1], Vector3::new(0.6, 1.9, 0.9));
        let q = t.orientations.as_ref().unwrap();
        assert!((q[0].k.abs() - 1.0).abs() < 1e-12 && (q[1].w - 1.0).abs() < 1e-12);
    }
}
