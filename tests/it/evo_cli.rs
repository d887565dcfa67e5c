//! evo's command line beyond the metric, at the process boundary: every flag of evo 1.38.1's
//! evo_ape/evo_rpe parsers parses (`tests/data/evo-1.38.1-flags.tsv`, extracted from evo's own
//! parsers by `tests/python/extract_evo_flags.py`), result zips with evo's members, `res` with its
//! statistics over runs and paired comparison, `traj --full_check` finding what evo_traj finds,
//! conversions that round-trip, figures without a display, one-line errors on bad input.
//! (evo_res reading trajdrift's zips and `trajdrift res` printing evo_res's table are checked against
//! evo itself by `tests/python/check_evo_res.py` in `.ci/run`.)

use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

fn run_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_trajdrift"))
        .current_dir(dir)
        .args(args)
        .output()
        .expect("run trajdrift")
}

fn text(o: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// A 100 s figure-eight at 10 Hz with orientations, as TUM; the estimate with 2 cm of noise and a
/// small rotation, so that every relation and alignment has something to do.
fn write_tum_pair(dir: &Path) -> (PathBuf, PathBuf) {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let noise = Normal::new(0.0, 0.02).unwrap();
    let (mut r, mut e) = (String::new(), String::new());
    for i in 0..1000 {
        let t = i as f64 * 0.1;
        let (x, y, z) = (10.0 * (0.1 * t).sin(), 5.0 * (0.2 * t).sin(), 0.01 * t);
        let yaw: f64 = 0.1 * t;
        let (qz, qw) = ((yaw / 2.0).sin(), (yaw / 2.0).cos());
        r += &format!("{t:.3} {x:.6} {y:.6} {z:.6} 0 0 {qz:.9} {qw:.9}\n");
        let (ex, ey, ez) = (
            x + noise.sample(&mut rng) + 1.0,
            y + noise.sample(&mut rng),
            z + noise.sample(&mut rng),
        );
        e += &format!("{t:.3} {ex:.6} {ey:.6} {ez:.6} 0 0 {qz:.9} {qw:.9}\n");
    }
    let (rp, ep) = (dir.join("ref.tum"), dir.join("est.tum"));
    std::fs::write(&rp, r).unwrap();
    std::fs::write(&ep, e).unwrap();
    (rp, ep)
}

/// The rows of the committed flag list: (tool, form, option, number of values, example).
fn evo_flags() -> Vec<(String, String, String, usize, String)> {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/evo-1.38.1-flags.tsv");
    std::fs::read_to_string(&p)
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .map(|l| {
            let c: Vec<&str> = l.split('\t').collect();
            let option = c[2].split(',').next_back().unwrap().to_string();
            (
                c[0].into(),
                c[1].into(),
                option,
                c[3].parse().unwrap(),
                c[4].into(),
            )
        })
        .collect()
}

#[test]
fn every_flag_of_evo_ape_and_rpe_parses_and_runs() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (r, e) = write_tum_pair(d);
    // KITTI rows of the same poses (evo's `kitti` form), and a EuRoC ground truth.
    let tum_rows = |p: &Path| -> Vec<Vec<f64>> {
        std::fs::read_to_string(p)
            .unwrap()
            .lines()
            .map(|l| l.split(' ').map(|v| v.parse().unwrap()).collect())
            .collect()
    };
    let kitti = |rows: &[Vec<f64>]| -> String {
        rows.iter()
            .map(|v| {
                let (qz, qw) = (v[6], v[7]);
                let (c, s) = (1.0 - 2.0 * qz * qz, 2.0 * qz * qw);
                format!("{c} {} 0 {} {s} {c} 0 {} 0 0 1 {}\n", -s, v[1], v[2], v[3])
            })
            .collect()
    };
    std::fs::write(d.join("ref.kitti"), kitti(&tum_rows(&r))).unwrap();
    std::fs::write(d.join("est.kitti"), kitti(&tum_rows(&e))).unwrap();
    let mut euroc = String::from("#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z []\n");
    for v in tum_rows(&r) {
        euroc += &format!(
            "{},{},{},{},{},0,0,{}\n",
            (v[0] * 1e9).round() as i64,
            v[1],
            v[2],
            v[3],
            v[7],
            v[6]
        );
    }
    std::fs::write(d.join("gt.csv"), euroc).unwrap();
    std::fs::write(d.join("cfg.json"), "{}").unwrap();
    let mcap = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/sim_ground/mission.mcap");
    let mcap = mcap.to_str().unwrap();
    let flags = evo_flags();
    let (mut checked, mut failures) = (0, Vec::new());
    for (tool, form, option, n, example) in &flags {
        if tool != "ape" && tool != "rpe" {
            continue;
        }
        let mut args: Vec<String> = vec![tool.clone(), form.clone()];
        match form.as_str() {
            "tum" => args.extend(["ref.tum".into(), "est.tum".into()]),
            "kitti" => args.extend(["ref.kitti".into(), "est.kitti".into()]),
            "euroc" => args.extend(["gt.csv".into(), "est.tum".into()]),
            // The recording forms: the fixture's odometry against itself (it has orientations).
            _ => args.extend([
                mcap.into(),
                "/estimate/odom".into(),
                "/estimate/odom".into(),
            ]),
        }
        args.push(option.clone());
        let value = match option.as_str() {
            "--save_results" => d.join(format!("{tool}_{form}.zip")).display().to_string(),
            "--save_plot" => d.join(format!("{tool}_{form}.svg")).display().to_string(),
            "--logfile" => d.join(format!("{tool}_{form}.log")).display().to_string(),
            "--config" => "cfg.json".into(),
            // evo errors on a length → angle conversion too: a length unit for the default relation.
            "--change_unit" => "cm".into(),
            "--t_end" => "1e12".into(),
            // With the default unit (frames) evo refuses a fractional delta too.
            "--delta" => "2".into(),
            "--n_to_align" | "--downsample" => "100".into(),
            _ => example.clone(),
        };
        for _ in 0..*n {
            args.push(value.clone());
        }
        let refs: Vec<&str> = args.iter().map(String::as_str).collect();
        let o = run_in(d, &refs);
        let (_, err) = text(&o);
        checked += 1;
        // evo refuses to motion-filter KITTI paths (pairs by index) with an error too (exit 1).
        let allowed = if form == "kitti" && option == "--motion_filter" {
            1
        } else {
            0
        };
        if !matches!(o.status.code(), Some(c) if c == 0 || c == 3 || c == allowed)
            || err.contains("unexpected argument")
        {
            failures.push(format!(
                "{}: exit {:?}: {}",
                args.join(" "),
                o.status.code(),
                err.trim()
            ));
        }
    }
    println!("{checked} evo_ape/evo_rpe flag × form cases run");
    assert!(checked >= 190, "only {checked} cases in the flag list");
    assert!(
        failures.is_empty(),
        "{} failures:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

#[test]
fn every_flag_of_evo_res_and_evo_traj_parses() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_tum_pair(d);
    std::fs::write(d.join("cfg.json"), "{}").unwrap();
    std::fs::write(
        d.join("t.json"),
        r#"{"x": 1, "y": 0, "z": 0, "qx": 0, "qy": 0, "qz": 0, "qw": 1}"#,
    )
    .unwrap();
    let o = run_in(
        d,
        &[
            "ape",
            "tum",
            "ref.tum",
            "est.tum",
            "--save_results",
            "a.zip",
            "--silent",
        ],
    );
    assert_eq!(o.status.code(), Some(0));
    // The cases run one folder down, so that --save_as_tum writes beside, not over, the inputs.
    let w = d.join("w");
    std::fs::create_dir(&w).unwrap();
    let mcap = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/sim_ground/mission.mcap");
    let mcap = mcap.to_str().unwrap();
    let (mut checked, mut failures) = (0, Vec::new());
    for (k, (tool, form, option, n, example)) in evo_flags().iter().enumerate() {
        let mut args: Vec<String> = match (tool.as_str(), form.as_str()) {
            ("res", _) => vec!["res".into(), "../a.zip".into()],
            ("traj", "bag" | "bag2" | "mcap") => {
                vec![
                    "traj".into(),
                    form.clone(),
                    mcap.into(),
                    "/estimate/odom".into(),
                ]
            }
            ("traj", _) => vec!["traj".into(), "tum".into(), "../est.tum".into()],
            _ => continue,
        };
        args.push(option.clone());
        let out = |ext: &str| d.join(format!("out{k}.{ext}")).display().to_string();
        let value = match option.as_str() {
            "--ref" if ["bag", "bag2", "mcap"].contains(&form.as_str()) => "/estimate/odom".into(),
            "--ref" => "../ref.tum".into(),
            "--transform_left" | "--transform_right" => "../t.json".into(),
            "--save_plot" => out("svg"),
            "--save_table" => out("csv"),
            "--logfile" => out("log"),
            "--config" => "../cfg.json".into(),
            "--n_to_align" => "100".into(),
            _ => example.clone(),
        };
        for _ in 0..*n {
            args.push(value.clone());
        }
        // Alignment and sync need the reference, as in evo.
        if [
            "-a",
            "--align",
            "-s",
            "--correct_scale",
            "--align_origin",
            "--sync",
            "--n_to_align",
        ]
        .contains(&option.as_str())
        {
            args.push("--ref".into());
            args.push(if args[1] == "tum" {
                "../ref.tum".into()
            } else {
                "/estimate/odom".into()
            });
        }
        let refs: Vec<&str> = args.iter().map(String::as_str).collect();
        let o = run_in(&w, &refs);
        let (_, err) = text(&o);
        checked += 1;
        if !matches!(o.status.code(), Some(0 | 3)) || err.contains("unexpected argument") {
            failures.push(format!(
                "{}: exit {:?}: {}",
                args.join(" "),
                o.status.code(),
                err.trim()
            ));
        }
    }
    println!("{checked} evo_res/evo_traj flag × form cases run");
    assert!(checked >= 200, "only {checked} cases");
    assert!(
        failures.is_empty(),
        "{} failures:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

#[test]
fn flags_without_meaning_are_named_once_and_config_json_wins() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_tum_pair(d);
    let o = run_in(
        d,
        &[
            "ape",
            "tum",
            "ref.tum",
            "est.tum",
            "--rerun",
            "--map_tile",
            "EPSG:3857",
        ],
    );
    let (_, err) = text(&o);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert_eq!(err.matches("--rerun").count(), 1, "{err}");
    assert_eq!(err.matches("--map_tile").count(), 1, "{err}");
    // evo's argument JSON wins over the command line: -a given, the file says align false, Sim(3) off.
    std::fs::write(
        d.join("c.json"),
        r#"{"align": false, "correct_scale": true, "t_max_diff": 0.02, "plot_statistics": ["rmse"]}"#,
    )
    .unwrap();
    let o = run_in(
        d,
        &["ape", "tum", "ref.tum", "est.tum", "-a", "-c", "c.json"],
    );
    let (out, err) = text(&o);
    assert!(out.contains("(scale corrected)"), "{out}");
    assert!(err.contains("plot_statistics"), "{err}");
    // --silent prints no result; --logfile holds it; -v details on stderr.
    let o = run_in(
        d,
        &[
            "ape",
            "tum",
            "ref.tum",
            "est.tum",
            "--silent",
            "--logfile",
            "log.txt",
            "-v",
        ],
    );
    let (out, err) = text(&o);
    assert!(out.is_empty(), "{out}");
    assert!(err.contains("poses"), "{err}");
    let log = std::fs::read_to_string(d.join("log.txt")).unwrap();
    assert!(log.contains("rmse"), "{log}");
}

#[test]
fn result_zip_has_evos_members_and_figures_need_no_display() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_tum_pair(d);
    for (tool, extra) in [("ape", &[][..]), ("rpe", &["-d", "5", "-u", "m"][..])] {
        let mut args = vec![
            tool,
            "tum",
            "ref.tum",
            "est.tum",
            "-a",
            "--save_results",
            "r.zip",
            "-p",
        ];
        args.extend(extra);
        let o = run_in(d, &args);
        let (_, err) = text(&o);
        assert_eq!(o.status.code(), Some(0), "{err}");
        assert!(
            err.contains("figures written: r_raw.svg, r_map.svg, r_stats.svg"),
            "{err}"
        );
        let r = trajdrift::report::evo_zip::EvoResult::read(&d.join("r.zip")).unwrap();
        let names: Vec<&str> = r.arrays.iter().map(|a| a.0.as_str()).collect();
        assert_eq!(
            names,
            [
                "error_array",
                "seconds_from_start",
                "timestamps",
                "distances_from_start",
                "distances",
                "alignment_transformation_sim3"
            ]
        );
        let info: Vec<&str> = r.info.iter().map(|a| a.0.as_str()).collect();
        assert_eq!(info, ["title", "ref_name", "est_name", "label"]);
        let stats: Vec<&str> = r.stats.iter().map(|a| a.0.as_str()).collect();
        assert_eq!(
            stats,
            ["rmse", "mean", "median", "std", "min", "max", "sse"]
        );
        let n = r.array("error_array").unwrap().data.len();
        assert!(r.arrays.iter().take(5).all(|a| a.1.data.len() == n));
    }
    // --save_plot x.svg / x.png: no display needed (none is set in this test's environment either).
    for ext in ["svg", "png"] {
        let o = Command::new(env!("CARGO_BIN_EXE_trajdrift"))
            .current_dir(d)
            .env_remove("DISPLAY")
            .env_remove("WAYLAND_DISPLAY")
            .args([
                "ape",
                "tum",
                "ref.tum",
                "est.tum",
                "-a",
                "--plot_mode",
                "xy",
                "--save_plot",
            ])
            .arg(format!("x.{ext}"))
            .output()
            .unwrap();
        assert_eq!(
            o.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
        for f in ["raw", "map", "stats"] {
            let p = d.join(format!("x_{f}.{ext}"));
            assert!(
                std::fs::metadata(&p).unwrap().len() > 5000,
                "{}",
                p.display()
            );
        }
    }
    let png = png::Decoder::new(std::fs::File::open(d.join("x_map.png")).unwrap());
    let mut reader = png.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    let ink = buf[..info.buffer_size()]
        .chunks(info.color_type.samples())
        .filter(|p| p[..3].iter().any(|&c| c < 200))
        .count();
    assert!(ink > 2000, "the PNG map is blank ({ink} dark pixels)");
    // PDF: no backend; SVG written instead and said so, exit 3.
    let o = run_in(
        d,
        &["ape", "tum", "ref.tum", "est.tum", "--save_plot", "y.pdf"],
    );
    let (_, err) = text(&o);
    assert_eq!(o.status.code(), Some(3), "{err}");
    assert!(
        err.contains("no PDF backend") && d.join("y_map.svg").is_file(),
        "{err}"
    );
    // The SVG renders in headless Chromium to a page with ink.
    if let Some(chrome) = chromium() {
        let shot = d.join("shot.png");
        let o = Command::new(chrome)
            .args([
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                "--hide-scrollbars",
            ])
            .arg(format!("--user-data-dir={}", d.join("profile").display()))
            .arg("--window-size=960,560")
            .arg(format!("--screenshot={}", shot.display()))
            .arg(format!("file://{}", d.join("x_map.svg").display()))
            .output()
            .unwrap();
        assert!(shot.is_file(), "{}", String::from_utf8_lossy(&o.stderr));
        let dec = png::Decoder::new(std::fs::File::open(&shot).unwrap());
        let mut reader = dec.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size()];
        let info = reader.next_frame(&mut buf).unwrap();
        let px = info.color_type.samples();
        let ink = buf[..info.buffer_size()]
            .chunks(px)
            .filter(|p| p[..3].iter().any(|&c| c < 200))
            .count();
        println!("SVG in Chromium: {ink} dark pixels");
        assert!(ink > 2000, "the SVG rendered blank in Chromium");
    }
}

/// Debian's `chromium-headless-shell` (`.ci/run` installs it); CI must have it.
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
        panic!("chromium-headless-shell missing: .ci/run installs it");
    }
    eprintln!("skipped: chromium-headless-shell not installed");
    None
}

/// Runs of three estimators on each shared mission's reference: A and B with the same noise
/// (different seeds), C with 10 % larger errors. 10 runs each.
fn write_runs(shared: &Path, out: &Path) {
    for (m, mission) in common::MISSIONS.iter().enumerate() {
        let reference = common::mission(shared, mission).join("reference.tum");
        let rows: Vec<Vec<f64>> = std::fs::read_to_string(&reference)
            .unwrap()
            .lines()
            .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
            .map(|l| l.split_whitespace().map(|v| v.parse().unwrap()).collect())
            .collect();
        for (est, scale) in [("A", 1.0), ("B", 1.0), ("C", 1.1)] {
            for run in 0..10u64 {
                let seed = 1000 * m as u64 + 100 * (est.as_bytes()[0] as u64) + run;
                let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
                let n = Normal::new(0.0, 0.05 * scale).unwrap();
                let text: String = rows
                    .iter()
                    .map(|v| {
                        format!(
                            "{:.9} {:.6} {:.6} {:.6} 0 0 0 1\n",
                            v[0],
                            v[1] + n.sample(&mut rng),
                            v[2] + n.sample(&mut rng),
                            v[3] + n.sample(&mut rng)
                        )
                    })
                    .collect();
                let est_file = out.join(format!("{mission}_{est}_{run}.tum"));
                std::fs::write(&est_file, text).unwrap();
                let zip = out.join(format!("{est}_{mission}_{run:02}.zip"));
                let o = run_in(
                    out,
                    &[
                        "ape",
                        "tum",
                        reference.to_str().unwrap(),
                        est_file.to_str().unwrap(),
                        "--save_results",
                        zip.to_str().unwrap(),
                        "--silent",
                    ],
                );
                assert_eq!(o.status.code(), Some(0), "{}", text_err(&o));
            }
        }
    }
}

fn text_err(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The zips whose file name starts with `est_` (written as `EST_MISSION_RUN.zip`).
fn zips(dir: &Path, est: &str) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| {
            p.extension().is_some_and(|x| x == "zip")
                && p.file_name()
                    .unwrap()
                    .to_string_lossy()
                    .starts_with(&format!("{est}_"))
        })
        .collect();
    v.sort();
    v
}

#[test]
fn res_runs_give_intervals_and_the_comparison_needs_more_than_scatter() {
    let Some(shared) = common::shared() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_runs(&shared, d);
    // Per estimator a folder of EST_RUN.zip (the mission is in each zip's ref_name).
    for est in ["A", "B", "C"] {
        for z in zips(d, est) {
            let name = z.file_name().unwrap().to_string_lossy().into_owned();
            // A_lever_arm_03.zip → runs/A_lever_arm_03.zip is grouped as "A_lever_arm"; for the
            // comparison the estimator must be "A": copy as A_<mission index><run>.zip.
            let parts: Vec<&str> = name.trim_end_matches(".zip").rsplitn(2, '_').collect();
            let mission = common::MISSIONS
                .iter()
                .position(|m| parts[1].ends_with(m))
                .unwrap();
            std::fs::create_dir_all(d.join("cmp")).unwrap();
            std::fs::copy(
                &z,
                d.join("cmp")
                    .join(format!("{est}_{mission}{}.zip", parts[0])),
            )
            .unwrap();
        }
    }
    // 10 runs of one estimator on one mission: mean ± 95 % interval of each statistic.
    let a_lever: Vec<String> = zips(d, "A_lever_arm")
        .iter()
        .map(|p| p.display().to_string())
        .collect();
    assert_eq!(a_lever.len(), 10);
    let mut args: Vec<&str> = vec!["res", "--runs"];
    args.extend(a_lever.iter().map(String::as_str));
    args.push("--use_filenames");
    let o = run_in(d, &args);
    let (out, err) = text(&o);
    assert_eq!(o.status.code(), Some(0), "{err}");
    println!("{out}");
    let row = out
        .lines()
        .find(|l| l.starts_with("A_lever_arm"))
        .unwrap_or_else(|| panic!("no runs row: {out}"));
    assert!(
        row.contains(" 10 ") && row.matches('±').count() == 6,
        "{row}"
    );
    // Paired comparisons over the five missions.
    let cmp = d.join("cmp");
    let all: Vec<String> = std::fs::read_dir(&cmp)
        .unwrap()
        .flatten()
        .map(|e| e.path().display().to_string())
        .collect();
    let compare = |a: &str, b: &str| {
        let mut args: Vec<&str> = vec!["res", "--use_filenames", "--compare", a, b];
        args.extend(all.iter().map(String::as_str));
        let o = run_in(&cmp, &args);
        let (out, err) = text(&o);
        assert_eq!(o.status.code(), Some(0), "{err}");
        println!("{}", &out[out.find("paired comparison").unwrap()..]);
        out
    };
    let same = compare("A", "B");
    assert!(
        same.contains("lever_arm/reference.tum"),
        "missions not told apart: {same}"
    );
    assert!(same.contains("no difference"), "{same}");
    assert!(same.contains("paired over 5 missions"), "{same}");
    let worse = compare("A", "C");
    assert!(worse.contains("better: A"), "{worse}");
    let better = compare("C", "A");
    assert!(better.contains("better: A"), "{better}");
}

#[test]
fn traj_full_check_finds_what_evo_traj_finds() {
    let Some(shared) = common::shared() else {
        return;
    };
    let evo = shared.join("evo-data");
    // (form, file, quaternions ok, timestamps ok) as evo_traj 1.38.1 --full_check reports them.
    let cases = [
        ("tum", "fr2_desk_groundtruth.txt", false, false),
        ("tum", "fr2_desk_ORB.txt", true, true),
        ("tum", "freiburg1_xyz-groundtruth.txt", false, true),
        ("tum", "freiburg1_xyz-rgbdslam.txt", true, true),
        ("tum", "V102.txt", true, false),
        ("euroc", "V102_groundtruth.csv", false, true),
        ("kitti", "KITTI_00_ORB.txt", true, true),
    ];
    for (form, file, quats, stamps) in cases {
        let o = run_in(&evo, &["traj", form, file, "--full_check"]);
        let (out, err) = text(&o);
        let valid = quats && stamps;
        assert_eq!(
            o.status.code(),
            Some(if valid { 0 } else { 3 }),
            "{file}: {err}"
        );
        let line = |k: &str| {
            out.lines()
                .find(|l| l.trim_start().starts_with(k))
                .unwrap_or_else(|| panic!("{file}: no {k}: {out}"))
                .to_string()
        };
        assert_eq!(
            line("quaternions").contains("invalid"),
            !quats,
            "{file}: {out}"
        );
        if form != "kitti" {
            assert_eq!(
                line("timestamps").contains("wrong"),
                !stamps,
                "{file}: {out}"
            );
        }
        assert!(line("SE(3) conform").contains("yes"), "{file}");
    }
    // V102.txt: evo's "not ascending or duplicates" is 4 repeated stamps.
    let o = run_in(&evo, &["traj", "tum", "V102.txt", "-f"]);
    assert!(text(&o).0.contains("4 duplicate"), "{}", text(&o).0);
}

#[test]
fn traj_conversions_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_tum_pair(d);
    std::fs::create_dir(d.join("out")).unwrap();
    let out = d.join("out");
    let o = run_in(
        &out,
        &[
            "traj",
            "../est.tum",
            "--save_as_tum",
            "--save_as_kitti",
            "--save_as_mcap",
            "est.mcap",
        ],
    );
    assert_eq!(o.status.code(), Some(0), "{}", text_err(&o));
    let read = |p: &Path| trajdrift::sources::tum::read_tum(p).unwrap();
    let orig = read(&d.join("est.tum"));
    let tum = read(&out.join("est.tum"));
    assert_eq!(orig.stamps_ns, tum.stamps_ns);
    let close = |a: &trajdrift::Trajectory, b: &trajdrift::Trajectory, tol: f64| {
        a.positions
            .iter()
            .zip(&b.positions)
            .all(|(x, y)| (x - y).norm() <= tol)
            && a.orientations
                .as_ref()
                .unwrap()
                .iter()
                .zip(b.orientations.as_ref().unwrap())
                .all(|(p, q)| p.angle_to(q) <= 1e-8)
    };
    assert!(close(&orig, &tum, 0.0), "TUM round trip");
    let kitti = trajdrift::sources::kitti::read_kitti(&out.join("est.kitti"), None).unwrap();
    assert_eq!(kitti.len(), orig.len());
    assert!(kitti
        .positions
        .iter()
        .zip(&orig.positions)
        .all(|(x, y)| (x - y).norm() < 1e-12));
    // MCAP back to TUM through the recording form.
    std::fs::create_dir(out.join("back")).unwrap();
    let o = run_in(
        &out.join("back"),
        &["traj", "mcap", "../est.mcap", "/est", "--save_as_tum"],
    );
    assert_eq!(o.status.code(), Some(0), "{}", text_err(&o));
    let back = read(&out.join("back/est.tum"));
    assert_eq!(back.stamps_ns, orig.stamps_ns);
    assert!(close(&orig, &back, 0.0), "MCAP round trip");
    // The output guard: converting a TUM file onto itself is refused (exit 2), the file intact.
    let before = std::fs::read(d.join("est.tum")).unwrap();
    let o = run_in(d, &["traj", "est.tum", "--save_as_tum"]);
    assert_eq!(o.status.code(), Some(2), "{}", text_err(&o));
    assert_eq!(std::fs::read(d.join("est.tum")).unwrap(), before);
}

#[test]
fn traj_aligns_onto_the_reference() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_tum_pair(d);
    std::fs::create_dir(d.join("out")).unwrap();
    let o = run_in(
        &d.join("out"),
        &[
            "traj",
            "../est.tum",
            "--ref",
            "../ref.tum",
            "-a",
            "--save_as_tum",
            "-p",
            "--save_plot",
            "t.png",
            "--plot_mode",
            "xy",
        ],
    );
    assert_eq!(o.status.code(), Some(0), "{}", text_err(&o));
    let r = trajdrift::sources::tum::read_tum(&d.join("ref.tum")).unwrap();
    let e = trajdrift::sources::tum::read_tum(&d.join("out/est.tum")).unwrap();
    // The estimate was offset by 1 m in x: after the alignment it lies on the reference (noise 2 cm).
    let rms = (e
        .positions
        .iter()
        .zip(&r.positions)
        .map(|(a, b)| (a - b).norm_squared())
        .sum::<f64>()
        / r.len() as f64)
        .sqrt();
    assert!(rms < 0.05, "{rms}");
    assert!(d.join("out/t_trajectories.png").is_file() && d.join("out/t_xyz.png").is_file());
}

#[test]
fn bad_input_is_one_line_error_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_tum_pair(d);
    std::fs::write(d.join("bad.zip"), b"PK\x03\x04 not really").unwrap();
    let mut truncated = {
        let o = run_in(
            d,
            &[
                "ape",
                "tum",
                "ref.tum",
                "est.tum",
                "--save_results",
                "ok.zip",
                "--silent",
            ],
        );
        assert_eq!(o.status.code(), Some(0));
        std::fs::read(d.join("ok.zip")).unwrap()
    };
    truncated.truncate(truncated.len() / 2);
    std::fs::write(d.join("cut.zip"), &truncated).unwrap();
    for (args, exit, name) in [
        (vec!["res", "bad.zip"], 1, "bad.zip"),
        (vec!["res", "cut.zip"], 1, "cut.zip"),
        (vec!["res", "missing.zip"], 1, "missing.zip"),
        (vec!["res", "ref.tum"], 1, "ref.tum"),
        (vec!["traj", "missing.tum"], 1, "missing.tum"),
        (
            vec![
                "ape",
                "tum",
                "ref.tum",
                "est.tum",
                "--save_results",
                "ref.tum",
            ],
            2,
            "ref.tum",
        ),
        (
            vec!["ape", "tum", "ref.tum", "est.tum", "-c", "missing.json"],
            1,
            "missing.json",
        ),
        (
            vec!["ape", "tum", "ref.tum", "est.tum", "--change_unit", "deg"],
            2,
            "--change_unit",
        ),
        (vec!["res", "ok.zip", "--compare", "X", "Y"], 2, "--compare"),
    ] {
        let o = run_in(d, &args);
        let (_, err) = text(&o);
        assert_eq!(o.status.code(), Some(exit), "{args:?}: {err}");
        let lines: Vec<&str> = err.lines().filter(|l| l.starts_with("error")).collect();
        assert_eq!(lines.len(), 1, "{args:?}: {err}");
        assert!(
            lines[0].contains(name) && !err.contains("panicked"),
            "{args:?}: {err}"
        );
    }
}
