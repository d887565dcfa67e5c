//! Figures, the HTML report and sweeps, at the process boundary:
//! the HTML of a shared fixture renders in headless Chromium to a non-blank page and loads nothing
//! from the network; `sweep --param eps-min` shows the paper's shape and equals single `eval` runs;
//! a 2-hour mission's figures stay small.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_trajdrift"))
}

fn run(args: &[&str]) -> Output {
    let o = bin().args(args).output().expect("run trajdrift");
    assert!(
        matches!(o.status.code(), Some(0) | Some(3)),
        "trajdrift {args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

const FIGURES: [&str; 5] = [
    "top_view",
    "drift_error",
    "offset_search",
    "offset_profile",
    "speed",
];

/// `eval --html` (and `--plot`) on the shared lever_arm fixture.
fn lever_arm_report(dir: &Path) -> Option<PathBuf> {
    let shared = common::shared()?;
    let rec = common::mission(&shared, "lever_arm").join("mission.mcap");
    let html = dir.join("report.html");
    run(&[
        "eval",
        s(&rec),
        "--reference",
        "/reference/position",
        "--estimate",
        "/estimate/odom",
        "--html",
        s(&html),
        "--plot",
        s(&dir.join("figures")),
        "-q",
    ]);
    Some(html)
}

/// Every value of a `src=`/`href=` attribute.
fn references(html: &str) -> Vec<String> {
    let mut out = Vec::new();
    for attr in ["src=", "href="] {
        for (i, _) in html.match_indices(attr) {
            let rest = &html[i + attr.len()..];
            let rest = rest.trim_start_matches(['"', '\'']);
            out.push(
                rest.chars()
                    .take_while(|c| !matches!(c, '"' | '\'' | ' ' | '>'))
                    .collect(),
            );
        }
    }
    out
}

#[test]
fn html_is_self_contained_with_every_figure_inline() {
    let dir = tempfile::tempdir().unwrap();
    let Some(html) = lever_arm_report(dir.path()) else {
        return;
    };
    let text = std::fs::read_to_string(&html).unwrap();
    let remote: Vec<String> = references(&text)
        .into_iter()
        .filter(|r| r.to_ascii_lowercase().starts_with("http"))
        .collect();
    assert!(remote.is_empty(), "network references: {remote:?}");
    for tag in ["<script", "<link", "<img", "<iframe", "@import", "url("] {
        assert!(!text.contains(tag), "{tag} in the report");
    }
    assert_eq!(
        text.matches("<svg").count(),
        FIGURES.len(),
        "one inline SVG per figure"
    );
    for name in FIGURES {
        let svg = dir.path().join(format!("figures/estimate_odom_{name}.svg"));
        assert!(svg.is_file(), "{} missing", svg.display());
    }
    for section in [
        "Parameters",
        "Time offset",
        "signed-curvature",
        "Drift Error",
        "Warnings",
    ] {
        assert!(text.contains(section), "{section} missing");
    }
    println!(
        "report.html: {} bytes, {} inline SVGs, 0 http(s) src/href",
        text.len(),
        FIGURES.len()
    );
}

/// The headless Chromium binary: Debian's `chromium-headless-shell` (`.ci/run` installs it).
fn chromium() -> Option<PathBuf> {
    for name in ["chromium-headless-shell", "chromium", "chromium-browser"] {
        for dir in ["/usr/bin", "/usr/local/bin", "/usr/lib/chromium"] {
            let p = Path::new(dir).join(name);
            if p.is_file() {
                return Some(p);
            }
        }
    }
    if std::env::var_os("CI").is_some() {
        panic!("chromium-headless-shell missing: .ci/run installs it (apt-get install chromium-headless-shell)");
    }
    eprintln!("skipped: chromium-headless-shell not installed");
    None
}

#[test]
fn html_renders_in_headless_chromium_to_a_non_blank_page() {
    let dir = tempfile::tempdir().unwrap();
    let Some(html) = lever_arm_report(dir.path()) else {
        return;
    };
    let Some(chrome) = chromium() else { return };
    let shot = dir.path().join("screenshot.png");
    let profile = dir.path().join("profile");
    let o = Command::new(&chrome)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--hide-scrollbars",
            &format!("--user-data-dir={}", profile.display()),
            "--window-size=1100,3200",
            &format!("--screenshot={}", shot.display()),
        ])
        .arg(format!("file://{}", html.display()))
        .output()
        .expect("run chromium");
    assert!(
        shot.is_file(),
        "no screenshot: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let decoder = png::Decoder::new(std::fs::File::open(&shot).unwrap());
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    let px = info.color_type.samples();
    let bytes = &buf[..info.buffer_size()];
    let (mut ink, mut colours) = (0usize, std::collections::HashSet::new());
    for p in bytes.chunks(px) {
        if p[..3].iter().any(|&c| c < 240) {
            ink += 1;
        }
        colours.insert((p[0] >> 3, p[1] >> 3, p[2] >> 3));
    }
    let n = bytes.len() / px;
    let share = ink as f64 / n as f64;
    println!(
        "screenshot {}x{}: {:.1} % non-white pixels, {} colours",
        info.width,
        info.height,
        100.0 * share,
        colours.len()
    );
    assert!(
        share > 0.02,
        "the page looks blank: {:.2} % ink",
        100.0 * share
    );
    assert!(
        colours.len() > 50,
        "too few colours for figures: {}",
        colours.len()
    );
    if let Ok(keep) = std::env::var("TRAJDRIFT_KEEP_SCREENSHOT") {
        std::fs::copy(&shot, keep).unwrap();
    }
}

/// Parses sweep.csv into (value, de_median, de_rmse, discarded_fraction).
fn sweep_rows(csv: &str) -> Vec<(f64, f64, f64, f64)> {
    let mut lines = csv.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |n: &str| head.iter().position(|h| *h == n).unwrap();
    let (v, m, r, d) = (
        col("value"),
        col("de_median"),
        col("de_rmse"),
        col("discarded_fraction"),
    );
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            let p = |i: usize| f[i].parse::<f64>().unwrap();
            (p(v), p(m), p(r), p(d))
        })
        .collect()
}

#[test]
fn sweep_eps_min_has_the_papers_shape_and_equals_single_runs() {
    let Some(shared) = common::shared() else {
        return;
    };
    let rec = common::mission(&shared, "lever_arm").join("mission.mcap");
    let dir = tempfile::tempdir().unwrap();
    let topics = [
        "--reference",
        "/reference/position",
        "--estimate",
        "/estimate/odom",
    ];
    let mut args = vec!["sweep", s(&rec)];
    args.extend(topics);
    args.extend([
        "--param",
        "eps-min",
        "--values",
        "0.05,0.1,0.2,0.5,1,2",
        "-q",
    ]);
    args.extend(["--out", s(dir.path())]);
    run(&args);
    let csv = std::fs::read_to_string(dir.path().join("sweep.csv")).unwrap();
    let svg = std::fs::read_to_string(dir.path().join("sweep.svg")).unwrap();
    assert!(svg.contains("<svg") && svg.contains("discarded"));
    let rows = sweep_rows(&csv);
    println!("eps_min  DE median  DE RMSE  discarded");
    for r in &rows {
        println!("{:7}  {:9.4}  {:7.4}  {:9.3}", r.0, r.1, r.2, r.3);
    }
    assert_eq!(
        rows.iter().map(|r| r.0).collect::<Vec<_>>(),
        [0.05, 0.1, 0.2, 0.5, 1.0, 2.0]
    );
    // DE falls as ε grows: noise inflates the estimate's path at small ε; from 0.5 m on it sits at the
    // simulated 2 % scale error.
    let truth = common::truth(&shared, "lever_arm")["parameters"]["scale_error"]
        .as_f64()
        .unwrap_or(0.02);
    assert!(
        rows[0].2 > 1.5 * rows[3].2,
        "DE RMSE does not fall: {rows:?}"
    );
    for r in &rows[3..] {
        assert!(
            (r.1 - truth).abs() < 0.005,
            "plateau {} vs truth {truth}",
            r.1
        );
    }
    // The discarded share only grows, and is past half the path beyond ~0.5 m.
    assert!(rows.windows(2).all(|w| w[1].3 >= w[0].3), "{rows:?}");
    assert!(rows[2].3 < 0.5 && rows[3].3 > 0.5, "{rows:?}");
    // Each row equals the single eval at that value.
    for (k, v) in [(1usize, "0.1"), (4, "1")] {
        let json = dir.path().join(format!("eval_{v}.json"));
        let mut a = vec!["eval", s(&rec)];
        a.extend(topics);
        a.extend(["--eps-min", v, "--json", s(&json), "-q"]);
        run(&a);
        let r: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
        let d = &r["estimates"][0]["drift_error"][0];
        assert_eq!(d["median"].as_f64().unwrap(), rows[k].1, "median at {v}");
        assert_eq!(d["rmse"].as_f64().unwrap(), rows[k].2, "rmse at {v}");
        assert_eq!(
            d["discarded_fraction"].as_f64().unwrap(),
            rows[k].3,
            "discarded at {v}"
        );
    }
}

#[test]
fn sweep_time_offset_marks_each_methods_answer() {
    let Some(shared) = common::shared() else {
        return;
    };
    let rec = common::mission(&shared, "lever_arm").join("mission.mcap");
    let dir = tempfile::tempdir().unwrap();
    run(&[
        "sweep",
        s(&rec),
        "--reference",
        "/reference/position",
        "--estimate",
        "/estimate/odom",
        "--param",
        "time-offset",
        "--values",
        "-0.4:0.6:0.5",
        "--out",
        s(dir.path()),
        "-q",
    ]);
    let csv = std::fs::read_to_string(dir.path().join("sweep.csv")).unwrap();
    let rows = sweep_rows(&csv);
    assert_eq!(
        rows.iter().map(|r| r.0).collect::<Vec<_>>(),
        [-0.4, 0.1, 0.6]
    );
    // The DE is smallest near the true offset (0.1 s).
    assert!(rows[1].2 < rows[0].2 && rows[1].2 < rows[2].2, "{rows:?}");
    let svg = std::fs::read_to_string(dir.path().join("sweep.svg")).unwrap();
    for m in ["speed", "signed-curvature", "curvature"] {
        assert!(svg.contains(&format!("{m}: Δt")), "{m} not marked");
    }
}

#[test]
fn figures_of_a_two_hour_mission_stay_under_2_mb() {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("long.mcap");
    // 60 laps of the simulator's 121 s route: 7260 s.
    let o = bin()
        .args(["simulate", s(&rec), "--laps", "60"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let figs = dir.path().join("figures");
    run(&[
        "eval",
        s(&rec),
        "--reference",
        "/reference/position",
        "--estimate",
        "/estimate/odom",
        "--plot",
        s(&figs),
        "-q",
    ]);
    let mut largest = 0;
    for name in FIGURES {
        let p = figs.join(format!("estimate_odom_{name}.svg"));
        let n = std::fs::metadata(&p).unwrap().len();
        println!("{name}: {n} bytes");
        largest = largest.max(n);
    }
    assert!(largest <= 2 * 1024 * 1024, "largest SVG {largest} bytes");
}

#[test]
fn png_figures_use_the_built_in_font() {
    let Some(shared) = common::shared() else {
        return;
    };
    let rec = common::mission(&shared, "lever_arm").join("mission.mcap");
    let dir = tempfile::tempdir().unwrap();
    run(&[
        "eval",
        s(&rec),
        "--reference",
        "/reference/position",
        "--estimate",
        "/estimate/odom",
        "--plot",
        s(dir.path()),
        "--plot-format",
        "png",
        "-q",
    ]);
    for name in FIGURES {
        let p = dir.path().join(format!("estimate_odom_{name}.png"));
        let bytes = std::fs::read(&p).unwrap();
        assert_eq!(&bytes[1..4], b"PNG", "{name}");
    }
}

#[test]
fn sweep_usage_errors_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    for values in ["1:0:1", "0.1,x", "0:1"] {
        let o = bin()
            .args([
                "sweep",
                "none.mcap",
                "--reference",
                "/r",
                "--estimate",
                "/e",
            ])
            .args([
                "--param",
                "eps-min",
                "--values",
                values,
                "--out",
                s(dir.path()),
            ])
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "--values {values}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.contains("--values") && err.lines().count() == 1,
            "{err}"
        );
    }
}

#[test]
fn batch_writes_mission_pages_and_a_summary_html() {
    let Some(shared) = common::shared() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in");
    std::fs::create_dir(&input).unwrap();
    for m in ["lever_arm", "straight"] {
        let src = common::mission(&shared, m).join("mission.mcap");
        std::os::unix::fs::symlink(src, input.join(format!("{m}.mcap"))).unwrap();
    }
    let out = dir.path().join("out");
    run(&[
        "batch",
        s(&input),
        "--reference",
        "/reference/position",
        "--estimate",
        "/estimate/odom",
        "--out",
        s(&out),
        "--plot",
        "--html",
        "--jobs",
        "1",
        "-q",
    ]);
    let summary = std::fs::read_to_string(out.join("summary.html")).unwrap();
    for m in ["lever_arm", "straight"] {
        assert!(
            summary.contains(&format!("href=\"{m}.html\"")),
            "{m} not linked"
        );
        let page = std::fs::read_to_string(out.join(format!("{m}.html"))).unwrap();
        assert_eq!(page.matches("<svg").count(), FIGURES.len(), "{m}.html");
        for name in FIGURES {
            let f = out.join(format!("{m}_figures/estimate_odom_{name}.svg"));
            assert!(f.is_file(), "{} missing", f.display());
        }
    }
    assert_eq!(
        summary.matches("<svg").count(),
        1,
        "the DE distribution inline"
    );
    let remote: Vec<String> = references(&summary)
        .into_iter()
        .filter(|r| r.to_ascii_lowercase().starts_with("http"))
        .collect();
    assert!(remote.is_empty(), "{remote:?}");
}
