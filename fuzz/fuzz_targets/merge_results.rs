//! `merge`'s result reader: a folder holding one fuzzed JSON file (a mission result, a run record or
//! anything else, by its `kind`) beside a valid run record, read and checked as `merge` does, then the
//! summary built and written out as JSON, CSV, Markdown and HTML text.
#![no_main]

use std::path::PathBuf;
use std::sync::OnceLock;

use libfuzzer_sys::fuzz_target;

/// This process's scratch folder, with a run record of one mission `m`.
fn folder() -> &'static PathBuf {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let base = if std::path::Path::new("/dev/shm").is_dir() {
            PathBuf::from("/dev/shm")
        } else {
            std::env::temp_dir()
        };
        let d = base.join(format!("trajdrift-fuzz-merge-{}", std::process::id()));
        std::fs::create_dir_all(&d).expect("scratch folder");
        std::fs::write(
            d.join("trajdrift-run.json"),
            r#"{"kind":"trajdrift.run","run_id":"1","parameters":"2","missions":{"m":"3"},"selected":["m"],"status":"complete","trajdrift_version":"0","started_unix_s":0}"#,
        )
        .expect("run record");
        d
    })
}

fuzz_target!(|data: &[u8]| {
    let dir = folder();
    std::fs::write(dir.join("m.json"), data).expect("scratch file");
    trajdrift::fuzzing::merge_folder(dir);
});
