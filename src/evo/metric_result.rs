//! An APE/RPE result as evo holds it: the title and label evo prints, and the arrays of its result
//! file, made from a [`MetricResult`] and the poses it was computed on ([`Evaluated`]), the way
//! `evo.main_ape.ape` and `evo.main_rpe.rpe` make them.

use serde_json::Value;

use crate::metrics::standard::{
    Alignment, Evaluated, MetricResult, Pipeline, Plane, PoseRelation, Poses,
};
use crate::report::evo_zip::{py_float, EvoResult};
use crate::report::npy::NpyArray;

/// evo's name of a relation (`PoseRelation.value`).
pub fn relation_words(r: PoseRelation) -> &'static str {
    match r {
        PoseRelation::TransPart => "translation part",
        PoseRelation::RotPart => "rotation part",
        PoseRelation::Full => "full transformation",
        PoseRelation::AngleDeg => "rotation angle in degrees",
        PoseRelation::AngleRad => "rotation angle in radians",
        PoseRelation::PointDistance => "point distance",
        PoseRelation::PointDistanceErrorRatio => "point distance error ratio",
    }
}

/// evo's name of a result's unit (`Unit.value`).
pub fn unit_words(unit: &str) -> &str {
    match unit {
        "" => "unit-less",
        u => u,
    }
}

/// The title evo prints and stores (`info.title`): the metric, the delta (RPE), the alignment, the
/// poses aligned on and the projection, each on evo's line and in evo's words.
pub fn evo_title(r: &MetricResult, relation: PoseRelation, p: &Pipeline) -> String {
    let mut s = format!(
        "{} w.r.t. {} ({})",
        r.metric.to_uppercase(),
        relation_words(relation),
        unit_words(&r.unit)
    );
    if let Some(d) = &r.delta {
        let mode = if d.all_pairs { "all" } else { "consecutive" };
        s += &format!(
            "\nfor delta = {} ({}) using {mode} pairs",
            py_float(d.delta),
            d.unit
        );
    }
    s += match p.alignment {
        Alignment::None => "\n(not aligned)",
        Alignment::Se3 => "\n(with SE(3) Umeyama alignment)",
        Alignment::Sim3 => "\n(with Sim(3) Umeyama alignment)",
        Alignment::ScaleOnly => "\n(scale corrected)",
        Alignment::Origin => "",
        Alignment::YawTranslation => "\n(with 4-DoF yaw + translation alignment)",
    };
    if let (Some(n), Alignment::Se3 | Alignment::Sim3 | Alignment::ScaleOnly) =
        (p.n_to_align, p.alignment)
    {
        s += &format!(" (aligned poses: {n})");
    }
    if p.alignment == Alignment::Origin {
        s += "\n(with origin alignment)";
    }
    if let Some(plane) = p.project_to_plane {
        let name = match plane {
            Plane::Xy => "xy",
            Plane::Xz => "xz",
            Plane::Yz => "yz",
        };
        s += &format!("\n(projected to {name} plane)");
    }
    s
}

/// The cumulative path length of `positions` (evo's `PosePath3D.distances`).
pub fn distances(p: &Poses) -> Vec<f64> {
    let mut d = Vec::with_capacity(p.len());
    let mut acc = 0.0;
    for (k, x) in p.positions.iter().enumerate() {
        if k > 0 {
            acc += (x - p.positions[k - 1]).norm();
        }
        d.push(acc);
    }
    d
}

/// The poses at `ids` (positions and stamps only).
fn subset(p: &Poses, ids: &[usize]) -> Poses {
    Poses {
        stamps_s: p
            .stamps_s
            .as_ref()
            .map(|s| ids.iter().map(|&i| s[i]).collect()),
        positions: ids.iter().map(|&i| p.positions[i]).collect(),
        rotations: None,
    }
}

/// The per-value stamps, seconds from start and distances evo stores, and the poses its figures
/// colour: for APE the associated poses, for RPE the first pose and each pair's second pose (evo's
/// `[0] + delta_ids`).
#[derive(Debug, Clone)]
pub struct ValueAxes {
    /// Stamps of the estimate's poses carrying the values (`None` for KITTI paths).
    pub timestamps: Option<Vec<f64>>,
    pub seconds_from_start: Option<Vec<f64>>,
    /// Path length of the reference / the estimate at each value.
    pub distances_from_start: Vec<f64>,
    pub distances: Vec<f64>,
    /// The reference and estimate poses the values belong to (RPE: with the first pose in front).
    pub reference: Poses,
    pub estimate: Poses,
}

impl ValueAxes {
    /// The axes of `e`'s values.
    pub fn of(e: &Evaluated) -> ValueAxes {
        let (reference, estimate, skip) = match &e.pairs {
            None => (
                subset(&e.reference, &(0..e.reference.len()).collect::<Vec<_>>()),
                subset(&e.estimate, &(0..e.estimate.len()).collect::<Vec<_>>()),
                0,
            ),
            Some(pairs) => {
                let ids: Vec<usize> = std::iter::once(0)
                    .chain(pairs.iter().map(|p| p.1))
                    .collect();
                (subset(&e.reference, &ids), subset(&e.estimate, &ids), 1)
            }
        };
        let stamps = estimate.stamps_s.clone();
        let d_ref = distances(&reference);
        let d_est = distances(&estimate);
        ValueAxes {
            seconds_from_start: stamps
                .as_ref()
                .map(|s| s.iter().skip(skip).map(|t| t - s[0]).collect()),
            timestamps: stamps.map(|s| s[skip..].to_vec()),
            distances_from_start: d_ref[skip.min(d_ref.len())..].to_vec(),
            distances: d_est[skip.min(d_est.len())..].to_vec(),
            reference,
            estimate,
        }
    }
}

/// evo's `Result` of one APE/RPE run, ready for `--save_results`.
pub fn evo_result(
    r: &MetricResult,
    relation: PoseRelation,
    pipeline: &Pipeline,
    axes: &ValueAxes,
    ref_name: &str,
    est_name: &str,
) -> EvoResult {
    let mut out = EvoResult {
        info: vec![
            (
                "title".into(),
                Value::from(evo_title(r, relation, pipeline)),
            ),
            ("ref_name".into(), Value::from(ref_name)),
            ("est_name".into(), Value::from(est_name)),
            (
                "label".into(),
                Value::from(format!(
                    "{} ({})",
                    r.metric.to_uppercase(),
                    unit_words(&r.unit)
                )),
            ),
        ],
        stats: vec![
            ("rmse".into(), r.stats.rmse),
            ("mean".into(), r.stats.mean),
            ("median".into(), r.stats.median),
            ("std".into(), r.stats.std),
            ("min".into(), r.stats.min),
            ("max".into(), r.stats.max),
            ("sse".into(), r.stats.sse),
        ],
        arrays: Vec::new(),
    };
    out.push_array("error_array", r.values.clone());
    if let (Some(t), Some(s)) = (&axes.timestamps, &axes.seconds_from_start) {
        out.push_array("seconds_from_start", s.clone());
        out.push_array("timestamps", t.clone());
        out.push_array("distances_from_start", axes.distances_from_start.clone());
        out.push_array("distances", axes.distances.clone());
    }
    if pipeline.alignment != Alignment::None {
        let a = &r.alignment;
        let mut m = vec![0.0; 16];
        for i in 0..3 {
            for j in 0..3 {
                m[4 * i + j] = a.scale * a.rotation[i][j];
            }
            m[4 * i + 3] = a.translation_m[i];
        }
        m[15] = 1.0;
        out.arrays.push((
            "alignment_transformation_sim3".into(),
            NpyArray {
                shape: vec![4, 4],
                data: m,
            },
        ));
    }
    out
}

/// What the figures of `ape`/`rpe -p` show beyond the result.
#[derive(Debug, Clone, Default)]
pub struct FigureOptions {
    pub mode: crate::plot::evo::PlotMode,
    /// `index`, `seconds` or `distances`.
    pub x_dimension: String,
    pub colormap_min: Option<f64>,
    pub colormap_max: Option<f64>,
    pub colormap_max_percentile: Option<f64>,
    /// The whole reference as read (`--plot_full_ref`), else the associated poses are drawn.
    pub full_reference: Option<Vec<[f64; 3]>>,
}

/// evo's figures of one APE/RPE result: `raw` (the values against index, seconds or distance with
/// rmse, median, mean and std), `map` (the reference and the estimate coloured by its value) and
/// `stats` (the statistics as bars).
pub fn figures(
    r: &MetricResult,
    title: &str,
    axes: &ValueAxes,
    est_name: &str,
    o: &FigureOptions,
) -> Vec<(String, crate::plot::evo::EvoFigure)> {
    use crate::plot::evo::{EvoFigure, StatsBars};
    let label = format!("{} ({})", r.metric.to_uppercase(), unit_words(&r.unit));
    let one_line = title.replace('\n', " ");
    let st = &r.stats;
    let raw = raw_figure(r, axes, &o.x_dimension, &one_line, &label);
    let map = map_figure(r, axes, est_name, o, &one_line, &label);
    let names = ["rmse", "median", "mean", "std", "min", "max"];
    let stats = StatsBars {
        title: one_line,
        value_label: label,
        stats: names.iter().map(|s| s.to_string()).collect(),
        results: vec![(
            est_name.to_string(),
            vec![st.rmse, st.median, st.mean, st.std, st.min, st.max],
        )],
    };
    vec![
        ("raw".into(), EvoFigure::Errors(raw)),
        ("map".into(), EvoFigure::Map(map)),
        ("stats".into(), EvoFigure::Stats(stats)),
    ]
}

/// The raw figure: the values over `x_dimension` (`distances` or `seconds` when the poses have
/// stamps, else the index), with rmse, median, mean and std.
fn raw_figure(
    r: &MetricResult,
    axes: &ValueAxes,
    x_dimension: &str,
    title: &str,
    label: &str,
) -> crate::plot::evo::ErrorSeries {
    let (x, x_label): (Vec<f64>, &str) = match (x_dimension, &axes.seconds_from_start) {
        ("distances", Some(_)) => (axes.distances_from_start.clone(), "d (m)"),
        ("seconds", Some(s)) => (s.clone(), "t (s)"),
        _ => ((0..r.values.len()).map(|i| i as f64).collect(), "index"),
    };
    let st = &r.stats;
    crate::plot::evo::ErrorSeries {
        title: title.to_string(),
        x_label: x_label.into(),
        y_label: label.to_string(),
        series: vec![(
            label.to_string(),
            x.iter().copied().zip(r.values.iter().copied()).collect(),
        )],
        stats: vec![
            ("rmse".into(), st.rmse),
            ("median".into(), st.median),
            ("mean".into(), st.mean),
            ("std".into(), st.std),
        ],
        markers: false,
    }
}

/// The map figure: the reference (the whole one with `--plot_full_ref`) and the estimate coloured
/// by its values on the range of the `--plot_colormap_*` options (default: min to max).
fn map_figure(
    r: &MetricResult,
    axes: &ValueAxes,
    est_name: &str,
    o: &FigureOptions,
    title: &str,
    label: &str,
) -> crate::plot::evo::TrajectoryMap {
    use crate::plot::evo::{Coloured, TrajectoryMap};
    let st = &r.stats;
    let mut cmax = o.colormap_max.unwrap_or(st.max);
    if let Some(p) = o.colormap_max_percentile {
        let mut s = r.values.clone();
        s.sort_by(f64::total_cmp);
        cmax = crate::stats::quantile_sorted(&s, p / 100.0);
    }
    let cmin = o.colormap_min.unwrap_or(st.min);
    let xyz = |p: &Poses| {
        p.positions
            .iter()
            .map(|v| [v.x, v.y, v.z])
            .collect::<Vec<_>>()
    };
    // RPE: the first pose carries no value (evo's `[0] + delta_ids`): colour it with the first value.
    let est = xyz(&axes.estimate);
    let skip = est.len().saturating_sub(r.values.len());
    let mut values = vec![r.values.first().copied().unwrap_or(0.0); skip];
    values.extend(r.values.iter().copied());
    TrajectoryMap {
        title: title.to_string(),
        mode: o.mode,
        reference: Some(
            o.full_reference
                .clone()
                .unwrap_or_else(|| xyz(&axes.reference)),
        ),
        trajectories: Vec::new(),
        coloured: Some(Coloured {
            name: est_name.to_string(),
            positions: est,
            values,
            cmin,
            cmax,
            value_label: label.to_string(),
        }),
    }
}

/// `--change_unit`: the values and statistics in `to` (m, cm, mm, km from a length; deg, rad from an
/// angle), as evo's `PE.change_unit`.
pub fn change_unit(r: &mut MetricResult, to: &str) -> crate::error::Result<()> {
    let metres = |u: &str| match u {
        "mm" => Some(1e-3),
        "cm" => Some(1e-2),
        "m" => Some(1.0),
        "km" => Some(1e3),
        _ => None,
    };
    let factor = match (r.unit.as_str(), to) {
        (a, b) if a == b => return Ok(()),
        (a, b) if metres(a).is_some() && metres(b).is_some() => {
            metres(a).unwrap_or(1.0) / metres(b).unwrap_or(1.0)
        }
        ("rad", "deg") => 180.0 / std::f64::consts::PI,
        ("deg", "rad") => std::f64::consts::PI / 180.0,
        (a, b) => {
            return Err(crate::error::Error::InvalidArgument(format!(
                "--change_unit {b}: cannot convert {} to {b}",
                unit_words(a)
            )))
        }
    };
    if r.unit == "rad" && to == "deg" {
        r.values.iter_mut().for_each(|v| *v = v.to_degrees());
    } else if r.unit == "deg" && to == "rad" {
        r.values.iter_mut().for_each(|v| *v = v.to_radians());
    } else {
        r.values.iter_mut().for_each(|v| *v *= factor);
    }
    if let Some(s) = crate::metrics::standard::ErrorStats::of(&r.values) {
        r.stats = s;
    }
    r.unit = to.to_string();
    Ok(())
}
