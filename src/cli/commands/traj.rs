//! `trajdrift traj`: evo_traj's information, checks, conversions, alignment and figures
//! (`trajdrift::evo::traj`).

use std::path::{Path, PathBuf};

use anyhow::Result;

use trajdrift::clock::ClockCorrection;
use trajdrift::eval::config::{EvalConfig, NamedInput};
use trajdrift::evo::traj::{
    align_to, check, figures, full_check_text, info_table, invert, load_text, load_topics,
    load_transform, merge, motion_filter, save, save_mcap, shift, topic_name, transform,
    AlignOptions, SaveAs, TrajInput,
};
use trajdrift::metrics::standard::filters::downsample_ids;
use trajdrift::output::OutputGuard;
use trajdrift::plot::evo::PlotMode;
use trajdrift::report::json::TimeOffsetStatus;
use trajdrift::sources::text::TextFormat;
use trajdrift::sources::Warning;
use trajdrift::trajectory::Trajectory;

use crate::cli::evo_args::{ignored_notes, TrajArgs};
use crate::cli::evo_log::EvoLog;
use crate::cli::{EXIT_OK, EXIT_WARNING};

/// The trajectories of the command line: (trajectories, reference), and what reading them warns of
/// (a recording cut short).
type Read = (Vec<TrajInput>, Option<TrajInput>, Vec<Warning>);

/// The trajectories of the command line.
fn read(a: &TrajArgs) -> Result<Read> {
    let form = a.inputs.first().map(String::as_str);
    let text_form = match form {
        Some("tum") => Some(Some(TextFormat::Tum)),
        Some("kitti") => Some(Some(TextFormat::Kitti)),
        Some("euroc") => Some(Some(TextFormat::Euroc)),
        _ => None,
    };
    if let Some("bag" | "bag2" | "mcap") = form {
        let [_, recording, topics @ ..] = a.inputs.as_slice() else {
            return Err(trajdrift::Error::InvalidArgument(format!(
                "{}: give the recording and one or more topics: {} RECORDING TOPIC...",
                form.unwrap_or(""),
                form.unwrap_or("")
            ))
            .into());
        };
        let mut all: Vec<String> = topics.to_vec();
        if let Some(r) = &a.reference {
            all.insert(0, r.clone());
        }
        let (mut loaded, warnings) = load_topics(Path::new(recording), &all)?;
        let reference = a.reference.as_ref().map(|_| loaded.remove(0));
        return Ok((loaded, reference, warnings));
    }
    let (files, format) = match text_form {
        Some(f) => (&a.inputs[1..], f),
        None => (&a.inputs[..], None),
    };
    if files.is_empty() {
        return Err(trajdrift::Error::InvalidArgument(
            "give one or more trajectory files (trajdrift traj [tum|kitti|euroc] FILE... or bag|bag2|mcap RECORDING TOPIC...)".into(),
        )
        .into());
    }
    let mut ts = files
        .iter()
        .map(|f| load_text(Path::new(f), format))
        .collect::<trajdrift::Result<Vec<_>>>()?;
    let mut reference = a
        .reference
        .as_ref()
        .map(|r| load_text(Path::new(r), format))
        .transpose()?;
    if a.show_full_names {
        for t in ts.iter_mut().chain(reference.iter_mut()) {
            t.name = t.path.display().to_string();
        }
    }
    Ok((ts, reference, Vec::new()))
}

/// `--time-offset auto`: eval's offset search between the reference and `t`.
fn auto_offset(
    a: &TrajArgs,
    reference: &TrajInput,
    t: &TrajInput,
    log: &EvoLog,
) -> Result<(ClockCorrection, bool)> {
    let form = a.inputs.first().map(String::as_str);
    let config = match form {
        Some("bag" | "bag2" | "mcap") => EvalConfig::new(
            Some(reference.path.clone()),
            NamedInput::topic(&reference.name),
            vec![NamedInput::topic(&t.name)],
        ),
        _ => EvalConfig::new(
            None,
            NamedInput::file(&reference.path.to_string_lossy()),
            vec![NamedInput::file(&t.path.to_string_lossy())],
        ),
    };
    let report = trajdrift::eval::evaluate(&config, &|_| {})?;
    let o = &report.estimates[0].time_offset;
    let correction = ClockCorrection::from_report(o);
    log.note(&format!(
        "{}: time offset (auto) {:+.4} s found by {} ({}), {}",
        t.name,
        o.offset_s,
        o.method,
        o.status,
        match o.model.filter(|_| !correction.is_constant()) {
            Some(m) => format!("clock model {} applied", m.as_str()),
            None => format!("{:+.4} s applied", o.applied_s),
        }
    ));
    let weak = !matches!(o.status, TimeOffsetStatus::Ok | TimeOffsetStatus::Given);
    Ok((correction, weak))
}

/// Runs the command; returns the exit code. A pipeline, one stage per function, each a no-op unless
/// its flags are given: read, resample, merge, shift the clocks, align, transform, project; then the
/// reports (information and checks, the table, the conversions, the figures) of what it made.
pub fn run(a: TrajArgs) -> Result<u8> {
    let log = EvoLog::new(&a.usability, &a);
    warn_ignored(&a, &log);
    super::metric::check_motion_filter(a.motion_filter.as_deref())?;
    let mut inputs: Vec<PathBuf> = a.inputs.iter().map(PathBuf::from).collect();
    inputs.extend(a.reference.iter().map(PathBuf::from));
    inputs.extend(a.transform_left.iter().map(PathBuf::from));
    inputs.extend(a.transform_right.iter().map(PathBuf::from));
    inputs.extend(a.usability.config.iter().cloned());
    let mut guard = OutputGuard::new(&inputs);
    for (flag, out) in [
        ("--logfile", a.usability.logfile.as_deref()),
        ("--save_table", a.save_table.as_deref()),
    ] {
        if let Some(out) = out {
            guard.claim(flag, out)?;
        }
    }
    let (mut ts, reference, warnings) = read(&a)?;
    for w in &warnings {
        log.warn(&crate::cli::warning_line(w));
    }
    let mut code = crate::cli::exit_code(&warnings);
    resample(&a, &mut ts, &log)?;
    if a.merge {
        if ts.iter().any(|t| !t.stamped) {
            return Err(trajdrift::Error::InvalidArgument(
                "--merge: can't merge KITTI files (no stamps)".into(),
            )
            .into());
        }
        ts = vec![merge(ts)];
    }
    if shift_clocks(&a, &mut ts, reference.as_ref(), &log)? {
        code = EXIT_WARNING;
    }
    align_all(&a, &mut ts, reference.as_ref(), &log)?;
    transform_all(&a, &mut ts, &log)?;
    project(&a, &mut ts);
    let all: Vec<&TrajInput> = ts.iter().chain(reference.iter()).collect();
    claim_conversions(&a, &all, &mut guard)?;
    code = code.max(report_info(&a, &all, &log)?);
    if let Some(path) = &a.save_table {
        guard.write("--save_table", path, info_csv(&all).as_bytes())?;
    }
    save_conversions(&a, &all, &guard, &log)?;
    if (a.plot || a.save_plot.is_some()) && write_plots(&a, &ts, reference.as_ref(), &guard, &log)?
    {
        code = code.max(EXIT_WARNING);
    }
    log.finish(&guard)?;
    Ok(code)
}

/// Warns of each evo flag given that has no effect here (viewers, map layers, topic discovery).
fn warn_ignored(a: &TrajArgs, log: &EvoLog) {
    let all_topics = [(
        "--all_topics",
        a.all_topics,
        "name the topics; `trajdrift topics RECORDING` lists them",
    )];
    for note in ignored_notes(&[&a.viewer.given()[..], &a.map_layers.given(), &all_topics].concat())
    {
        log.warn(&note);
    }
}

/// `--downsample N` then `--motion_filter D A` on every trajectory (not the reference).
fn resample(a: &TrajArgs, ts: &mut [TrajInput], log: &EvoLog) -> Result<()> {
    if let Some(n) = a.downsample {
        for t in ts.iter_mut() {
            let ids = downsample_ids(t.trajectory.len(), n);
            let tr = &t.trajectory;
            t.trajectory = Trajectory {
                stamps_ns: ids.iter().map(|&i| tr.stamps_ns[i as usize]).collect(),
                positions: ids.iter().map(|&i| tr.positions[i as usize]).collect(),
                orientations: tr
                    .orientations
                    .as_ref()
                    .map(|o| ids.iter().map(|&i| o[i as usize]).collect()),
            };
        }
    }
    if let Some(m) = &a.motion_filter {
        for t in ts.iter_mut() {
            motion_filter(t, m[0], m[1])?;
            log.detail(&format!(
                "{}: motion filter kept {} poses",
                t.name,
                t.trajectory.len()
            ));
        }
    }
    Ok(())
}

/// Time offsets: `--t_offset S` for every trajectory, `--time-offset S`, or `--time-offset auto`,
/// each found against the reference ([`auto_offset`]) and applied as its clock correction. Returns
/// true when an automatic offset was not confident (then none was applied: a warning).
fn shift_clocks(
    a: &TrajArgs,
    ts: &mut [TrajInput],
    reference: Option<&TrajInput>,
    log: &EvoLog,
) -> Result<bool> {
    let mut weak_any = false;
    for t in ts.iter_mut() {
        let offset = match (a.t_offset, a.time_offset.as_deref(), reference) {
            (Some(s), _, _) => s,
            (None, Some("auto"), Some(r)) => {
                let (correction, weak) = auto_offset(a, r, t, log)?;
                if weak {
                    log.warn(&format!("warning [weak_time_offset]: {}: the automatic time offset is not confident; none was applied", t.name));
                    weak_any = true;
                }
                t.trajectory = correction.apply(&t.trajectory);
                0.0
            }
            (None, Some("auto"), None) => {
                return Err(trajdrift::Error::InvalidArgument(
                    "--time-offset auto needs a reference: --ref REF".into(),
                )
                .into())
            }
            (None, Some(s), _) => s.parse::<f64>().map_err(|_| {
                trajdrift::Error::InvalidArgument(format!(
                    "--time-offset {s}: expected seconds or `auto`"
                ))
            })?,
            (None, None, _) => 0.0,
        };
        if offset != 0.0 {
            shift(&mut t.trajectory, offset);
            log.detail(&format!("{}: stamps shifted by {offset:+} s", t.name));
        }
    }
    Ok(weak_any)
}

/// `-a`, `-s`, `--align_origin`, `--sync`: every trajectory aligned onto the reference (which they
/// need).
fn align_all(
    a: &TrajArgs,
    ts: &mut [TrajInput],
    reference: Option<&TrajInput>,
    log: &EvoLog,
) -> Result<()> {
    if !(a.align || a.correct_scale || a.align_origin || a.sync) {
        return Ok(());
    }
    let options = AlignOptions {
        align: a.align,
        correct_scale: a.correct_scale,
        align_origin: a.align_origin,
        n_to_align: a.n_to_align.and_then(|n| usize::try_from(n).ok()),
        t_max_diff_s: a.t_max_diff,
        sync: a.sync,
        interpolate: a.sync_method == "interpolation",
    };
    let Some(r) = reference else {
        return Err(trajdrift::Error::InvalidArgument(
            "-a, -s, --align_origin and --sync need a reference: --ref REF".into(),
        )
        .into());
    };
    for t in ts.iter_mut() {
        let (aligned, sim) = align_to(r, t, &options)?;
        log.detail(&format!(
            "{}: aligned onto {}: rotation {:?}, translation {:?}, scale {}",
            t.name, r.name, sim.rotation, sim.translation, sim.scale
        ));
        t.trajectory = aligned;
    }
    Ok(())
}

/// `--transform_left FILE` (else `--transform_right FILE`), inverted with `--invert_transform`,
/// applied to every trajectory.
fn transform_all(a: &TrajArgs, ts: &mut [TrajInput], log: &EvoLog) -> Result<()> {
    let Some((file, right)) = a
        .transform_left
        .as_ref()
        .map(|f| (f, false))
        .or(a.transform_right.as_ref().map(|f| (f, true)))
    else {
        return Ok(());
    };
    let mut t = load_transform(Path::new(file))?;
    if a.invert_transform {
        t = invert(&t);
    }
    for x in ts.iter_mut() {
        transform(&mut x.trajectory, &t, right, a.propagate_transform);
    }
    log.detail(&format!(
        "{} transformation from {file} applied",
        if right { "right" } else { "left" }
    ));
    Ok(())
}

/// `--project_to_plane xy|xz|yz`: the third coordinate of every position set to 0.
fn project(a: &TrajArgs, ts: &mut [TrajInput]) {
    let Some(plane) = &a.project_to_plane else {
        return;
    };
    let k = match plane.as_str() {
        "xz" => 1,
        "yz" => 0,
        _ => 2,
    };
    for t in ts.iter_mut() {
        for p in t.trajectory.positions.iter_mut() {
            p[k] = 0.0;
        }
    }
}

/// The information table, and with `-f` (or `-v`) evo's checks of each trajectory; returns
/// [`EXIT_WARNING`] when `-f` finds a trajectory that fails them.
fn report_info(a: &TrajArgs, all: &[&TrajInput], log: &EvoLog) -> Result<u8> {
    log.result(&info_table(all))?;
    if a.full_check || a.usability.verbose {
        for t in all {
            log.result(&full_check_text(t))?;
        }
    }
    if a.full_check && all.iter().any(|t| !check(t).valid()) {
        log.warn("warning [check_failed]: a trajectory failed evo's checks (see `checks:` above)");
        return Ok(EXIT_WARNING);
    }
    Ok(EXIT_OK)
}

/// The information table as the CSV of `--save_table`.
fn info_csv(all: &[&TrajInput]) -> String {
    let mut csv = String::from(
        "name,poses,length_m,duration_s,rate_hz,dt_max_s,gaps,stamps_going_back,duplicate_stamps\n",
    );
    for t in all {
        let i = trajdrift::evo::traj::info(t);
        let o = |v: Option<f64>| v.map_or(String::new(), |x| x.to_string());
        csv += &format!(
            "{},{},{},{},{},{},{},{},{}\n",
            trajdrift::report::escape::csv_field(&t.name),
            i.poses,
            i.length_m,
            o(i.duration_s),
            o(i.rate_hz),
            o(i.dt_max_s),
            i.gaps,
            t.rows.stamp_going_back,
            t.rows.duplicate_stamp
        );
    }
    csv
}

/// A trajectory's file stem (its name, `/` replaced).
fn stem(t: &TrajInput) -> String {
    trajdrift::output::names::file_stem(&t.name.replace('/', "_"))
}

/// The file `--save_as_mcap` (or `--save_as_bag`/`--save_as_bag2`) writes.
fn mcap_out(a: &TrajArgs) -> Option<PathBuf> {
    match (&a.save_as_mcap, a.save_as_bag || a.save_as_bag2) {
        (Some(p), _) => Some(p.clone()),
        (None, true) => Some(PathBuf::from("trajectories.mcap")),
        _ => None,
    }
}

/// Claims every file the conversions write before any is written: refused when one is an input or
/// another output, and when two trajectories of one name (`d1/est.tum` and `d2/est.tum`) would be
/// written to one file, or on one topic of the MCAP (evo asks before replacing the first, or with
/// --no_warnings replaces it).
fn claim_conversions(a: &TrajArgs, all: &[&TrajInput], guard: &mut OutputGuard) -> Result<()> {
    let twice = |flag: &str, x: &TrajInput, y: &TrajInput, into: String| {
        trajdrift::Error::InvalidArgument(format!(
            "{flag}: {} and {} would both be written {into}; rename one of the files (its name names the output)",
            x.path.display(),
            y.path.display()
        ))
    };
    for (flag, on, ext) in [
        ("--save_as_tum", a.save_as_tum, "tum"),
        ("--save_as_kitti", a.save_as_kitti, "kitti"),
    ] {
        if !on {
            continue;
        }
        for (i, t) in all.iter().enumerate() {
            let path = PathBuf::from(format!("{}.{ext}", stem(t)));
            if let Some(first) = all[..i].iter().find(|u| stem(u) == stem(t)) {
                return Err(twice(flag, first, t, format!("to {}", path.display())).into());
            }
            guard.claim(flag, &path)?;
        }
    }
    if let Some(path) = mcap_out(a) {
        for (i, t) in all.iter().enumerate() {
            let topic = topic_name(&t.name);
            if let Some(first) = all[..i].iter().find(|u| topic_name(&u.name) == topic) {
                return Err(twice(
                    "--save_as_mcap",
                    first,
                    t,
                    format!("on the topic {topic} of {}", path.display()),
                )
                .into());
            }
        }
        guard.claim("--save_as_mcap", &path)?;
    }
    Ok(())
}

/// Conversions: NAME.tum / NAME.kitti in the current folder, and one MCAP for all
/// (`--save_as_mcap`, or `--save_as_bag`/`--save_as_bag2`, which evo writes as bags).
fn save_conversions(
    a: &TrajArgs,
    all: &[&TrajInput],
    guard: &OutputGuard,
    log: &EvoLog,
) -> Result<()> {
    for (flag, on, ext, fmt) in [
        ("--save_as_tum", a.save_as_tum, "tum", SaveAs::Tum),
        ("--save_as_kitti", a.save_as_kitti, "kitti", SaveAs::Kitti),
    ] {
        if !on {
            continue;
        }
        // Two names mapping to one file would overwrite each other: refused by name.
        trajdrift::output::names::file_stems(
            "trajectories",
            all.iter().map(|t| t.name.as_str()),
            "give them distinct names",
        )?;
        for t in all {
            let path = PathBuf::from(format!("{}.{ext}", stem(t)));
            save(guard, flag, &path, &t.trajectory, fmt)?;
            log.note(&format!("{}: written to {}", t.name, path.display()));
        }
    }
    if a.save_as_mcap.is_none() && (a.save_as_bag || a.save_as_bag2) {
        log.warn("note: --save_as_bag/--save_as_bag2: trajdrift writes MCAP (ROS 2 PoseStamped), not a bag: trajectories.mcap");
    }
    if let Some(path) = mcap_out(a) {
        let list: Vec<(String, &Trajectory)> = all
            .iter()
            .map(|t| (topic_name(&t.name), &t.trajectory))
            .collect();
        save_mcap(guard, "--save_as_mcap", &path, &list)?;
        log.note(&format!(
            "trajectories written to {} ({})",
            path.display(),
            list.iter()
                .map(|l| l.0.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    Ok(())
}

/// `-p` / `--save_plot`: the trajectories and x/y/z figures, beside the first input
/// (`traj_NAME_...`) or at `--save_plot`. Returns true when a figure could not be written as asked
/// (a warning).
fn write_plots(
    a: &TrajArgs,
    ts: &[TrajInput],
    reference: Option<&TrajInput>,
    guard: &OutputGuard,
    log: &EvoLog,
) -> Result<bool> {
    let list: Vec<(String, &Trajectory)> =
        ts.iter().map(|t| (t.name.clone(), &t.trajectory)).collect();
    let figs = figures(
        &list,
        reference.map(|r| (r.name.as_str(), &r.trajectory)),
        PlotMode::parse(&a.plot_mode)?,
        a.plot_relative_time,
    );
    let base = PathBuf::from(format!("traj_{}", ts.first().map(stem).unwrap_or_default()));
    super::metric::write_figures(log, guard, a.save_plot.as_deref(), &base, &figs)
}
