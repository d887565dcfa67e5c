//! `trajdrift._trajdrift`: trajdrift's library API on NumPy arrays, and the command line in process.
//!
//! The Python package `trajdrift` (`python/trajdrift/`) is the face users see: evo's nouns, keyword
//! arguments, typed results. This module is the thin layer under it, and it stands on the `trajdrift`
//! crate's root items only (`trajdrift::read`, `trajdrift::ape`, `trajdrift::Parameters`, …), never on a
//! module path inside the crate, so that the crate can rearrange its modules freely.
//!
//! How the data cross: a trajectory the library read goes to NumPy without a copy (its `Vec`s become
//! the arrays' buffers: stamps as `int64` nanoseconds, positions N×3 and quaternions N×4 `x, y, z, w`
//! reinterpreted in place with bytemuck); arrays from Python are copied once into the library's types.
//! Every long computation runs with the interpreter's lock released (`Python::detach`). Reports cross
//! as their JSON text (the façade parses it), so `Report.to_dict()` is the command line's JSON by
//! construction. Errors become the package's exceptions (`trajdrift._errors`) with the command line's
//! one-line message.
//!
//! Threads: the library's parallel loops run in a rayon pool this module owns and rebuilds in a process
//! forked from the one that built it (`run`): rayon's global pool would be shared with the parent,
//! whose worker threads do not exist in a forked child, and a child's first parallel loop would wait
//! for them forever (`multiprocessing`'s `fork` start method).

use std::collections::HashMap;
use std::ffi::OsString;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3};
use numpy::{
    IntoPyArray, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3,
    PyUntypedArrayMethods,
};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString, PyTuple};

use trajdrift::{
    CsvMapping, DeltaUnit, EvalRequest, LeverSpec, MetricOptions, NamedInput, NamedTrajectory,
    PairSelection, Parameters, Plane, PoseRelation, Poses, ReadOptions, Rotations, StampSeconds,
    StampSource, StandardResult, SyncMethod, TextFormat, TextOptions, Trajectory, TrajectoryInput,
    TrajectoryRead, ValueKind, SPECS,
};

/// The package's exception for a library error: `UsageError` (a `ValueError`: a bad parameter or
/// argument, the command line's exit 2), `MetricError` (the data do not allow the computation) or
/// `InputError` (a file, recording, topic or format that cannot be read), with the command line's
/// one-line message.
fn py_error(e: trajdrift::Error) -> PyErr {
    let class = match &e {
        trajdrift::Error::InvalidArgument(_) | trajdrift::Error::OutputIsInput { .. } => {
            "UsageError"
        }
        trajdrift::Error::TooFewSamples { .. }
        | trajdrift::Error::NoOverlap { .. }
        | trajdrift::Error::Metric(_) => "MetricError",
        _ => "InputError",
    };
    exception(class, trajdrift::error_message(&e))
}

/// An instance of the package's exception `class` with `message`.
fn exception(class: &str, message: String) -> PyErr {
    Python::attach(|py| {
        match py
            .import("trajdrift._errors")
            .and_then(|m| m.getattr(class))
            .and_then(|c| c.call1((message.clone(),)))
        {
            Ok(e) => PyErr::from_value(e),
            Err(_) => PyValueError::new_err(message),
        }
    })
}

fn usage(message: String) -> PyErr {
    exception("UsageError", message)
}

// ---------------------------------------------------------------------------------------------------
// The thread pool.

/// The pool of this process, with the id of the process that built it.
static POOL: Mutex<Option<(u32, Arc<rayon::ThreadPool>)>> = Mutex::new(None);

/// The rayon pool of the current process: built on first use, and built again in a forked child (whose
/// copy of the parent's pool has no threads; it is leaked, as its threads cannot be joined).
fn pool() -> PyResult<Arc<rayon::ThreadPool>> {
    let mut slot = POOL.lock().unwrap_or_else(|e| e.into_inner());
    let pid = std::process::id();
    if let Some((owner, pool)) = slot.as_ref() {
        if *owner == pid {
            return Ok(Arc::clone(pool));
        }
    }
    let pool = Arc::new(
        rayon::ThreadPoolBuilder::new()
            .thread_name(|i| format!("trajdrift-{i}"))
            .build()
            .map_err(|e| {
                exception(
                    "Error",
                    format!("could not start trajdrift's worker threads: {e}"),
                )
            })?,
    );
    if let Some(parents) = slot.replace((pid, Arc::clone(&pool))) {
        std::mem::forget(parents);
    }
    Ok(pool)
}

/// `work` with the interpreter's lock released, its parallel loops in this process's pool.
fn run<T: Send>(py: Python<'_>, work: impl FnOnce() -> T + Send) -> PyResult<T> {
    let pool = pool()?;
    Ok(py.detach(|| pool.install(work)))
}

// ---------------------------------------------------------------------------------------------------
// Arrays in and out.

/// Positions from an N×3 array.
fn positions(xyz: &PyReadonlyArray2<'_, f64>, n: usize) -> PyResult<Vec<Vector3<f64>>> {
    let a = xyz.as_array();
    if a.shape() != [n, 3] {
        return Err(usage(format!(
            "xyz must be N×3 with N = {n} stamps, got shape {:?}",
            a.shape()
        )));
    }
    Ok(a.rows()
        .into_iter()
        .map(|r| Vector3::new(r[0], r[1], r[2]))
        .collect())
}

/// Quaternions from an N×4 array `x, y, z, w`: unit ones for the evaluation (`normalize`), as given for
/// evo's metrics (which normalise inside `quaternion_matrix`, as evo does).
fn quaternions(
    quat: &PyReadonlyArray2<'_, f64>,
    n: usize,
    normalize: bool,
) -> PyResult<Vec<UnitQuaternion<f64>>> {
    let a = quat.as_array();
    if a.shape() != [n, 4] {
        return Err(usage(format!(
            "quat must be N×4 (x, y, z, w) with N = {n} stamps, got shape {:?}",
            a.shape()
        )));
    }
    Ok(a.rows()
        .into_iter()
        .map(|r| {
            let q = Quaternion::new(r[3], r[0], r[1], r[2]);
            if normalize {
                UnitQuaternion::from_quaternion(q)
            } else {
                UnitQuaternion::new_unchecked(q)
            }
        })
        .collect())
}

/// A trajectory from its arrays (copied).
fn trajectory(
    t: &PyReadonlyArray1<'_, i64>,
    xyz: &PyReadonlyArray2<'_, f64>,
    quat: &Option<PyReadonlyArray2<'_, f64>>,
) -> PyResult<Trajectory> {
    let stamps_ns = t.as_array().to_vec();
    let n = stamps_ns.len();
    Ok(Trajectory {
        positions: positions(xyz, n)?,
        orientations: quat.as_ref().map(|q| quaternions(q, n, true)).transpose()?,
        stamps_ns,
    })
}

/// The arrays of a trajectory the library made, handed to NumPy without copying: stamps (int64 ns),
/// positions N×3, quaternions N×4 `x, y, z, w` or `None`.
fn trajectory_arrays<'py>(
    py: Python<'py>,
    t: Trajectory,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    let n = t.stamps_ns.len();
    let stamps = t.stamps_ns.into_pyarray(py).into_any();
    let xyz = bytemuck::cast_vec::<Vector3<f64>, f64>(t.positions)
        .into_pyarray(py)
        .reshape([n, 3])?
        .into_any();
    let quat = match t.orientations {
        Some(q) => bytemuck::cast_vec::<UnitQuaternion<f64>, f64>(q)
            .into_pyarray(py)
            .reshape([n, 4])?
            .into_any(),
        None => py.None().into_bound(py),
    };
    Ok((stamps, xyz, quat))
}

/// evo's stamp conversion by its word in the package (`Trajectory.stamp_seconds`).
fn stamp_seconds(word: Option<&str>) -> PyResult<Option<StampSeconds>> {
    Ok(match word {
        None => None,
        Some("decimal") => Some(StampSeconds::Decimal),
        Some("nanos_over_1e9") => Some(StampSeconds::NanosOverE9),
        Some("sec_plus_nanos") => Some(StampSeconds::SecPlusNanos),
        Some(w) => {
            return Err(usage(format!(
                "stamp_seconds `{w}`: expected decimal, nanos_over_1e9, sec_plus_nanos or None"
            )))
        }
    })
}

fn stamp_seconds_word(s: Option<StampSeconds>) -> Option<&'static str> {
    s.map(|s| match s {
        StampSeconds::Decimal => "decimal",
        StampSeconds::NanosOverE9 => "nanos_over_1e9",
        StampSeconds::SecPlusNanos => "sec_plus_nanos",
    })
}

/// evo's form of one trajectory for APE/RPE: stamps as seconds (given, as evo's objects hold them, or
/// converted from nanoseconds by the source's rule, or none: paired by index), positions, and the
/// rotation matrices as written (KITTI) or the quaternions.
#[derive(FromPyObject)]
struct PosesIn<'py> {
    #[pyo3(item)]
    t: Option<PyReadonlyArray1<'py, i64>>,
    #[pyo3(item)]
    stamp_seconds: Option<String>,
    #[pyo3(item)]
    seconds: Option<PyReadonlyArray1<'py, f64>>,
    #[pyo3(item)]
    xyz: PyReadonlyArray2<'py, f64>,
    #[pyo3(item)]
    quat: Option<PyReadonlyArray2<'py, f64>>,
    #[pyo3(item)]
    rot: Option<PyReadonlyArray3<'py, f64>>,
}

impl PosesIn<'_> {
    fn poses(&self) -> PyResult<Poses> {
        let n = self.xyz.shape()[0];
        let stamps_s = match (&self.seconds, &self.t) {
            (Some(s), _) => Some(s.as_array().to_vec()),
            (None, Some(t)) => stamp_seconds(self.stamp_seconds.as_deref())?
                .map(|c| t.as_array().iter().map(|&ns| c.convert(ns)).collect()),
            (None, None) => None,
        };
        if stamps_s.as_ref().is_some_and(|s: &Vec<f64>| s.len() != n) {
            return Err(usage(
                "the stamps and the positions differ in length".into(),
            ));
        }
        let rotations = match (&self.rot, &self.quat) {
            (Some(r), _) => {
                let a = r.as_array();
                if a.shape() != [n, 3, 3] {
                    return Err(usage(format!(
                        "rot must be N×3×3 with N = {n}, got shape {:?}",
                        a.shape()
                    )));
                }
                Some(Rotations::Matrices(
                    a.outer_iter()
                        .map(|m| Matrix3::from_fn(|i, j| m[[i, j]]))
                        .collect(),
                ))
            }
            (None, Some(q)) => Some(Rotations::Quaternions {
                q: quaternions(q, n, false)?,
                left: Matrix3::identity(),
            }),
            (None, None) => None,
        };
        Ok(Poses {
            stamps_s,
            positions: positions(&self.xyz, n)?,
            rotations,
        })
    }
}

// ---------------------------------------------------------------------------------------------------
// Parameters: the one table, from keyword arguments.

/// The command-line items of one parameter's value: a string as the flag takes it (a list's items
/// split at `,`), a number or word as Python writes it, a sequence item by item (a triple joined
/// back into `a,b,c`). The table's parser then reads them exactly as it reads the command line's.
fn items(kind: ValueKind, v: &Bound<'_, PyAny>) -> PyResult<Vec<String>> {
    let list_kind = matches!(kind, ValueKind::Numbers | ValueKind::Words(_));
    if let Ok(s) = v.cast::<PyString>() {
        let s: String = s.extract()?;
        return Ok(if list_kind {
            s.split(',').map(|x| x.trim().to_string()).collect()
        } else {
            vec![s]
        });
    }
    let seq: Option<Vec<String>> = if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>()
    {
        Some(
            v.try_iter()?
                .map(|x| x.and_then(|x| x.str()?.extract::<String>()))
                .collect::<PyResult<_>>()?,
        )
    } else if v.hasattr("tolist")? && v.hasattr("shape")? {
        // A NumPy array.
        return items(kind, &v.call_method0("tolist")?);
    } else {
        None
    };
    Ok(match (seq, kind) {
        (Some(s), ValueKind::Triple) => vec![s.join(",")],
        (Some(s), _) => s,
        (None, _) => vec![v.str()?.extract::<String>()?],
    })
}

/// [`Parameters`] from keyword arguments (keys as the table writes them, `-` as `_`), parsed and checked
/// by the table like the command line's flags: a bad value is the command line's message, as a
/// `UsageError` (a `ValueError`). `None` values are unset.
fn parameters(given: Option<&Bound<'_, PyDict>>) -> PyResult<Parameters> {
    let mut map: HashMap<&'static str, Vec<String>> = HashMap::new();
    if let Some(d) = given {
        for (k, v) in d.iter() {
            let key: String = k.extract()?;
            let Some(spec) = SPECS.iter().find(|s| s.key == key) else {
                return Err(usage(format!(
                    "unexpected parameter `{key}`; the parameters are {}",
                    SPECS.iter().map(|s| s.key).collect::<Vec<_>>().join(", ")
                )));
            };
            if v.is_none() {
                continue;
            }
            map.insert(spec.key, items(spec.kind, &v)?);
        }
    }
    let p = Parameters::from_flags(|k| map.get(k).cloned()).map_err(usage)?;
    p.validate().map_err(py_error)?;
    Ok(p)
}

/// Every parameter of the table: key, flag, value name, help, default, range and kind, for the
/// package's documentation and `help()`.
#[pyfunction]
fn parameter_specs(py: Python<'_>) -> PyResult<Vec<Bound<'_, PyDict>>> {
    SPECS
        .iter()
        .map(|s| {
            let d = PyDict::new(py);
            d.set_item("key", s.key)?;
            d.set_item("flag", s.flag())?;
            d.set_item("value_name", s.value_name)?;
            d.set_item("help", s.help())?;
            d.set_item("default", s.default_text())?;
            d.set_item("range", s.range.map(|r| r.text()))?;
            let (kind, words) = match s.kind {
                ValueKind::Number => ("number", None),
                ValueKind::Numbers => ("numbers", None),
                ValueKind::Triple => ("triple", None),
                ValueKind::Word(w) => ("word", Some(w())),
                ValueKind::Words(w) => ("words", Some(w())),
            };
            d.set_item("kind", kind)?;
            d.set_item("words", words)?;
            Ok(d)
        })
        .collect()
}

/// Checks keyword parameters as `evaluate` does: raises the command line's message for a bad value.
#[pyfunction]
#[pyo3(signature = (parameters_=None))]
fn check_parameters(parameters_: Option<&Bound<'_, PyDict>>) -> PyResult<()> {
    parameters(parameters_).map(|_| ())
}

// ---------------------------------------------------------------------------------------------------
// The functions.

fn text_options(
    text_format: Option<&str>,
    csv: Option<&str>,
    kitti_times: Option<PathBuf>,
) -> PyResult<TextOptions> {
    let format = match text_format {
        None => None,
        Some("tum") => Some(TextFormat::Tum),
        Some("kitti") => Some(TextFormat::Kitti),
        Some("euroc") => Some(TextFormat::Euroc),
        Some("csv") => Some(TextFormat::Csv),
        Some(w) => {
            return Err(usage(format!(
                "text_format `{w}`: expected tum, kitti, euroc or csv"
            )))
        }
    };
    Ok(TextOptions {
        format,
        csv: csv.map(CsvMapping::parse).transpose().map_err(py_error)?,
        kitti_times,
    })
}

/// `trajdrift.read`: one trajectory of a recording (a topic or TF chain) or a text file, with its
/// arrays and what is known of it.
#[pyfunction]
#[pyo3(signature = (sources, topic=None, stamp="header", origin=None, text_format=None, csv=None, kitti_times=None))]
#[allow(clippy::too_many_arguments)]
fn read<'py>(
    py: Python<'py>,
    sources: Vec<PathBuf>,
    topic: Option<String>,
    stamp: &str,
    origin: Option<[f64; 3]>,
    text_format: Option<&str>,
    csv: Option<&str>,
    kitti_times: Option<PathBuf>,
) -> PyResult<Bound<'py, PyDict>> {
    let stamp = match stamp {
        "header" => StampSource::Header,
        "log" => StampSource::Log,
        w => return Err(usage(format!("stamp `{w}`: expected header or log"))),
    };
    if origin.is_some() {
        // `evaluate(origin=…)`'s check: each number in its range, named as the keyword.
        let p = Parameters {
            origin,
            ..Parameters::default()
        };
        p.validate_as(&|key| key.to_string()).map_err(py_error)?;
    }
    let options = ReadOptions {
        stamp,
        origin,
        text: text_options(text_format, csv, kitti_times)?,
    };
    let r: TrajectoryRead =
        run(py, || trajdrift::read(&sources, topic.as_deref(), &options))?.map_err(py_error)?;
    let d = PyDict::new(py);
    d.set_item("name", &r.name)?;
    d.set_item("source", &r.source)?;
    d.set_item("type_name", &r.type_name)?;
    d.set_item("stamp_seconds", stamp_seconds_word(r.stamp_seconds))?;
    d.set_item(
        "rows",
        serde_json::to_string(&r.rows).map_err(|e| PyValueError::new_err(e.to_string()))?,
    )?;
    d.set_item(
        "rot",
        match r.rotation_matrices {
            Some(m) => {
                let n = m.len();
                let flat: Vec<f64> = m
                    .iter()
                    .flat_map(|r| (0..9).map(move |k| r[(k / 3, k % 3)]))
                    .collect();
                flat.into_pyarray(py).reshape([n, 3, 3])?.into_any()
            }
            None => py.None().into_bound(py),
        },
    )?;
    // What the user must see (a recording cut short): the façade warns with them.
    let warnings: Vec<(&str, &str)> = r
        .warnings
        .iter()
        .map(|w| (w.code.as_str(), w.message.as_str()))
        .collect();
    d.set_item("warnings", warnings)?;
    let (t, xyz, quat) = trajectory_arrays(py, r.trajectory)?;
    d.set_item("t", t)?;
    d.set_item("xyz", xyz)?;
    d.set_item("quat", quat)?;
    Ok(d)
}

/// One input of `evaluate` by reference: a topic or a file, with its name when given.
fn named_input(name: Option<String>, kind: &str, value: String) -> PyResult<NamedInput> {
    let mut input = match kind {
        "topic" => NamedInput::topic(&value),
        "file" => NamedInput::file(&value),
        k => return Err(usage(format!("input kind `{k}`"))),
    };
    if let Some(n) = name {
        input.name = n;
        input.input = match kind {
            "topic" => TrajectoryInput::Topic(value),
            _ => TrajectoryInput::TumFile(PathBuf::from(value)),
        };
    }
    Ok(input)
}

/// `trajdrift.evaluate` on recordings and files: the command line's `eval`, its JSON report, and the
/// notes the command line prints (a preset's estimate absent from the recording, skipped).
#[pyfunction]
#[pyo3(signature = (recordings, reference, estimates, preset=None, parameters_=None, text_format=None, csv=None, kitti_times=None, reference_lever=None, estimate_levers=Vec::new()))]
#[allow(clippy::too_many_arguments)]
fn evaluate(
    py: Python<'_>,
    recordings: Vec<PathBuf>,
    reference: Option<(Option<String>, String, String)>,
    estimates: Vec<(Option<String>, String, String)>,
    preset: Option<String>,
    parameters_: Option<&Bound<'_, PyDict>>,
    text_format: Option<&str>,
    csv: Option<&str>,
    kitti_times: Option<PathBuf>,
    reference_lever: Option<String>,
    estimate_levers: Vec<(Option<String>, String)>,
) -> PyResult<(String, Vec<String>)> {
    let request = EvalRequest {
        recordings,
        reference: reference
            .map(|(n, k, v)| named_input(n, &k, v))
            .transpose()?,
        estimates: estimates
            .into_iter()
            .map(|(n, k, v)| named_input(n, &k, v))
            .collect::<PyResult<_>>()?,
        preset,
        parameters: parameters(parameters_)?,
        text: text_options(text_format, csv, kitti_times)?,
        reference_lever: reference_lever
            .map(|l| LeverSpec::parse("reference_lever", &l))
            .transpose()
            .map_err(py_error)?,
        estimate_levers: estimate_levers
            .into_iter()
            .map(|(n, l)| LeverSpec::parse("estimate_lever", &l).map(|l| (n, l)))
            .collect::<trajdrift::Result<_>>()
            .map_err(py_error)?,
    };
    let (report, notes) = run(py, || {
        let (config, notes) = request.config()?;
        trajdrift::evaluate(&config).map(|report| (report, notes))
    })?
    .map_err(py_error)?;
    Ok((to_json(&report)?, notes))
}

fn to_json<T: serde::Serialize>(v: &T) -> PyResult<String> {
    serde_json::to_string(v).map_err(|e| PyValueError::new_err(e.to_string()))
}

/// One trajectory in memory for the evaluation: name, source, type, stamps, positions, quaternions
/// (`x, y, z, w`) and lever arm.
type TrajIn<'py> = (
    String,
    String,
    String,
    PyReadonlyArray1<'py, i64>,
    PyReadonlyArray2<'py, f64>,
    Option<PyReadonlyArray2<'py, f64>>,
    Option<[f64; 3]>,
);

fn named(t: &TrajIn<'_>) -> PyResult<NamedTrajectory> {
    Ok(NamedTrajectory {
        name: t.0.clone(),
        source: t.1.clone(),
        type_name: t.2.clone(),
        trajectory: trajectory(&t.3, &t.4, &t.5)?,
        lever_m: t.6,
    })
}

/// `trajdrift.evaluate` on trajectories in memory: the same job and report.
#[pyfunction]
#[pyo3(signature = (reference, estimates, parameters_=None))]
fn evaluate_arrays(
    py: Python<'_>,
    reference: TrajIn<'_>,
    estimates: Vec<TrajIn<'_>>,
    parameters_: Option<&Bound<'_, PyDict>>,
) -> PyResult<String> {
    let p = parameters(parameters_)?;
    let reference = named(&reference)?;
    let estimates = estimates.iter().map(named).collect::<PyResult<Vec<_>>>()?;
    let report = run(py, || {
        trajdrift::evaluate_trajectories(reference, estimates, &p)
    })?
    .map_err(py_error)?;
    to_json(&report)
}

type Arrays<'py> = (
    PyReadonlyArray1<'py, i64>,
    PyReadonlyArray2<'py, f64>,
    Option<PyReadonlyArray2<'py, f64>>,
);

/// `trajdrift.time_offset`: the report's `time_offset` object, as JSON.
#[pyfunction]
#[pyo3(signature = (reference, estimate, parameters_=None))]
fn time_offset(
    py: Python<'_>,
    reference: Arrays<'_>,
    estimate: Arrays<'_>,
    parameters_: Option<&Bound<'_, PyDict>>,
) -> PyResult<String> {
    let p = parameters(parameters_)?;
    let r = trajectory(&reference.0, &reference.1, &reference.2)?;
    let e = trajectory(&estimate.0, &estimate.1, &estimate.2)?;
    let o = run(py, || trajdrift::time_offset(&r, &e, &p))?.map_err(py_error)?;
    to_json(&o)
}

/// `trajdrift.drift_error`: the report's `drift_error` list, as JSON.
#[pyfunction]
#[pyo3(signature = (reference, estimate, parameters_=None))]
fn drift_error(
    py: Python<'_>,
    reference: Arrays<'_>,
    estimate: Arrays<'_>,
    parameters_: Option<&Bound<'_, PyDict>>,
) -> PyResult<String> {
    let p = parameters(parameters_)?;
    let r = trajectory(&reference.0, &reference.1, &reference.2)?;
    let e = trajectory(&estimate.0, &estimate.1, &estimate.2)?;
    let d = run(py, || trajdrift::drift_error(&r, &e, &p))?.map_err(py_error)?;
    to_json(&d)
}

/// evo's options of APE/RPE from the façade's keywords (already named as evo names them).
#[derive(FromPyObject)]
struct OptionsIn {
    #[pyo3(item)]
    pose_relation: String,
    #[pyo3(item)]
    align: bool,
    #[pyo3(item)]
    correct_scale: bool,
    #[pyo3(item)]
    n_to_align: Option<i64>,
    #[pyo3(item)]
    align_origin: bool,
    #[pyo3(item)]
    align_yaw: bool,
    #[pyo3(item)]
    t_max_diff: f64,
    #[pyo3(item)]
    t_offset: f64,
    #[pyo3(item)]
    sync_method: String,
    #[pyo3(item)]
    t_start: Option<f64>,
    #[pyo3(item)]
    t_end: Option<f64>,
    #[pyo3(item)]
    project_to_plane: Option<String>,
}

impl OptionsIn {
    fn options(&self) -> PyResult<MetricOptions> {
        let finite = |name: &str, v: f64| {
            if v.is_finite() {
                Ok(v)
            } else {
                Err(usage(format!("{name} {v}: expected a finite number")))
            }
        };
        if !(self.t_max_diff.is_finite() && self.t_max_diff >= 0.0) {
            return Err(usage(format!(
                "t_max_diff {}: expected a finite number of seconds, 0 or more",
                self.t_max_diff
            )));
        }
        if self.align_origin && (self.align || self.align_yaw) {
            return Err(usage(
                "align_origin cannot be combined with align or align_yaw; choose one alignment"
                    .into(),
            ));
        }
        if self.align_yaw && (self.align || self.correct_scale) {
            return Err(usage(
                "align_yaw cannot be combined with align or correct_scale; choose one alignment"
                    .into(),
            ));
        }
        Ok(MetricOptions {
            pose_relation: PoseRelation::parse(&self.pose_relation).map_err(py_error)?,
            align: self.align,
            correct_scale: self.correct_scale,
            // evo's -1 (and any negative) means all poses.
            n_to_align: self.n_to_align.and_then(|n| usize::try_from(n).ok()),
            align_origin: self.align_origin,
            align_yaw: self.align_yaw,
            t_max_diff_s: self.t_max_diff,
            t_offset_s: finite("t_offset", self.t_offset)?,
            sync: match self.sync_method.as_str() {
                "nearest_time" => SyncMethod::NearestTime,
                "interpolation" => SyncMethod::Interpolation,
                w => {
                    return Err(usage(format!(
                        "sync_method `{w}`: expected nearest_time or interpolation"
                    )))
                }
            },
            // evo tests `if t_start or t_end`: 0 means unset.
            t_start_s: self
                .t_start
                .filter(|&t| t != 0.0)
                .map(|t| finite("t_start", t))
                .transpose()?,
            t_end_s: self
                .t_end
                .filter(|&t| t != 0.0)
                .map(|t| finite("t_end", t))
                .transpose()?,
            project_to_plane: match self.project_to_plane.as_deref() {
                None => None,
                Some("xy") => Some(Plane::Xy),
                Some("xz") => Some(Plane::Xz),
                Some("yz") => Some(Plane::Yz),
                Some(w) => {
                    return Err(usage(format!(
                        "project_to_plane `{w}`: expected xy, xz or yz"
                    )))
                }
            },
        })
    }
}

/// A result as the façade takes it: the JSON of `trajdrift ape --json`, and the per-value arrays.
fn standard_result<'py>(py: Python<'py>, r: StandardResult) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("json", to_json(&r.result)?)?;
    d.set_item("error_array", r.result.values.into_pyarray(py))?;
    let opt = |v: Option<Vec<f64>>| -> Bound<'py, PyAny> {
        match v {
            Some(v) => v.into_pyarray(py).into_any(),
            None => py.None().into_bound(py),
        }
    };
    d.set_item("timestamps", opt(r.timestamps))?;
    d.set_item("seconds_from_start", opt(r.seconds_from_start))?;
    d.set_item(
        "distances_from_start",
        r.distances_from_start.into_pyarray(py),
    )?;
    d.set_item("distances", r.distances.into_pyarray(py))?;
    let pairs = match r.pairs {
        Some(p) => {
            let n = p.len();
            let flat: Vec<i64> = p
                .into_iter()
                .flat_map(|(i, j)| [i as i64, j as i64])
                .collect();
            flat.into_pyarray(py).reshape([n, 2])?.into_any()
        }
        None => py.None().into_bound(py),
    };
    d.set_item("pairs", pairs)?;
    Ok(d)
}

/// `trajdrift.ape`.
#[pyfunction]
fn ape<'py>(
    py: Python<'py>,
    reference: PosesIn<'py>,
    estimate: PosesIn<'py>,
    options: OptionsIn,
) -> PyResult<Bound<'py, PyDict>> {
    let o = options.options()?;
    let (r, e) = (reference.poses()?, estimate.poses()?);
    let result = run(py, || trajdrift::ape(r, e, &o))?.map_err(py_error)?;
    standard_result(py, result)
}

/// `trajdrift.rpe`.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
fn rpe<'py>(
    py: Python<'py>,
    reference: PosesIn<'py>,
    estimate: PosesIn<'py>,
    options: OptionsIn,
    delta: f64,
    delta_unit: &str,
    rel_delta_tol: f64,
    all_pairs: bool,
    pairs_from_reference: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let o = options.options()?;
    if !(delta.is_finite() && delta > 0.0) {
        return Err(usage(format!("delta {delta}: expected a number above 0")));
    }
    if !(rel_delta_tol.is_finite() && rel_delta_tol >= 0.0) {
        return Err(usage(format!(
            "rel_delta_tol {rel_delta_tol}: expected a finite number, 0 or more"
        )));
    }
    let pairs = PairSelection {
        delta,
        unit: DeltaUnit::parse(delta_unit).map_err(py_error)?,
        rel_tol: rel_delta_tol,
        all_pairs,
        from_reference: pairs_from_reference,
    };
    let (r, e) = (reference.poses()?, estimate.poses()?);
    let result = run(py, || trajdrift::rpe(r, e, &o, &pairs))?.map_err(py_error)?;
    standard_result(py, result)
}

/// The `trajdrift` command line, in process: `argv` with the program name first; returns the exit code.
/// The interpreter's lock is released while it runs; it writes to the process's stdout and stderr.
#[pyfunction]
fn main(py: Python<'_>, argv: Vec<OsString>) -> PyResult<u8> {
    run(py, || trajdrift::main_with_args(argv))
}

/// The extension module.
#[pymodule]
fn _trajdrift(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(read, m)?)?;
    m.add_function(wrap_pyfunction!(evaluate, m)?)?;
    m.add_function(wrap_pyfunction!(evaluate_arrays, m)?)?;
    m.add_function(wrap_pyfunction!(time_offset, m)?)?;
    m.add_function(wrap_pyfunction!(drift_error, m)?)?;
    m.add_function(wrap_pyfunction!(ape, m)?)?;
    m.add_function(wrap_pyfunction!(rpe, m)?)?;
    m.add_function(wrap_pyfunction!(parameter_specs, m)?)?;
    m.add_function(wrap_pyfunction!(check_parameters, m)?)?;
    m.add_function(wrap_pyfunction!(main, m)?)?;
    Ok(())
}
