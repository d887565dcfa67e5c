//! `trajdrift export` writes a topic as text that the text readers take back unchanged.

mod common;

use std::process::Command;

use trajdrift::sources::text::{read_text, TextOptions};
use trajdrift::sources::tum::read_tum;

#[test]
fn exported_topic_reads_back_as_csv_and_tum() {
    let Some(shared) = common::shared() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let rec = common::mission(&shared, "legged").join("mission.mcap");
    let reference = read_tum(&common::mission(&shared, "legged").join("estimate.tum")).unwrap();
    for (format, file) in [("csv", "est.csv"), ("tum", "est.tum")] {
        let out = dir.path().join(file);
        let o = Command::new(env!("CARGO_BIN_EXE_trajdrift"))
            .args(["export", rec.to_str().unwrap(), "--topic", "/estimate/odom"])
            .args(["--format", format, out.to_str().unwrap()])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let (t, _) = read_text(&out, &TextOptions::default()).unwrap();
        assert_eq!(t.stamps_ns, reference.stamps_ns, "{format}");
        assert_eq!(t.len(), reference.len());
    }
}
