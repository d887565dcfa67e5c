//! What `ape` and `rpe` share: turning evo's (or trajdrift's) command line into inputs and a pipeline,
//! `--time-offset auto` through eval's offset search, and evo's printout.

use anyhow::Result;

use trajdrift::clock::ClockCorrection;
use trajdrift::eval::config::{EvalConfig, NamedInput};
use trajdrift::eval::preset::Preset;
use trajdrift::eval::roles;
use trajdrift::evo::metric_result::{
    change_unit, evo_result, evo_title, figures, FigureOptions, ValueAxes,
};
use trajdrift::metrics::standard::filters::{downsample_ids, motion_filter_ids};
use trajdrift::metrics::standard::{
    Alignment, Metric, MetricResult, Pipeline, Plane, PoseRelation, SyncMethod,
};
use trajdrift::output::{is_stdout, write_json, OutputGuard};
use trajdrift::params::{Bound, Range};
use trajdrift::plot::evo::{PlotMode, PlotTarget};
use trajdrift::report::escape::escape;
use trajdrift::report::json::TimeOffsetStatus;
use trajdrift::standard::inputs::{EvoFormat, LoadedPair, MetricInputs};

use crate::cli::args::{text_options, MetricArgs};
use crate::cli::evo_args::{ignored_notes, EvoMetricArgs};
use crate::cli::evo_log::EvoLog;
use crate::cli::{EXIT_OK, EXIT_WARNING};

/// A range check of an evo flag, refused like `eval`'s (flag, value, range; exit 2).
fn in_range(
    flag: &str,
    v: f64,
    min: Bound,
    max: Bound,
    unit: &'static str,
) -> trajdrift::Result<f64> {
    Range { min, max, unit }.check(flag, v)
}

/// Every numeric flag shared by `ape`, `rpe` and `offset`, checked before anything is read: NaN,
/// infinities, negative or zero tolerances are refused naming the flag.
pub fn validate(a: &MetricArgs) -> trajdrift::Result<()> {
    use Bound::{Exclusive, Inclusive};
    in_range(
        "--t_max_diff",
        a.t_max_diff,
        Exclusive(0.0),
        Inclusive(86_400.0),
        "s",
    )?;
    if let Some(t) = a.t_offset {
        in_range("--t_offset", t, Inclusive(-1.0e10), Inclusive(1.0e10), "s")?;
    }
    if let Some(s) = a.time_offset.as_deref().filter(|s| *s != "auto") {
        let t = s.parse::<f64>().map_err(|_| {
            trajdrift::Error::InvalidArgument(format!(
                "--time-offset {s}: expected seconds or `auto`"
            ))
        })?;
        in_range(
            "--time-offset",
            t,
            Inclusive(-1.0e10),
            Inclusive(1.0e10),
            "s",
        )?;
    }
    for (flag, v) in [("--t_start", a.t_start), ("--t_end", a.t_end)] {
        if let Some(v) = v {
            in_range(flag, v, Inclusive(-1.0e15), Inclusive(1.0e15), "s")?;
        }
    }
    // evo takes 0 as unset (see `t_start_s` below); two set bounds must leave a span.
    if let (Some(start), Some(end)) = (
        a.t_start.filter(|&t| t != 0.0),
        a.t_end.filter(|&t| t != 0.0),
    ) {
        if start >= end {
            return Err(trajdrift::Error::InvalidArgument(format!(
                "--t_start {start} --t_end {end}: the crop is empty; give a --t_start before --t_end"
            )));
        }
    }
    if a.n_to_align == Some(0) {
        return Err(trajdrift::Error::InvalidArgument(
            "--n_to_align 0: align on at least 1 pair (leave it out to align on all)".into(),
        ));
    }
    Ok(())
}

/// evo's `--motion_filter DISTANCE ANGLE_DEGREES` (ape, rpe, traj): a distance in [0, 1e6] m and an
/// angle in [0, 360]°, checked before anything is read.
pub fn check_motion_filter(m: Option<&[f64]>) -> trajdrift::Result<()> {
    use Bound::Inclusive;
    if let Some(&[d, a]) = m {
        in_range(
            "--motion_filter DISTANCE",
            d,
            Inclusive(0.0),
            Inclusive(1.0e6),
            "m",
        )?;
        in_range(
            "--motion_filter ANGLE_DEGREES",
            a,
            Inclusive(0.0),
            Inclusive(360.0),
            "°",
        )?;
    }
    Ok(())
}

/// evo's numeric output flags of ape and rpe, checked before anything is read: the motion filter
/// ([`check_motion_filter`]), the colour map's bounds finite with its minimum below its maximum, its
/// percentile in [0, 100].
pub fn validate_evo(evo: &EvoMetricArgs) -> trajdrift::Result<()> {
    use Bound::Inclusive;
    check_motion_filter(evo.motion_filter.as_deref())?;
    let bound = |flag, v| in_range(flag, v, Inclusive(-1.0e15), Inclusive(1.0e15), "");
    let max = evo
        .plot_colormap_max
        .map(|v| bound("--plot_colormap_max", v))
        .transpose()?;
    let min = evo
        .plot_colormap_min
        .map(|v| bound("--plot_colormap_min", v))
        .transpose()?;
    if let Some(p) = evo.plot_colormap_max_percentile {
        in_range(
            "--plot_colormap_max_percentile",
            p,
            Inclusive(0.0),
            Inclusive(100.0),
            "%",
        )?;
    }
    if let (Some(lo), Some(hi)) = (min, max) {
        if lo >= hi {
            return Err(trajdrift::Error::InvalidArgument(format!(
                "--plot_colormap_min {lo} must be below --plot_colormap_max {hi}"
            )));
        }
    }
    Ok(())
}

/// The inputs named on the command line: evo's positional form, or the native one.
pub fn inputs(a: &MetricArgs) -> Result<MetricInputs> {
    if let Some(format) = a.inputs.first().and_then(|w| EvoFormat::parse(w)) {
        return Ok(MetricInputs::from_evo(format, &a.inputs[1..])?);
    }
    if a.inputs.len() > 1 {
        return Err(trajdrift::Error::InvalidArgument(format!(
            "`{}` is not a format (tum, kitti, euroc, bag, bag2, mcap); the native form takes one RECORDING with --reference/--estimate",
            a.inputs[0]
        ))
        .into());
    }
    let estimates: Vec<NamedInput> = match (&a.estimate, &a.estimate_file) {
        (Some(t), _) => vec![NamedInput::topic(t)],
        (None, Some(f)) => vec![NamedInput::file(&f.to_string_lossy())],
        _ => Vec::new(),
    };
    let recording: Vec<std::path::PathBuf> = a
        .inputs
        .first()
        .map(std::path::PathBuf::from)
        .into_iter()
        .collect();
    let preset = a.preset.as_deref().map(Preset::load).transpose()?;
    let roles = roles::resolve(
        &recording,
        roles::named_reference(a.reference.as_deref(), a.reference_file.as_deref()),
        estimates,
        preset.as_ref(),
        "give evo's form (tum REF EST, kitti REF EST, euroc GT EST, bag|bag2|mcap REC REF EST) or --reference/--reference-file",
    )?;
    let estimates = roles.estimates.clone();
    if estimates.is_empty() {
        return Err(trajdrift::Error::InvalidArgument(
            "give an estimate: --estimate TOPIC or --estimate-file FILE".into(),
        )
        .into());
    }
    let mut c = EvalConfig::new(recording.first().cloned(), roles.reference, estimates);
    c.params.stamp = Some(a.stamp);
    c.text = text_options(&a.text)?;
    Ok(MetricInputs::Eval(Box::new(c)))
}

/// The pipeline of the flags (the time offset is resolved separately).
pub fn pipeline(a: &MetricArgs, t_offset_s: f64) -> Pipeline {
    Pipeline {
        alignment: match (a.align, a.correct_scale, a.align_origin, a.align_yaw) {
            (_, _, true, _) => Alignment::Origin,
            (_, _, _, true) => Alignment::YawTranslation,
            (true, true, ..) => Alignment::Sim3,
            (true, false, ..) => Alignment::Se3,
            (false, true, ..) => Alignment::ScaleOnly,
            _ => Alignment::None,
        },
        // evo's default -1 (and any negative) means all poses.
        n_to_align: a.n_to_align.and_then(|n| usize::try_from(n).ok()),
        t_max_diff_s: a.t_max_diff,
        t_offset_s,
        sync: match a.sync_method.as_str() {
            "interpolation" => SyncMethod::Interpolation,
            _ => SyncMethod::NearestTime,
        },
        // evo tests `if args.t_start or args.t_end`: 0 means unset.
        t_start_s: a.t_start.filter(|&t| t != 0.0),
        t_end_s: a.t_end.filter(|&t| t != 0.0),
        project_to_plane: a.project_to_plane.as_deref().map(|p| match p {
            "xz" => Plane::Xz,
            "yz" => Plane::Yz,
            _ => Plane::Xy,
        }),
    }
}

/// The estimate's time offset for the metric: a constant added to its stamps in seconds (evo's
/// `--t_offset`), or the clock model `--time-offset auto` found when it is not constant (the same
/// correction `eval` applies); and whether the user must see a warning (a weak automatic offset).
pub struct ResolvedOffset {
    pub constant_s: f64,
    pub model: Option<ClockCorrection>,
    pub weak: bool,
}

/// Resolves `--t_offset` / `--time-offset S|auto`.
pub fn time_offset(a: &MetricArgs, inputs: &MetricInputs) -> Result<ResolvedOffset> {
    let constant = |t: f64| ResolvedOffset {
        constant_s: t,
        model: None,
        weak: false,
    };
    if let Some(t) = a.t_offset {
        return Ok(constant(t));
    }
    match a.time_offset.as_deref() {
        None => Ok(constant(0.0)),
        Some("auto") => {
            let config = inputs.offset_config()?;
            let report = trajdrift::eval::evaluate(&config, &|_| {})?;
            let o = &report.estimates[0].time_offset;
            let correction = ClockCorrection::from_report(o);
            let model = o.model.filter(|_| !correction.is_constant());
            eprintln!(
                "time offset (auto): {:+.4} s found by {} ({}), {}",
                o.offset_s,
                o.method,
                o.status,
                match model {
                    Some(m) => format!("clock model {} applied", m.as_str()),
                    None => format!("{:+.4} s applied", o.applied_s),
                }
            );
            let weak = !matches!(o.status, TimeOffsetStatus::Ok | TimeOffsetStatus::Given);
            Ok(match model {
                Some(_) => ResolvedOffset {
                    constant_s: 0.0,
                    model: Some(correction),
                    weak,
                },
                None => ResolvedOffset {
                    constant_s: o.applied_s,
                    model: None,
                    weak,
                },
            })
        }
        Some(s) => s.parse::<f64>().map(constant).map_err(|_| {
            trajdrift::Error::InvalidArgument(format!(
                "--time-offset {s}: expected seconds or `auto`"
            ))
            .into()
        }),
    }
}

/// Runs `metric` for the command line `a` (and evo's output flags `evo`) and prints it like evo (or
/// as JSON); writes evo's result file and figures when asked.
pub fn run(a: &MetricArgs, evo: &EvoMetricArgs, metric: Metric) -> Result<u8> {
    let log = EvoLog::new(&evo.usability, &(a, evo));
    note_ignored(&log, evo);
    validate(a)?;
    validate_evo(evo)?;
    let relation = PoseRelation::parse(&a.pose_relation)?;
    let inputs = inputs(a)?;
    let guard = claim_outputs(a, evo)?;
    let resolved = time_offset(a, &inputs)?;
    let pipeline = pipeline(a, resolved.constant_s);
    let pair = load_pair(evo, &inputs, &resolved, (metric, relation, &pipeline), &log)?;
    let LoadedPair {
        reference,
        estimate,
        reference_label,
        estimate_label,
        warnings,
    } = pair;
    let plots = evo.plot || evo.save_plot.is_some();
    let full_reference = (plots && evo.plot_full_ref).then(|| {
        reference
            .positions
            .iter()
            .map(|p| [p.x, p.y, p.z])
            .collect::<Vec<_>>()
    });
    let (mut result, evaluated) = if plots || evo.save_results.is_some() {
        let (r, e) = trajdrift::metrics::standard::evaluate_detailed(
            reference, estimate, metric, relation, &pipeline,
        )?;
        (r, Some(e))
    } else {
        (
            trajdrift::metrics::standard::evaluate(
                reference, estimate, metric, relation, &pipeline,
            )?,
            None,
        )
    };
    if let Some(u) = &evo.change_unit {
        change_unit(&mut result, u)?;
    }
    let al = &result.alignment;
    log.detail(&format!(
        "{} pairs; alignment {}: rotation {:?}, translation {:?} m, scale {}",
        result.pairs, al.method, al.rotation, al.translation_m, al.scale
    ));
    let to_stdout = a.json.as_deref().is_some_and(is_stdout);
    if let Some(path) = &a.json {
        write_json(path, &result)?;
    }
    if !to_stdout {
        log.result(&render(&result, relation, &pipeline))?;
    }
    let mut code = if resolved.weak { EXIT_WARNING } else { EXIT_OK };
    if let Some(e) = &evaluated {
        let names = names(a, &reference_label, &estimate_label);
        let written = EvoOutputs {
            result: &result,
            relation,
            pipeline: &pipeline,
            axes: &ValueAxes::of(e),
            names: (&names.0, &names.1),
            full_reference,
        }
        .write(evo, &log, &guard)?;
        if written {
            code = code.max(EXIT_WARNING);
        }
    }
    if resolved.weak {
        log.warn("warning [weak_time_offset]: the automatic time offset is not confident; none was applied");
    }
    for w in &warnings {
        log.warn(&crate::cli::warning_line(w));
    }
    code = code.max(crate::cli::exit_code(&warnings));
    log.finish(&guard)?;
    Ok(code)
}

/// Loads both trajectories (orientations only where the metric, the alignment or evo's motion
/// filter needs them), moves the estimate by a non-constant clock model, refuses single poses and
/// applies evo's pose filters.
fn load_pair(
    evo: &EvoMetricArgs,
    inputs: &MetricInputs,
    resolved: &ResolvedOffset,
    (metric, relation, pipeline): (Metric, PoseRelation, &Pipeline),
    log: &EvoLog,
) -> Result<LoadedPair> {
    let orientation =
        trajdrift::metrics::standard::needs_orientation(metric, relation, pipeline.alignment)
            || evo.motion_filter.is_some();
    let mut pair = inputs.load_with(&|_| {}, orientation)?;
    if let Some(model) = &resolved.model {
        pair.estimate = model.apply_to_poses(pair.estimate);
    }
    refuse_single_poses(&pair)?;
    log.detail(&format!(
        "reference {}: {} poses; estimate {}: {} poses",
        pair.reference_label,
        pair.reference.len(),
        pair.estimate_label,
        pair.estimate.len()
    ));
    filter_poses(&mut pair, evo, log)?;
    Ok(pair)
}

/// Names once on stderr the evo flags that have no meaning here (accepted, never a usage error).
fn note_ignored(log: &EvoLog, evo: &EvoMetricArgs) {
    for note in ignored_notes(&[evo.viewer.given(), evo.map_layers.given()].concat()) {
        log.warn(&note);
    }
}

/// Every output claimed before any work: never an input, never two outputs on one path.
fn claim_outputs(a: &MetricArgs, evo: &EvoMetricArgs) -> Result<OutputGuard> {
    let mut guard = OutputGuard::new(
        input_paths(a)
            .into_iter()
            .chain(evo.usability.config.clone()),
    );
    for (flag, out) in [
        ("--json", a.json.as_deref()),
        ("--save_results", evo.save_results.as_deref()),
        ("--logfile", evo.usability.logfile.as_deref()),
    ] {
        if let Some(out) = out {
            guard.claim(flag, out)?;
        }
    }
    Ok(guard)
}

/// One pose (or one stamp, written again) is no trajectory: refused by name rather than measured.
fn refuse_single_poses(pair: &LoadedPair) -> Result<()> {
    for (label, poses) in [
        (&pair.reference_label, &pair.reference),
        (&pair.estimate_label, &pair.estimate),
    ] {
        let distinct = match &poses.stamps_s {
            Some(t) => {
                let mut t: Vec<u64> = t.iter().map(|x| x.to_bits()).collect();
                t.sort_unstable();
                t.dedup();
                t.len()
            }
            None => poses.len(),
        };
        if distinct < 2 {
            return Err(trajdrift::Error::TooFewSamples {
                what: format!("{} (distinct stamps)", escape(label)),
                n: distinct,
                need: 2,
            }
            .into());
        }
    }
    Ok(())
}

/// evo's `--downsample` and `--motion_filter`, on both trajectories, said in the log.
fn filter_poses(pair: &mut LoadedPair, evo: &EvoMetricArgs, log: &EvoLog) -> Result<()> {
    if let Some(n) = evo.downsample {
        let (ir, ie) = (
            downsample_ids(pair.reference.len(), n),
            downsample_ids(pair.estimate.len(), n),
        );
        select_pair(pair, &ir, &ie);
        log.detail(&format!(
            "downsampled to at most {n} poses: {} and {}",
            pair.reference.len(),
            pair.estimate.len()
        ));
    }
    if let Some(m) = &evo.motion_filter {
        if pair.reference.stamps_s.is_none() || pair.estimate.stamps_s.is_none() {
            return Err(trajdrift::Error::Metric(
                "--motion_filter: trajectories without stamps (KITTI) can't be motion filtered: it would break the pairing by index".into(),
            )
            .into());
        }
        let (ir, ie) = (
            motion_filter_ids(&pair.reference, m[0], m[1])?,
            motion_filter_ids(&pair.estimate, m[0], m[1])?,
        );
        select_pair(pair, &ir, &ie);
        log.detail(&format!(
            "motion filter: {} and {} poses kept",
            pair.reference.len(),
            pair.estimate.len()
        ));
    }
    Ok(())
}

/// Keeps the reference's poses at `ir` and the estimate's at `ie`.
fn select_pair(pair: &mut LoadedPair, ir: &[u32], ie: &[u32]) {
    let take = |p: &mut trajdrift::metrics::standard::Poses, ids: &[u32]| {
        let all = std::mem::replace(
            p,
            trajdrift::metrics::standard::Poses {
                stamps_s: None,
                positions: Vec::new(),
                rotations: None,
            },
        );
        *p = all.select(ids);
    };
    take(&mut pair.reference, ir);
    take(&mut pair.estimate, ie);
}

/// What `--save_results` and `-p`/`--save_plot` write, from one metric's result.
struct EvoOutputs<'a> {
    result: &'a MetricResult,
    relation: PoseRelation,
    pipeline: &'a Pipeline,
    axes: &'a ValueAxes,
    /// The reference's and the estimate's names, as evo writes them.
    names: (&'a str, &'a str),
    /// `--plot_full_ref`: the reference's positions before the association.
    full_reference: Option<Vec<[f64; 3]>>,
}

impl EvoOutputs<'_> {
    /// Writes the result zip and the figures asked for; true when a figure format had to change (a
    /// warning the user must see).
    fn write(self, evo: &EvoMetricArgs, log: &EvoLog, guard: &OutputGuard) -> Result<bool> {
        let (ref_name, est_name) = self.names;
        if let Some(path) = &evo.save_results {
            let zip = evo_result(
                self.result,
                self.relation,
                self.pipeline,
                self.axes,
                ref_name,
                est_name,
            )
            .to_zip()?;
            replace_note(log, evo, path);
            guard.write("--save_results", path, &zip)?;
            log.detail(&format!("results written to {}", path.display()));
        }
        if !(evo.plot || evo.save_plot.is_some()) {
            return Ok(false);
        }
        let options = FigureOptions {
            mode: PlotMode::parse(&evo.plot_mode)?,
            x_dimension: evo.plot_x_dimension.clone(),
            colormap_min: evo.plot_colormap_min,
            colormap_max: evo.plot_colormap_max,
            colormap_max_percentile: evo.plot_colormap_max_percentile,
            full_reference: self.full_reference,
        };
        let title = evo_title(self.result, self.relation, self.pipeline);
        let short = std::path::Path::new(est_name)
            .file_name()
            .map_or(est_name.to_string(), |n| n.to_string_lossy().into_owned());
        let figures = figures(self.result, &title, self.axes, &short, &options);
        let default_base = evo.save_results.as_ref().map_or_else(
            || {
                std::path::PathBuf::from(format!(
                    "{}_{}",
                    self.result.metric,
                    trajdrift::output::names::file_stem(&short)
                ))
            },
            |r| r.with_extension(""),
        );
        write_figures(
            log,
            guard,
            evo.save_plot.as_deref(),
            &default_base,
            &figures,
        )
    }
}

/// The files a metric reads: what an output must not overwrite.
pub fn input_paths(a: &MetricArgs) -> Vec<std::path::PathBuf> {
    a.inputs
        .iter()
        .map(std::path::PathBuf::from)
        .chain(a.reference_file.iter().cloned())
        .chain(a.estimate_file.iter().cloned())
        .chain(a.text.kitti_times.iter().cloned())
        .chain(
            a.preset
                .iter()
                .map(std::path::PathBuf::from)
                .filter(|p| p.is_file()),
        )
        .collect()
}

/// The guard over the inputs, with `--json` claimed: refused before any work when it is an input.
pub fn claim_json(a: &MetricArgs) -> trajdrift::Result<OutputGuard> {
    let mut guard = OutputGuard::new(input_paths(a));
    if let Some(out) = &a.json {
        guard.claim("--json", out)?;
    }
    Ok(guard)
}

/// evo's `ref_name`/`est_name`: the files as given, the topics of the recording forms, else the
/// loaded labels.
fn names(a: &MetricArgs, reference: &str, estimate: &str) -> (String, String) {
    match (
        a.inputs.first().and_then(|w| EvoFormat::parse(w)),
        a.inputs.len(),
    ) {
        (Some(EvoFormat::Bag | EvoFormat::Bag2 | EvoFormat::Mcap), 4) => {
            (a.inputs[2].clone(), a.inputs[3].clone())
        }
        (Some(_), 3) => (a.inputs[1].clone(), a.inputs[2].clone()),
        _ => (reference.to_string(), estimate.to_string()),
    }
}

/// Says that an existing output is replaced (evo asks; `--no_warnings` skips both).
pub fn replace_note(log: &EvoLog, evo: &EvoMetricArgs, path: &std::path::Path) {
    if !evo.usability.no_warnings && path.exists() {
        log.warn(&format!("note: replacing {}", path.display()));
    }
}

/// Writes evo's figures to `--save_plot FILE` (or beside `default_base`) and says where; true when
/// a PDF was asked for and SVG written instead.
pub fn write_figures(
    log: &EvoLog,
    guard: &OutputGuard,
    save_plot: Option<&std::path::Path>,
    default_base: &std::path::Path,
    figures: &[(String, trajdrift::plot::evo::EvoFigure)],
) -> Result<bool> {
    let (target, substituted) = match save_plot {
        Some(p) => match PlotTarget::of(p) {
            Ok(t) => (t, false),
            Err(svg) => {
                log.warn(&format!(
                    "warning [no_pdf_backend]: --save_plot {}: trajdrift draws SVG and PNG only (no PDF backend in plotters); writing SVG instead (convert with e.g. rsvg-convert -f pdf)",
                    p.display()
                ));
                (svg, true)
            }
        },
        None => (
            PlotTarget {
                base: default_base.to_path_buf(),
                format: trajdrift::plot::PlotFormat::Svg,
            },
            false,
        ),
    };
    for (name, _) in figures {
        guard.check("--save_plot", &target.path(name))?;
    }
    let written = target.write(figures)?;
    let list: Vec<String> = written.iter().map(|p| p.display().to_string()).collect();
    log.note(&format!("figures written: {}", list.join(", ")));
    Ok(substituted)
}

/// evo's printout: the title (evo's words, `evo_title`), then the statistics sorted by name, six
/// decimals.
pub fn render(r: &MetricResult, relation: PoseRelation, p: &Pipeline) -> String {
    let mut s = evo_title(r, relation, p);
    if r.time_offset_s != 0.0 {
        s += &format!(" (estimate stamps shifted by {:+.6} s)", r.time_offset_s);
    }
    s += &format!("\n\n{:>10}\t{}\n\n", "pairs", r.pairs);
    let st = &r.stats;
    for (name, v) in [
        ("max", st.max),
        ("mean", st.mean),
        ("median", st.median),
        ("min", st.min),
        ("rmse", st.rmse),
        ("sse", st.sse),
        ("std", st.std),
    ] {
        s += &format!("{name:>10}\t{v:.6}\n");
    }
    s
}
