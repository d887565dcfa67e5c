//! Hostile inputs at the process boundary: outputs that would overwrite an input, parameter
//! values out of range, damaged and truncated recordings, names with control characters, closed pipes,
//! dropped rows, and a seeded mutation test of an MCAP and a bag under a 1 GB address-space limit.

use crate::common;
use crate::hostile_support;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use hostile_support::{small_bag, small_mcap};
use trajdrift::sources::bag::writer::BagCompression;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_trajdrift"))
}

fn run(args: &[&str]) -> Output {
    bin().args(args).output().expect("run trajdrift")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Writes the fuzz seeds (small recordings, messages, text files) into fuzz/corpus/. Run by hand:
/// `cargo test --release --test it -- --ignored hostile::write_fuzz_seeds`.
#[test]
#[ignore]
fn write_fuzz_seeds() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fuzz/corpus");
    let dir = |t: &str| {
        let d = root.join(t);
        std::fs::create_dir_all(&d).unwrap();
        d
    };
    small_mcap(&dir("mcap_source").join("small.mcap"), 20);
    small_bag(
        &dir("bag_reader").join("none.bag"),
        BagCompression::None,
        10,
    );
    small_bag(&dir("bag_reader").join("lz4.bag"), BagCompression::Lz4, 10);
    small_bag(&dir("bag_reader").join("bz2.bag"), BagCompression::Bz2, 10);
    use trajdrift::decode::cdr::encode_le;
    use trajdrift::decode::ros2_msgs::{Header, Odometry, PointStamped, Time};
    let header = Header {
        stamp: Time::from_ns(1_700_000_000_123_456_789),
        frame_id: "map".into(),
    };
    let ps = PointStamped {
        header: header.clone(),
        ..Default::default()
    };
    let od = Odometry {
        header,
        ..Default::default()
    };
    let cdr = dir("cdr_decode");
    std::fs::write(cdr.join("point.cdr"), encode_le(&ps)).unwrap();
    std::fs::write(cdr.join("odom.cdr"), encode_le(&od)).unwrap();
    std::fs::write(
        cdr.join("point.ros1"),
        trajdrift::decode::ros1::encode_point_stamped(1, &ps),
    )
    .unwrap();
    let tf = dir("tf_decode");
    let edge = trajdrift::decode::ros2_msgs::TransformStamped {
        header: ps.header.clone(),
        child_frame_id: "base_link".into(),
        ..Default::default()
    };
    let msg = trajdrift::decode::ros2_msgs::TFMessage {
        transforms: vec![edge.clone(), edge],
    };
    std::fs::write(tf.join("tf.cdr"), encode_le(&msg)).unwrap();
    std::fs::write(
        tf.join("tf.ros1"),
        trajdrift::decode::ros1::encode_tf_message(1, &msg),
    )
    .unwrap();
    let text = dir("text_readers");
    std::fs::write(
        text.join("tum"),
        b"\x00# t x y z qx qy qz qw\n1.0 0 0 0 0 0 0 1\n1.1 0.1 0 0 0 0 0 1\n1.1 0.1 0 0 0 0 0 1\n",
    )
    .unwrap();
    std::fs::write(text.join("csv"), b"\x01t,x,y,z\n1.0,0,0,0\n1.1,0.1,0,0\n").unwrap();
    std::fs::write(
        text.join("kitti"),
        b"\x021 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0.1 0 1 0 0 0 0 1 0\n",
    )
    .unwrap();
    std::fs::write(
        text.join("euroc"),
        b"\x01#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z []\n1403715523912143104,0,0,0,1,0,0,0\n",
    )
    .unwrap();
}

/// A folder with a small MCAP, a small bag, and a TUM reference/estimate pair.
struct Fixture {
    dir: tempfile::TempDir,
}

impl Fixture {
    fn new() -> Self {
        let dir = tempfile::tempdir().unwrap();
        small_mcap(&dir.path().join("in.mcap"), 400);
        small_bag(&dir.path().join("in.bag"), BagCompression::Lz4, 40);
        let f = Fixture { dir };
        // Export the MCAP's trajectories as TUM text for the text-only cases.
        for (topic, name) in [
            ("/reference/position", "ref.tum"),
            ("/estimate/odom", "est.tum"),
        ] {
            let o = run(&[
                "export",
                s(&f.p("in.mcap")),
                "--topic",
                topic,
                s(&f.p(name)),
            ]);
            assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        }
        f
    }

    fn p(&self, name: &str) -> PathBuf {
        self.dir.path().join(name)
    }
}

fn eval_args<'a>(rec: &'a str, extra: &[&'a str]) -> Vec<&'a str> {
    let mut v = vec![
        "eval",
        rec,
        "--reference",
        "/reference/position",
        "--estimate",
        "/estimate/odom",
        "-q",
    ];
    v.extend_from_slice(extra);
    v
}

// 1. One output guard: no output may overwrite an input (exit 2, input unchanged).
#[test]
fn outputs_that_resolve_to_an_input_are_refused() {
    let f = Fixture::new();
    let rec = f.p("in.mcap");
    let before = std::fs::read(&rec).unwrap();
    let tum_before = std::fs::read(f.p("est.tum")).unwrap();
    let link = f.p("link.mcap");
    std::os::unix::fs::symlink(&rec, &link).unwrap();
    let hard = f.p("hard.mcap");
    std::fs::hard_link(&rec, &hard).unwrap();
    let dotted = format!("{}/./in.mcap", f.dir.path().display());
    let est = f.p("est.tum");
    let cases: Vec<Vec<&str>> = vec![
        eval_args(s(&rec), &["--json", s(&rec)]),
        eval_args(s(&rec), &["--json", s(&link)]),
        eval_args(s(&rec), &["--json", s(&hard)]),
        eval_args(s(&rec), &["--json", &dotted]),
        eval_args(s(&rec), &["--export-aligned", s(&rec)]),
        eval_args(s(&rec), &["--annotate", s(&link), "--force"]),
        vec!["export", s(&rec), "--topic", "/estimate/odom", s(&rec)],
        vec!["export", s(&est), s(&est)],
    ];
    for args in cases {
        let o = run(&args);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {e}");
        assert!(
            e.contains("writing it would destroy the input") && e.lines().count() == 1,
            "{args:?}: {e}"
        );
    }
    assert_eq!(std::fs::read(&rec).unwrap(), before);
    assert_eq!(std::fs::read(f.p("est.tum")).unwrap(), tum_before);
}

#[test]
fn outputs_are_atomic_and_stale_temp_files_are_removed() {
    let f = Fixture::new();
    // A temp file a killed run left (PIDs above the kernel's maximum never run).
    let stale = f.p(".out.json.4194305.tmp");
    std::fs::write(&stale, "half a report").unwrap();
    let o = run(&eval_args(
        s(&f.p("in.mcap")),
        &["--json", s(&f.p("out.json"))],
    ));
    assert!(matches!(o.status.code(), Some(0 | 3)), "{}", stderr(&o));
    assert!(!stale.exists(), "stale temp file left");
    let names: Vec<String> = std::fs::read_dir(f.dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(!names.iter().any(|n| n.ends_with(".tmp")), "{names:?}");
    let _: serde_json::Value =
        serde_json::from_slice(&std::fs::read(f.p("out.json")).unwrap()).unwrap();
}

// 2. Parameter validation in one place: flag, value and range named, exit 2, nothing run.
#[test]
fn parameter_values_out_of_range_are_usage_errors() {
    let f = Fixture::new();
    let rec = f.p("in.mcap");
    let cases: [(&[&str], &str); 9] = [
        (&["--max-offset", "1e9"], "--max-offset 1e9"),
        (&["--grid", "1e-9"], "--grid 1e-9"),
        (&["--grid", "1e-5"], "--grid 1e-5"),
        (&["--t-start", "nan"], "--t-start NaN"),
        (&["--origin", "nan,nan,nan"], "--origin latitude NaN"),
        (&["--origin", "a,b,c"], "--origin <LAT,LON,H>': takes three"),
        (&["--time-offset", "1e300"], "--time-offset 1e300"),
        (&["--window", "inf"], "--window inf"),
        (&["--overlap", "1"], "--overlap 1"),
    ];
    for (extra, says) in cases {
        let start = std::time::Instant::now();
        let o = run(&eval_args(s(&rec), extra));
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{extra:?}: {e}");
        assert!(e.contains(says), "{extra:?}: {e}");
        if !says.contains("takes three") {
            assert!(e.contains("expected a finite value in"), "{extra:?}: {e}");
        }
        assert!(
            start.elapsed().as_secs() < 10,
            "{extra:?} took {:?}",
            start.elapsed()
        );
    }
}

// 3. Bounded allocation: lengths from the file never allocate past the bytes that remain.
#[test]
fn huge_lengths_in_a_bag_or_mcap_stay_under_one_gigabyte() {
    let f = Fixture::new();
    let bag = std::fs::read(f.p("in.bag")).unwrap();
    let u32_at =
        |d: &[u8], at: usize| u32::from_le_bytes(d[at..at + 4].try_into().unwrap()) as usize;
    // The bag header record: its header length at 13, its data length after the header.
    let data_len_at = 13 + 4 + u32_at(&bag, 13);
    let next = data_len_at + 4 + u32_at(&bag, data_len_at);
    let next_data_len_at = next + 4 + u32_at(&bag, next);
    let mut cases = Vec::new();
    for at in [next, next_data_len_at] {
        let mut d = bag.clone();
        d[at..at + 4].copy_from_slice(&u32::MAX.to_le_bytes());
        cases.push(("bag", d));
    }
    let mcap = std::fs::read(f.p("in.mcap")).unwrap();
    // The first record after the magic and its opcode: a u64 length of 2^63.
    let mut d = mcap.clone();
    d[9..17].copy_from_slice(&(1u64 << 63).to_le_bytes());
    cases.push(("mcap", d));
    for (i, (ext, data)) in cases.iter().enumerate() {
        let path = f.p(&format!("huge{i}.{ext}"));
        std::fs::write(&path, data).unwrap();
        for args in [
            vec!["topics", s(&path)],
            vec![
                "export",
                s(&path),
                "--topic",
                "/estimate/odom",
                s(&f.p("o.tum")),
            ],
        ] {
            let o = limited(&args, 1 << 30);
            let e = stderr(&o);
            assert!(
                matches!(o.status.code(), Some(1 | 3)),
                "{args:?}: {:?} {e}",
                o.status
            );
            assert!(
                e.contains("damaged") || e.contains("cut short") || e.contains("cannot read"),
                "{args:?}: {e}"
            );
            assert!(!e.contains("memory allocation"), "{args:?}: {e}");
        }
    }
}

/// Runs trajdrift with its address space limited to `bytes` (RLIMIT_AS).
fn limited(args: &[&str], bytes: u64) -> Output {
    use std::os::unix::process::CommandExt;
    let mut c = bin();
    c.args(args);
    unsafe {
        c.pre_exec(move || {
            let lim = libc::rlimit {
                rlim_cur: bytes as libc::rlim_t,
                rlim_max: bytes as libc::rlim_t,
            };
            if libc::setrlimit(libc::RLIMIT_AS, &lim) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
    c.output().expect("run trajdrift")
}

// 4. `topics` says when a recording is truncated, damaged or empty (exit 3 / 1).
#[test]
fn topics_names_truncation_damage_and_emptiness() {
    let f = Fixture::new();
    for name in ["in.mcap", "in.bag"] {
        let bytes = std::fs::read(f.p(name)).unwrap();
        let cut = f.p(&format!("cut.{name}"));
        std::fs::write(&cut, &bytes[..bytes.len() * 2 / 3]).unwrap();
        let o = run(&["topics", s(&cut)]);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(3), "{name}: {e}");
        assert!(
            e.contains("warning [truncated_recording]") && e.contains("cut short at byte"),
            "{e}"
        );
    }
    let empty = f.p("empty.mcap");
    std::fs::write(&empty, b"").unwrap();
    let o = run(&["topics", s(&empty)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("the file is empty (0 bytes)"),
        "{}",
        stderr(&o)
    );
    let magic = f.p("magic.mcap");
    std::fs::write(&magic, b"\x89MCAP0\r\n").unwrap();
    let o = run(&["topics", s(&magic)]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert!(stderr(&o).contains("cut short at byte 8"), "{}", stderr(&o));
    // A well-formed MCAP without a channel is empty.
    let none = f.p("none.mcap");
    let w = mcap::Writer::new(std::io::BufWriter::new(
        std::fs::File::create(&none).unwrap(),
    ));
    w.unwrap().finish().unwrap();
    let o = run(&["topics", s(&none)]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert!(stderr(&o).contains("empty recording"), "{}", stderr(&o));
    // A topic missing before the cut is named as damage at its byte offset.
    let o = run(&[
        "export",
        s(&magic),
        "--topic",
        "/estimate/odom",
        s(&f.p("o.tum")),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("damaged at byte 8"), "{}", stderr(&o));
}

// 5. Exit codes from one type; a closed stdout ends quietly; an I/O error says its cause once.
#[test]
fn io_errors_say_their_cause_once_with_a_hint() {
    let o = run(&["topics", "/nonexistent/x.mcap"]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(e.matches("No such file or directory").count(), 1, "{e}");
    assert!(e.contains("check the path"), "{e}");
    assert_eq!(e.lines().count(), 1, "{e}");
}

#[test]
fn a_closed_stdout_ends_quietly() {
    let f = Fixture::new();
    let rec = f.p("in.mcap");
    for args in [
        vec!["topics", s(&rec)],
        eval_args(s(&rec), &["--json", "-"]),
    ] {
        let mut child = bin()
            .args(&args)
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        drop(child.stdout.take()); // the reader went away, like `| head -0`
        let o = child.wait_with_output().unwrap();
        let e = stderr(&o);
        assert!(
            matches!(o.status.code(), Some(0 | 3)),
            "{args:?}: {:?} {e}",
            o.status
        );
        assert!(
            !e.contains("panicked") && !e.contains("Broken pipe"),
            "{args:?}: {e}"
        );
    }
}

// 6. Every dropped row is counted, per reason, in the report and the text output.
#[test]
fn dropped_rows_are_counted_per_reason() {
    let f = Fixture::new();
    let est = std::fs::read_to_string(f.p("est.tum")).unwrap();
    let mut lines: Vec<&str> = est.lines().collect();
    let dup = lines[10];
    lines.insert(11, dup); // a duplicate stamp
    lines.swap(20, 21); // a stamp going back
    let mut text: Vec<String> = lines.iter().map(|s| s.to_string()).collect();
    let fields: Vec<&str> = lines[30].split(' ').collect();
    text[30] = format!("{} inf {}", fields[0], fields[2..].join(" "));
    let fields: Vec<&str> = lines[40].split(' ').collect();
    text[40] = format!("{} 1e300 {}", fields[0], fields[2..].join(" "));
    std::fs::write(f.p("dirty.tum"), text.join("\n") + "\n").unwrap();
    let json = f.p("dirty.json");
    let o = run(&[
        "eval",
        "--reference-file",
        s(&f.p("ref.tum")),
        "--estimate-file",
        s(&f.p("dirty.tum")),
        "--json",
        s(&json),
    ]);
    assert!(matches!(o.status.code(), Some(0 | 3)), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    let r: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    let rows = &r["estimates"][0]["rows"];
    assert_eq!(rows["read"], text.len() as u64, "{rows}");
    assert_eq!(rows["not_finite"], 1, "{rows}");
    assert_eq!(rows["out_of_range"], 1, "{rows}");
    assert_eq!(rows["duplicate_stamp"], 1, "{rows}");
    assert_eq!(rows["stamp_going_back"], 1, "{rows}");
    assert_eq!(r["estimates"][0]["dropped_samples"], 3);
    assert!(
        out.contains("3 dropped (1 not finite, 1 out of range, 1 duplicate stamp), 1 with a stamp going back"),
        "{out}"
    );
}

#[test]
fn v102_says_why_807_rows_gave_803_samples() {
    let Some(shared) = common::shared() else {
        return;
    };
    let evo = shared.join("evo-data");
    let o = run(&[
        "eval",
        "--reference-file",
        s(&evo.join("V102_groundtruth.csv")),
        "--estimate-file",
        s(&evo.join("V102.txt")),
        "--json",
        "-",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let r: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let e = &r["estimates"][0];
    assert_eq!(
        (e["samples"].as_u64(), e["rows"]["read"].as_u64()),
        (Some(803), Some(807))
    );
    assert_eq!(e["rows"]["duplicate_stamp"], 4);
}

// 7. Names from files are escaped in every message and table.
#[test]
fn names_from_files_are_escaped() {
    let f = Fixture::new();
    let path = f.p("evil.bag");
    let file = std::fs::File::create(&path).unwrap();
    let mut w = trajdrift::sources::bag::writer::BagWriter::new(
        std::io::BufWriter::new(file),
        BagCompression::None,
        4096,
    )
    .unwrap();
    let c = w.add_connection("/a\nerror: fake\x1b[31m", "nav_msgs/Odometry");
    w.write(c, 1, &[0u8; 4]).unwrap();
    w.finish().unwrap();
    let o = run(&["topics", s(&path)]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("/a\\nerror: fake\\x1b[31m"), "{out}");
    assert!(
        !out.contains('\x1b') && !out.lines().any(|l| l.starts_with("error")),
        "{out}"
    );
    let o = run(&["export", s(&path), "--topic", "/nope", s(&f.p("o.tum"))]);
    let e = stderr(&o);
    assert_eq!(e.lines().count(), 1, "{e}");
    assert!(
        e.contains("/a\\nerror: fake\\x1b[31m") && !e.contains('\x1b'),
        "{e}"
    );
    // A message that fails to decode names the topic escaped too.
    let o = run(&[
        "export",
        s(&path),
        "--topic",
        "/a\nerror: fake\x1b[31m",
        s(&f.p("o.tum")),
    ]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert_eq!(e.lines().count(), 1, "{e}");
    assert!(!e.contains('\x1b'), "{e}");
}

#[test]
fn help_texts_name_every_recording_format() {
    for cmd in ["eval", "topics"] {
        let o = run(&[cmd, "--help"]);
        let out = String::from_utf8_lossy(&o.stdout);
        assert!(!out.contains("The recording (.mcap)"), "{cmd}: {out}");
        assert!(out.contains("ROS 1 bag"), "{cmd}: {out}");
    }
}

// 8 (in `cargo test`). Seeded mutation test: 2000 mutants of an MCAP and 2000 of a bag, read in a child
// process of this test binary under a 1 GB address-space limit: no panic, no hang, no abort.

/// Mutants per recording.
const MUTANTS: usize = 2000;
/// The whole child (500 mutants) must end within this.
const CHILD_TIMEOUT: std::time::Duration = std::time::Duration::from_secs(120);

/// One mutant of `base`: a few byte flips, a hostile length written over a u32/u64, a cut, or a
/// slice repeated, chosen by `rng`.
fn mutate(base: &[u8], rng: &mut rand_chacha::ChaCha8Rng) -> Vec<u8> {
    use rand::Rng;
    let mut d = base.to_vec();
    for _ in 0..rng.random_range(1..=3) {
        let n = d.len().max(1);
        match rng.random_range(0..5) {
            0 => {
                for _ in 0..rng.random_range(1..=8) {
                    let i = rng.random_range(0..n);
                    if let Some(b) = d.get_mut(i) {
                        *b ^= 1 << rng.random_range(0..8);
                    }
                }
            }
            1 | 2 => {
                let hostile: [u64; 6] = [u64::MAX, u32::MAX as u64, 1 << 31, 1 << 40, 0, n as u64];
                let v = hostile[rng.random_range(0..hostile.len())];
                let width = if rng.random_bool(0.5) { 4 } else { 8 };
                let i = rng.random_range(0..n);
                let bytes = v.to_le_bytes();
                for (k, b) in bytes[..width].iter().enumerate() {
                    if let Some(x) = d.get_mut(i + k) {
                        *x = *b;
                    }
                }
            }
            3 => d.truncate(rng.random_range(0..n)),
            _ => {
                let a = rng.random_range(0..n);
                let b = (a + rng.random_range(1..=64)).min(d.len());
                let slice = d.get(a..b).map(<[u8]>::to_vec).unwrap_or_default();
                let at = rng.random_range(0..=d.len());
                d.splice(at..at, slice);
            }
        }
    }
    d
}

/// Everything a user can ask of a recording; errors are fine, panics are not. Returns how far it
/// got: 0 refused at open, 1 no topics, 2 topics listed, 3 trajectories extracted.
fn exercise(path: &Path) -> usize {
    use trajdrift::sources::{ExtractOptions, Source};
    let Ok(source) = trajdrift::sources::open(path) else {
        return 0;
    };
    let source: &dyn Source = source.as_ref();
    let Ok(topics) = source.topics() else {
        return 1;
    };
    let _ = source.frame_pairs_checked(&|_| {});
    let readable: Vec<String> = topics
        .iter()
        .filter(|t| t.readable)
        .map(|t| t.topic.clone())
        .collect();
    match source.extract(&readable, &ExtractOptions::default(), &|_| {}) {
        Ok(_) => 3,
        Err(_) => 2,
    }
}

/// The child's work, when `HOSTILE_MUTANTS` names a recording kind: read every mutant, catching
/// panics, and print `mutants: N, panics: P` (the parent checks it). A no-op otherwise.
#[test]
fn mutation_child() {
    use rand::SeedableRng;
    let Ok(kind) = std::env::var("HOSTILE_MUTANTS") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let base_path = dir.path().join(format!("base.{kind}"));
    match kind.as_str() {
        "mcap" => small_mcap(&base_path, 20),
        _ => small_bag(&base_path, BagCompression::Lz4, 10),
    }
    let base = std::fs::read(&base_path).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
    std::panic::set_hook(Box::new(|_| {}));
    let mut panics = Vec::new();
    let mut reached = [0usize; 4];
    for i in 0..MUTANTS {
        let path = dir.path().join(format!("m{i}.{kind}"));
        std::fs::write(&path, mutate(&base, &mut rng)).unwrap();
        match std::panic::catch_unwind(|| exercise(&path)) {
            Ok(stage) => reached[stage] += 1,
            Err(_) => panics.push(i),
        }
        std::fs::remove_file(&path).unwrap();
    }
    println!("mutants: {MUTANTS}, panics: {panics:?}");
    println!(
        "refused at open {}, topics failed {}, extraction failed {}, extracted {}",
        reached[0], reached[1], reached[2], reached[3]
    );
}

fn run_mutants(kind: &str) {
    use std::os::unix::process::CommandExt;
    let exe = std::env::current_exe().unwrap();
    let mut c = Command::new(exe);
    c.args([
        "--exact",
        "hostile::mutation_child",
        "--nocapture",
        "--test-threads",
        "1",
    ])
    .env("HOSTILE_MUTANTS", kind)
    .stdout(std::process::Stdio::piped())
    .stderr(std::process::Stdio::piped());
    let limit: u64 = 1 << 30;
    unsafe {
        c.pre_exec(move || {
            let lim = libc::rlimit {
                rlim_cur: limit as libc::rlim_t,
                rlim_max: limit as libc::rlim_t,
            };
            if libc::setrlimit(libc::RLIMIT_AS, &lim) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
    let start = std::time::Instant::now();
    let mut child = c.spawn().unwrap();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > CHILD_TIMEOUT {
            child.kill().unwrap();
            panic!("{kind}: {MUTANTS} mutants did not finish within {CHILD_TIMEOUT:?} (a hang)");
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    let o = child.wait_with_output().unwrap();
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{kind}: the child died ({:?}; an allocation over 1 GB aborts): {out} {}",
        o.status,
        stderr(&o)
    );
    assert!(
        out.contains(&format!("mutants: {MUTANTS}, panics: []")),
        "{kind}: {out}"
    );
    let stages = out
        .lines()
        .find(|l| l.contains("refused at open"))
        .unwrap_or_else(|| panic!("{kind}: no summary line in {out}"));
    eprintln!(
        "{kind}: {MUTANTS} mutants in {:.1} s: {stages}",
        start.elapsed().as_secs_f64()
    );
    // The mutants must reach the readers' depths, not only the magic check.
    assert!(!stages.ends_with("extracted 0"), "{kind}: {stages}");
}

#[test]
fn mutated_mcaps_never_panic_hang_or_exceed_1gb() {
    run_mutants("mcap");
}

#[test]
fn mutated_bags_never_panic_hang_or_exceed_1gb() {
    run_mutants("bag");
}

/// The record-length checks accept every valid file: the summary of each of the 416 MCAP
/// conformance variants (every record type, with and without summaries, statistics, indexes).
#[test]
fn length_checks_accept_every_conformance_file() {
    let Some(shared) = common::shared() else {
        return;
    };
    let root = shared.join("conformance/data");
    let mut n = 0;
    for d in std::fs::read_dir(&root).unwrap() {
        for e in std::fs::read_dir(d.unwrap().path()).unwrap() {
            let p = e.unwrap().path();
            if p.extension().is_some_and(|e| e == "mcap") {
                trajdrift::sources::mcap::lengths::check_summary(&p, 64 << 20)
                    .unwrap_or_else(|d| panic!("{}: {d}", p.display()));
                n += 1;
            }
        }
    }
    assert_eq!(n, 416);
}

/// Batch outputs go through the same guard: `--annotate` into the recordings' own folder would
/// replace `in.mcap` with its annotated copy.
#[test]
fn batch_outputs_that_resolve_to_an_input_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("in.mcap");
    small_mcap(&rec, 400);
    let before = std::fs::read(&rec).unwrap();
    let o = run(&[
        "batch",
        s(dir.path()),
        "--reference",
        "/reference/position",
        "--estimate",
        "/estimate/odom",
        "--out",
        s(dir.path()),
        "--annotate",
        "--force",
        "-q",
    ]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("writing it would destroy the input"), "{e}");
    assert_eq!(std::fs::read(&rec).unwrap(), before);
}

/// Fuzzing finds, kept as regression tests: each input must end, with an error or a result, within
/// seconds.
#[test]
fn fuzz_regressions_end_quickly() {
    let dir = tempfile::tempdir().unwrap();
    // text_readers timeout: a KITTI row whose matrix holds 7.7e17 made the rotation projection loop
    // for ever.
    let cases: [(&str, &[u8]); 1] = [(
        "kitti_huge_matrix.txt",
        b"1 0 0 0 077777777777777777 1 0 0 0 0 1 0\n]1 \x01\x00\x00\x85",
    )];
    for (name, bytes) in cases {
        let path = dir.path().join(name);
        std::fs::write(&path, bytes).unwrap();
        let start = std::time::Instant::now();
        let o = run(&["export", s(&path), s(&dir.path().join("o.tum"))]);
        assert!(
            matches!(o.status.code(), Some(0..=3)),
            "{name}: {:?}",
            o.status
        );
        assert!(
            start.elapsed().as_secs() < 10,
            "{name}: {:?}",
            start.elapsed()
        );
    }
}

/// Asserts a usage error (exit 2) said on one line that contains `says`, within seconds.
#[track_caller]
fn one_line_usage_error(args: &[&str], says: &str) {
    let start = std::time::Instant::now();
    let o = run(args);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{args:?}: {e}");
    assert_eq!(e.trim_end().lines().count(), 1, "{args:?}: {e}");
    assert!(e.contains(says), "{args:?}: {e}");
    assert!(
        start.elapsed().as_secs() < 10,
        "{args:?} took {:?}",
        start.elapsed()
    );
}

/// The offset profile's window and step have a floor (a step of a microsecond made tens of GB of
/// windows), on the command line of eval and audit and in a manifest alike.
#[test]
fn offset_profile_window_and_step_have_a_floor() {
    let f = Fixture::new();
    let rec = f.p("in.mcap");
    for (flag, value, says) in [
        (
            "--offset-window",
            "1e-6",
            "--offset-window 1e-6: out of range; expected a finite value in [1, 86400] s",
        ),
        (
            "--offset-step",
            "1e-6",
            "--offset-step 1e-6: out of range; expected a finite value in [0.1, 86400] s",
        ),
        (
            "--offset-step",
            "0.001",
            "--offset-step 0.001: out of range",
        ),
    ] {
        one_line_usage_error(&eval_args(s(&rec), &[flag, value]), says);
    }
    one_line_usage_error(
        &["audit", s(&rec), "--offset-step", "1e-6", "-q"],
        "--offset-step 1e-6: out of range",
    );
    let manifest = f.p("m.toml");
    std::fs::write(
        &manifest,
        format!(
            "[defaults]\noffset_step = 1e-7\n\n[[mission]]\nname = \"a\"\nrecording = \"{}\"\nreference = \"/reference/position\"\nestimates = [\"/estimate/odom\"]\n",
            s(&rec)
        ),
    )
    .unwrap();
    let out = f.p("out");
    one_line_usage_error(
        &["batch", s(&manifest), "--out", s(&out), "-q"],
        "offset_step 1e-7: out of range",
    );
}

/// One stamp years late made a span the offset search (eval) or the simulation (validate --like)
/// could not hold: refused naming the file and the gap, on one line.
#[test]
fn a_stamp_years_late_is_refused_naming_its_file_and_gap() {
    let f = Fixture::new();
    let text = std::fs::read_to_string(f.p("ref.tum")).unwrap();
    for (name, late) in [("bad1e7.tum", "1e7"), ("bad1e300.tum", "1e300")] {
        let mut rows: Vec<String> = text.lines().map(String::from).collect();
        let k = rows.len() / 2;
        let (stamp, rest) = rows[k].split_once(' ').unwrap();
        let stamp = stamp.parse::<f64>().unwrap() + late.parse::<f64>().unwrap();
        rows[k] = format!("{stamp:e} {rest}");
        let bad = f.p(name);
        std::fs::write(&bad, rows.join("\n") + "\n").unwrap();
        let est = f.p("est.tum");
        for args in [
            vec![
                "eval",
                "--reference-file",
                s(&bad),
                "--estimate-file",
                s(&est),
                "-q",
            ],
            vec![
                "validate",
                "--missions",
                "1",
                "--reference-file",
                s(&bad),
                "--estimate-file",
                s(&est),
            ],
        ] {
            one_line_usage_error(&args, &format!("{}: a gap of", s(&bad)));
        }
    }
}

/// `simulate` refuses numbers that are not finite or beyond what a mission can be, naming the flag,
/// before anything is simulated or written.
#[test]
fn simulate_refuses_numbers_out_of_range() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("sim.mcap");
    let cases: [(&[&str], &str); 9] = [
        (&["--est-rate", "1e9"], "--est-rate 1e9: out of range"),
        (&["--laps", "1000000"], "--laps 1000000: out of range"),
        (&["--duration", "1e12"], "--duration 1e12: out of range"),
        (&["--time-offset", "nan"], "--time-offset NaN: out of range"),
        (
            &["--time-offset", "1e300"],
            "--time-offset 1e300: out of range",
        ),
        (
            &["--clock-drift-ppm", "-1e6"],
            "--clock-drift-ppm -1e6: out of range",
        ),
        (&["--lever", "nan,0,0"], "--lever x NaN: out of range"),
        (&["--scale-error", "nan"], "--scale-error NaN: out of range"),
        (
            &["--duration", "21600", "--est-rate", "1000"],
            "--est-rate 1000:",
        ),
    ];
    for (extra, says) in cases {
        let mut args = vec!["simulate", s(&out)];
        args.extend_from_slice(extra);
        one_line_usage_error(&args, says);
        assert!(!out.exists(), "{extra:?}");
    }
}

/// A `--transform_left/--transform_right` file with a zero or non-finite quaternion (which made the
/// normalisation loop for ever) or a scale of zero (NaN poses once inverted) is refused by name.
#[test]
fn transforms_without_a_rotation_or_scale_are_refused() {
    let f = Fixture::new();
    let one = f.p("est.tum");
    let cases = [
        (
            "tfz.json",
            r#"{"x":0,"y":0,"z":0,"qx":0,"qy":0,"qz":0,"qw":0}"#,
            "has no rotation",
        ),
        (
            "tfs0.json",
            r#"{"x":0,"y":0,"z":0,"qx":0,"qy":0,"qz":0,"qw":1,"scale":0}"#,
            "scale 0",
        ),
        (
            "tfm.txt",
            "1 0 0 0\n0 1 0 nan\n0 0 1 0\n0 0 0 1\n",
            "not finite",
        ),
    ];
    for (name, text, says) in cases {
        let tf = f.p(name);
        std::fs::write(&tf, text).unwrap();
        for flag in ["--transform_left", "--transform_right"] {
            for invert in [false, true] {
                let mut args = vec!["traj", "tum", s(&one), flag, s(&tf)];
                if invert {
                    args.push("--invert_transform");
                }
                one_line_usage_error(&args, &format!("{}: ", s(&tf)));
                one_line_usage_error(&args, says);
            }
        }
    }
}

/// ape and rpe drop the rows that are not finite, like every reader: the numbers are those of the
/// file without them, and the alignment and the pairs are found.
#[test]
fn ape_and_rpe_drop_rows_not_finite_like_every_reader() {
    let f = Fixture::new();
    let (r, e) = (f.p("ref.tum"), f.p("est.tum"));
    let text = std::fs::read_to_string(&e).unwrap();
    let rows: Vec<&str> = text.lines().filter(|l| !l.starts_with('#')).collect();
    let (mut with_nan, mut without) = (String::new(), String::new());
    for (i, row) in rows.iter().enumerate() {
        if i % 37 == 5 {
            let v: Vec<&str> = row.split(' ').collect();
            with_nan.push_str(&format!("{} {} nan {}\n", v[0], v[1], v[3..].join(" ")));
        } else {
            with_nan.push_str(&format!("{row}\n"));
            without.push_str(&format!("{row}\n"));
        }
    }
    let (nan, dropped) = (f.p("est_nan.tum"), f.p("est_dropped.tum"));
    std::fs::write(&nan, with_nan).unwrap();
    std::fs::write(&dropped, without).unwrap();
    for extra in [
        vec!["ape", "--t_max_diff", "0.02"],
        vec!["ape", "--t_max_diff", "0.02", "-a"],
        vec!["rpe", "--t_max_diff", "0.02"],
    ] {
        let stats = |est: &std::path::Path| {
            let mut args = vec![extra[0], "tum", s(&r), s(est)];
            args.extend_from_slice(&extra[1..]);
            args.extend_from_slice(&["--json", "-"]);
            let o = run(&args);
            assert_eq!(o.status.code(), Some(0), "{args:?}: {}", stderr(&o));
            let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
            v["stats"].clone()
        };
        let (a, b) = (stats(&nan), stats(&dropped));
        assert!(
            a["sse"].as_f64().is_some_and(f64::is_finite),
            "{extra:?}: {a}"
        );
        assert_eq!(a, b, "{extra:?}");
    }
}

/// evo's numeric flags of ape and rpe are checked like eval's: a usage error naming the flag.
#[test]
fn evo_numeric_flags_out_of_range_are_usage_errors() {
    let f = Fixture::new();
    let (r, e) = (f.p("ref.tum"), f.p("est.tum"));
    let cases: [(&[&str], &str); 7] = [
        (
            &["--motion_filter", "-1", "-1"],
            "--motion_filter DISTANCE -1: out of range",
        ),
        (
            &["--motion_filter", "nan", "0"],
            "--motion_filter DISTANCE NaN: out of range",
        ),
        (
            &["--motion_filter", "0", "inf"],
            "--motion_filter ANGLE_DEGREES inf: out of range",
        ),
        (
            &["--plot_colormap_max", "nan"],
            "--plot_colormap_max NaN: out of range",
        ),
        (
            &["--plot_colormap_max_percentile", "200"],
            "--plot_colormap_max_percentile 200: out of range",
        ),
        (
            &["--plot_colormap_max_percentile", "-5"],
            "--plot_colormap_max_percentile -5: out of range",
        ),
        (
            &["--plot_colormap_min", "2", "--plot_colormap_max", "1"],
            "--plot_colormap_min 2 must be below --plot_colormap_max 1",
        ),
    ];
    for (extra, says) in cases {
        for metric in ["ape", "rpe"] {
            let mut args = vec![metric, "tum", s(&r), s(&e)];
            args.extend_from_slice(extra);
            one_line_usage_error(&args, says);
        }
    }
    one_line_usage_error(
        &["traj", "tum", s(&e), "--motion_filter", "nan", "0"],
        "--motion_filter DISTANCE NaN: out of range",
    );
}

/// The sim_ground fixture's MCAP, copied into `dir` with its last `cut` bytes left out.
fn cut_fixture(dir: &Path, cut: usize) -> PathBuf {
    let bytes = std::fs::read(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/fixtures/sim_ground/mission.mcap"
    ))
    .unwrap();
    let p = dir.join(format!("cut{cut}.mcap"));
    std::fs::write(&p, &bytes[..bytes.len() - cut]).unwrap();
    p
}

fn assert_truncated(what: &str, o: &Output) {
    let e = stderr(o);
    assert_eq!(o.status.code(), Some(3), "{what}: {e}");
    assert!(e.contains("warning [truncated_recording]"), "{what}: {e}");
}

// An MCAP whose data is whole but whose summary or footer is cut off is a truncated recording.
#[test]
fn an_mcap_cut_after_its_data_is_truncated() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o.tum");
    for cut in [1, 8, 37, 100, 1500] {
        let rec = cut_fixture(dir.path(), cut);
        let o = run(&["topics", s(&rec)]);
        assert_truncated(&format!("topics, {cut} bytes cut"), &o);
        let o = run(&["export", s(&rec), "--topic", "/reference/position", s(&out)]);
        assert_truncated(&format!("export, {cut} bytes cut"), &o);
        assert!(stderr(&o).contains("no footer"), "{}", stderr(&o));
    }
    // The whole file is not.
    let whole = cut_fixture(dir.path(), 0);
    let o = run(&[
        "export",
        s(&whole),
        "--topic",
        "/reference/position",
        s(&out),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
}

// Every command that reads a recording carries its truncation to exit code 3.
#[test]
fn every_reading_command_exits_3_on_a_truncated_recording() {
    let dir = tempfile::tempdir().unwrap();
    let rec = cut_fixture(dir.path(), 1);
    let r = s(&rec);
    let topics = [
        "--reference",
        "/reference/position",
        "--estimate",
        "/estimate/odom",
    ];
    let sweep = dir.path().join("sweep");
    let fixed = dir.path().join("fixed.mcap");
    let cases: Vec<(&str, Vec<&str>)> = vec![
        ("ape", [&["ape", r][..], &topics].concat()),
        (
            "rpe",
            [&["rpe", r][..], &topics, &["-r", "point_distance"]].concat(),
        ),
        ("traj", vec!["traj", "mcap", r, "/estimate/odom"]),
        (
            "sweep",
            [
                &[
                    "sweep",
                    r,
                    "--param",
                    "window",
                    "--values",
                    "10",
                    "--time-offset",
                    "0",
                ][..],
                &["--out", s(&sweep)],
                &topics,
            ]
            .concat(),
        ),
        (
            "validate --like",
            [&["validate", "--like", r, "--missions", "1"][..], &topics].concat(),
        ),
        (
            "export",
            vec!["export", r, "--topic", "/estimate/odom", "-"],
        ),
        ("restamp", vec!["restamp", r, "--out", s(&fixed), "--quiet"]),
    ];
    for (what, args) in cases {
        assert_truncated(what, &run(&args));
    }
}

// `topics` counts what the readers read in a bag whose index is cut short, and says it is cut.
#[test]
fn topics_counts_a_bag_with_its_index_cut_as_the_readers_read_it() {
    let f = Fixture::new();
    let bytes = std::fs::read(f.p("in.bag")).unwrap();
    let cut = f.p("cut.bag");
    std::fs::write(&cut, &bytes[..bytes.len() - 10]).unwrap();
    let o = run(&["topics", s(&cut), "--json", "-"]);
    assert_truncated("topics", &o);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let count = |topic: &str| {
        v["topics"]
            .as_array()
            .unwrap()
            .iter()
            .find(|t| t["topic"] == topic)
            .map(|t| t["message_count"].as_u64().unwrap())
    };
    let out = f.p("o.tum");
    let o = run(&["export", s(&cut), "--topic", "/reference/position", s(&out)]);
    assert_truncated("export", &o);
    let exported = std::fs::read_to_string(&out).unwrap().lines().count() as u64;
    assert_eq!(count("/reference/position"), Some(exported), "{v}");
    assert_eq!(exported, 40);
}

// An audit of a recording cut before any pose topic fails on the damage, not as a usage error.
#[test]
fn audit_of_a_recording_cut_before_its_topics_is_a_failure() {
    let dir = tempfile::tempdir().unwrap();
    let bytes = std::fs::read(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/fixtures/sim_ground/mission.mcap"
    ))
    .unwrap();
    let rec = dir.path().join("cut.mcap");
    std::fs::write(&rec, &bytes[..100]).unwrap();
    let o = run(&["audit", s(&rec)]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("damaged at byte"), "{}", stderr(&o));
}

// `offset` warns (exit 3) when no method finds a confident offset, as `eval` does.
#[test]
fn offset_exits_3_when_no_method_is_confident() {
    let dir = tempfile::tempdir().unwrap();
    let still = dir.path().join("still.tum");
    let rows: String = (0..600)
        .map(|i| format!("{:.3} 1 2 3 0 0 0 1\n", 100.0 + i as f64 * 0.1))
        .collect();
    std::fs::write(&still, rows).unwrap();
    let o = run(&["offset", "tum", s(&still), s(&still)]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(3), "{e}");
    assert!(e.contains("warning [weak_time_offset]"), "{e}");
}
