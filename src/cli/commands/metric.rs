//! What `ape` and `rpe` share: turning evo's (or trajdrift's) command line into inputs and a pipeline,
//! `--time-offset auto` through eval's offset search, and evo's printout.

use anyhow::Result;

use trajdrift::clock::ClockCorrection;
use trajdrift::eval::config::{EvalConfig, NamedInput};
use trajdrift::eval::preset::Preset;
use trajdrift::metrics::standard::{
    Alignment, Metric, MetricResult, Pipeline, Plane, PoseRelation, SyncMethod,
};
use trajdrift::output::write_output;
use trajdrift::report::json::TimeOffsetStatus;
use trajdrift::standard::inputs::{EvoFormat, LoadedPair, MetricInputs};

use crate::cli::args::{text_options, MetricArgs};
use crate::cli::{EXIT_OK, EXIT_WARNING};

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
    let reference = match (&a.reference, &a.reference_file) {
        (Some(t), _) => Some(NamedInput::topic(t)),
        (None, Some(f)) => Some(NamedInput::file(&f.to_string_lossy())),
        _ => None,
    };
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
    let (reference, estimates) = match a.preset.as_deref().map(Preset::load).transpose()? {
        Some(p) => {
            let s = p.select_in(recording.as_slice(), reference, estimates)?;
            (s.reference, s.estimates)
        }
        None => (
            reference.ok_or_else(|| {
                trajdrift::Error::InvalidArgument(
                    "give evo's form (tum REF EST, kitti REF EST, euroc GT EST, bag|bag2|mcap REC REF EST) or --reference/--reference-file".into(),
                )
            })?,
            estimates,
        ),
    };
    if estimates.is_empty() {
        return Err(trajdrift::Error::InvalidArgument(
            "give an estimate: --estimate TOPIC or --estimate-file FILE".into(),
        )
        .into());
    }
    let mut c = EvalConfig::new(recording.first().cloned(), reference, estimates);
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
        n_to_align: a.n_to_align,
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

/// Runs `metric` for the command line `a` and prints it like evo (or as JSON).
pub fn run(a: &MetricArgs, metric: Metric) -> Result<u8> {
    let relation = PoseRelation::parse(&a.pose_relation)?;
    let inputs = inputs(a)?;
    let resolved = time_offset(a, &inputs)?;
    let (offset, weak) = (resolved.constant_s, resolved.weak);
    let LoadedPair {
        reference,
        mut estimate,
        ..
    } = {
        let alignment = pipeline(a, offset).alignment;
        let orientation =
            trajdrift::metrics::standard::needs_orientation(metric, relation, alignment);
        inputs.load_with(&|_| {}, orientation)?
    };
    if let Some(model) = &resolved.model {
        estimate = model.apply_to_poses(estimate);
    }
    let pipeline = pipeline(a, offset);
    let result =
        trajdrift::metrics::standard::evaluate(reference, estimate, metric, relation, &pipeline)?;
    let to_stdout = a.json.as_deref().is_some_and(|p| p.as_os_str() == "-");
    if let Some(path) = &a.json {
        let mut bytes = serde_json::to_vec_pretty(&result)?;
        bytes.push(b'\n');
        write_output(path, &bytes)?;
    }
    if !to_stdout {
        print!("{}", render(&result, relation, &pipeline));
    }
    if weak {
        eprintln!("warning [weak_time_offset]: the automatic time offset is not confident; none was applied");
    }
    Ok(if weak { EXIT_WARNING } else { EXIT_OK })
}

/// evo's printout: the title, then the statistics sorted by name, six decimals.
pub fn render(r: &MetricResult, relation: PoseRelation, p: &Pipeline) -> String {
    let what = match relation {
        PoseRelation::TransPart => "translation part",
        PoseRelation::RotPart => "rotation part",
        PoseRelation::Full => "full transformation",
        PoseRelation::AngleDeg => "rotation angle in degrees",
        PoseRelation::AngleRad => "rotation angle in radians",
        PoseRelation::PointDistance => "point distance",
        PoseRelation::PointDistanceErrorRatio => "point distance error ratio",
    };
    let unit = match r.unit.as_str() {
        "" => "unit-less".to_string(),
        u => u.to_string(),
    };
    let mut s = format!("{} w.r.t. {what} ({unit})\n", r.metric.to_uppercase());
    if let Some(d) = &r.delta {
        let mode = if d.all_pairs { "all" } else { "consecutive" };
        s += &format!("for delta = {} ({}) using {mode} pairs\n", d.delta, d.unit);
    }
    s += match p.alignment {
        Alignment::None => "(not aligned)",
        Alignment::Se3 => "(with SE(3) Umeyama alignment)",
        Alignment::Sim3 => "(with Sim(3) Umeyama alignment)",
        Alignment::ScaleOnly => "(scale corrected)",
        Alignment::Origin => "(with origin alignment)",
        Alignment::YawTranslation => "(with 4-DoF yaw + translation alignment)",
    };
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
