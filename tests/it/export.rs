//! `trajdrift export` writes a topic as text that the text readers take back unchanged.

use crate::common;

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

#[test]
fn every_recording_format_exports_the_same_tum_bytes() {
    let Some(shared) = common::shared() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let legged = common::mission(&shared, "legged");
    let export = |input: &std::path::Path, name: &str| {
        let out = dir.path().join(name);
        let o = Command::new(env!("CARGO_BIN_EXE_trajdrift"))
            .args([
                "export",
                input.to_str().unwrap(),
                "--topic",
                "/estimate/odom",
            ])
            .arg(&out)
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        std::fs::read(out).unwrap()
    };
    let mcap = export(&legged.join("mission.mcap"), "mcap.tum");
    assert!(!mcap.is_empty());
    assert_eq!(export(&legged.join("mission_ros1.bag"), "bag.tum"), mcap);
    assert_eq!(export(&legged.join("rosbag2"), "rosbag2.tum"), mcap);
}
