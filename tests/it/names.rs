//! Names are data, at the process boundary: topic names holding newlines, ANSI escapes, markup, a bidi
//! override and a spreadsheet formula reach the terminal, `summary.md`, `summary.csv`,
//! `summary.html`, the HTML report and the SVG figures, each through its sink's escaping.

use crate::robust_support::{expect_code, run, s, stderr, stdout, Snapshot};

/// Topics a hostile recording names its estimates with.
const EVIL: [&str; 3] = [
    "/a\nerror: fake\x1b[31m",
    "/<script>alert(1)</script>",
    "/evil\u{202e}fdp.exe",
];

/// A ROS 1 bag with a reference and one odometry channel per name of [`EVIL`].
fn evil_bag(path: &std::path::Path) {
    use trajdrift::decode::ros1;
    use trajdrift::decode::ros2_msgs::{Header, Odometry, Point, PointStamped, Time};
    use trajdrift::sources::bag::writer::{BagCompression, BagWriter};
    let file = std::fs::File::create(path).unwrap();
    let mut w =
        BagWriter::new(std::io::BufWriter::new(file), BagCompression::None, 1 << 16).unwrap();
    let r = w.add_connection("/reference/position", "geometry_msgs/PointStamped");
    let conns: Vec<u32> = EVIL
        .iter()
        .map(|t| w.add_connection(t, "nav_msgs/Odometry"))
        .collect();
    for i in 0..400u32 {
        let ns = 1_700_000_000_000_000_000 + i as i64 * 100_000_000;
        let header = Header {
            stamp: Time::from_ns(ns),
            frame_id: "map".into(),
        };
        let a = i as f64 * 0.05;
        let point = Point {
            x: 10.0 * a.cos() + a,
            y: 6.0 * (1.7 * a).sin(),
            z: 0.0,
        };
        let ps = PointStamped {
            header: header.clone(),
            point,
        };
        w.write(r, ns as u64, &ros1::encode_point_stamped(i, &ps))
            .unwrap();
        let mut o = Odometry {
            header,
            ..Default::default()
        };
        o.pose.pose.position = point;
        o.pose.pose.orientation.w = 1.0;
        for &c in &conns {
            w.write(c, ns as u64, &ros1::encode_odometry(i, &o))
                .unwrap();
        }
    }
    w.finish().unwrap();
}

/// No raw control, bidi or markup character of the hostile names in `text`.
#[track_caller]
fn clean(what: &str, text: &str, markup: bool) {
    assert!(!text.contains('\x1b'), "{what}: an escape character");
    assert!(!text.contains('\u{202e}'), "{what}: a bidi override");
    assert!(!text.contains("\nerror: fake"), "{what}: a faked line");
    if markup {
        assert!(!text.contains("<script"), "{what}: markup");
    }
}

#[test]
fn names_from_data_are_escaped_in_every_sink() {
    let dir = tempfile::tempdir().unwrap();
    let recs = dir.path().join("recs");
    std::fs::create_dir(&recs).unwrap();
    evil_bag(&recs.join("m.bag"));
    let snap = Snapshot::of(&[&recs]);
    let out = dir.path().join("out");
    let mut args = vec!["batch", s(&recs), "--reference", "/reference/position"];
    for t in EVIL {
        args.extend(["--estimate", t]);
    }
    let formula = "@HYPERLINK(\"http:x\")=/a\nerror: fake\x1b[31m";
    args.extend(["--time-offset", "0", "--plot", "--html", "--out", s(&out)]);
    let o = run(&args);
    expect_code(&o, &[0, 3], "batch");
    clean("batch stdout", &stdout(&o), false);
    clean("batch stderr", &stderr(&o), false);
    let read = |name: &str| std::fs::read_to_string(out.join(name)).unwrap();
    let md = read("summary.md");
    clean("summary.md", &md, false);
    // Markup is backslash-escaped in Markdown: shown, never interpreted.
    assert!(
        md.match_indices('<').all(|(i, _)| md[..i].ends_with('\\')),
        "{md}"
    );
    clean("summary.csv", &read("summary.csv"), false);
    clean("summary.html", &read("summary.html"), true);
    clean("m.html", &read("m.html"), true);
    let csv = read("summary.csv");
    // One row per estimate and a header: no name broke a row.
    assert_eq!(csv.lines().count(), 1 + EVIL.len(), "{csv}");
    for f in std::fs::read_dir(out.join("m_figures")).unwrap() {
        let p = f.unwrap().path();
        let svg = std::fs::read_to_string(&p).unwrap();
        clean(&p.display().to_string(), &svg, true);
        assert!(
            !svg.chars()
                .any(|c| c.is_control() && !matches!(c, '\n' | '\t' | '\r')),
            "{}: a character XML forbids",
            p.display()
        );
    }
    // A name that is a spreadsheet formula stays text in the CSV.
    let out2 = dir.path().join("out2");
    let o = run(&[
        "batch",
        s(&recs),
        "--reference",
        "/reference/position",
        "--estimate",
        formula,
        "--time-offset",
        "0",
        "--out",
        s(&out2),
        "-q",
    ]);
    expect_code(&o, &[0, 3], "a formula as a name");
    let csv = std::fs::read_to_string(out2.join("summary.csv")).unwrap();
    assert!(csv.contains("'@HYPERLINK"), "{csv}");
    assert!(
        !csv.lines().any(|l| l
            .split(',')
            .any(|c| c.trim_start_matches('"').starts_with(['=', '@', '+']))),
        "{csv}"
    );
    // The terminal table of eval.
    let bag = recs.join("m.bag");
    let mut args = vec!["eval", s(&bag), "--reference", "/reference/position"];
    for t in EVIL {
        args.extend(["--estimate", t]);
    }
    args.extend(["--time-offset", "0"]);
    let o = run(&args);
    expect_code(&o, &[0, 3], "eval");
    clean("eval stdout", &stdout(&o), false);
    clean("eval stderr", &stderr(&o), false);
    snap.assert_unchanged();
}
