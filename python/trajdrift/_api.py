"""trajdrift's functions: read, evaluate, time_offset, drift_error, ape, rpe."""

from __future__ import annotations

import difflib
import json
import math
import operator
import os
import warnings
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union, overload

from . import _trajdrift
from ._errors import UsageError
from ._report import DriftError, MetricResult, Report, TimeOffset
from ._trajectory import Trajectory, arrays, as_trajectory, poses

__all__ = ["read", "evaluate", "time_offset", "drift_error", "ape", "rpe", "PARAMETERS"]

PathLike = Union[str, "os.PathLike[str]"]

#: Every evaluation parameter of :func:`evaluate` (the command line's ``eval`` flags, ``-`` written
#: ``_``): key → its flag, help, default, range and accepted words. One table in the Rust library
#: defines them; this is a read-only view of it.
PARAMETERS: Dict[str, Dict[str, Any]] = {s["key"]: s for s in _trajdrift.parameter_specs()}


def _check_keys(parameters: Mapping[str, Any], function: str) -> Dict[str, Any]:
    """The parameters, their keys checked against the table (a ``-`` is read as ``_``)."""
    out = {}
    for key, value in parameters.items():
        k = key.replace("-", "_")
        if k not in PARAMETERS:
            close = difflib.get_close_matches(k, PARAMETERS, n=1)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            raise UsageError(
                f"{function}() got an unexpected keyword argument {key!r}{hint} "
                f"(parameters: {', '.join(PARAMETERS)})"
            )
        out[k] = value
    return out


def _parameters_doc() -> str:
    lines = ["", "Evaluation parameters (keyword arguments; the command line's flags, ``-`` written ``_``):", ""]
    for key, s in PARAMETERS.items():
        words = f" One of: {', '.join(s['words'])}." if s["words"] else ""
        rng = f" Range {s['range']}." if s["range"] else ""
        lines.append(f"    {key} ({s['value_name']}): {s['help']}{words}{rng} Default: {s['default']}.")
    return "\n".join(lines)


def read(
    source: Union[PathLike, Sequence[PathLike]],
    topic: Optional[str] = None,
    *,
    stamp: str = "header",
    origin: Optional[Sequence[float]] = None,
    text_format: Optional[str] = None,
    csv: Optional[str] = None,
    kitti_times: Optional[PathLike] = None,
) -> Trajectory:
    """Reads one trajectory from anything the command line reads.

    - ``read("mission.mcap", "/odom")``: a topic of an MCAP file, a ROS 1 bag or a rosbag2 folder; a
      ``/tf:PARENT:CHILD`` chain composes the TF tree. ``source`` may also be the files of one mission
      (a list) or a folder of them.
    - ``read("gt.tum")``: a text file, TUM, KITTI (``kitti_times=`` its times.txt), EuRoC's ground-truth
      CSV or a CSV (``csv="t=stamp:us,x=px,y=py,z=pz"`` maps its columns); ``text_format`` forces one.

    ``stamp``: ``"header"`` (when the sensor measured) or ``"log"`` (when the recorder received it).
    ``origin``: the ENU origin (lat, lon, h) of NavSatFix topics. A recording's samples are sorted by
    stamp and a repeated stamp dropped (``Trajectory.rows`` counts them); a TUM file's rows are kept as
    written, as evo reads them (the evaluation sorts them itself). A recording is streamed once; the
    arrays are the library's, without a copy. Raises :class:`trajdrift.InputError` with the command line's message.
    A recording cut short (the recorder stopped abruptly) is read up to its last complete record, with a
    ``UserWarning`` that says so (the ``truncated_recording`` warning of :func:`evaluate`'s report).
    """
    sources = _paths(source, "read(): source")
    if not sources:
        raise UsageError("read(): source is empty; give a recording, the files of a mission or a text trajectory file")
    if topic is not None and not isinstance(topic, str):
        raise UsageError(f"read(): topic must be a string such as '/odom' or '/tf:odom:base_link'; got {type(topic).__name__}")
    for name, v in (("stamp", stamp), ("text_format", text_format), ("csv", csv)):
        if v is not None and not isinstance(v, str):
            raise UsageError(f"read(): {name} must be a string; got {type(v).__name__}")
    d = _trajdrift.read(
        sources,
        topic,
        stamp,
        None if origin is None else _origin(origin),
        text_format,
        csv,
        None if kitti_times is None else _path(kitti_times, "read(): kitti_times"),
    )
    for _code, message in d.pop("warnings"):
        warnings.warn(message, UserWarning, stacklevel=2)
    return Trajectory._from_native(d)


def _origin(origin: Any) -> List[float]:
    """``origin`` as three numbers (their ranges are checked by the library, as ``evaluate``'s)."""
    try:
        values = [float(x) for x in origin]
    except (TypeError, ValueError):
        values = []
    if len(values) != 3 or isinstance(origin, str):
        raise UsageError(f"read(): origin takes three numbers (latitude °, longitude °, height m); got {origin!r}")
    return values


def _lever(v: Any, what: str = "estimate_lever") -> str:
    if isinstance(v, str):
        return v
    return ",".join(repr(x) for x in _lever_xyz(v, what))


#: The range of a lever's components, metres (the library's, for `--reference-lever`/`--estimate-lever`).
_LEVER_M = 1000.0


def _lever_xyz(v: Any, what: str) -> List[float]:
    """A lever ``(x, y, z)`` in metres, checked as the recording path checks it: three finite numbers
    within ±1000 m."""
    try:
        xs = [float(x) for x in v]
    except (TypeError, ValueError):
        xs = []
    if len(xs) != 3:
        raise UsageError(f"{what} takes (x, y, z) metres or 'tf-static:[BODY:]FRAME', got {v!r}")
    for x in xs:
        if not (math.isfinite(x) and -_LEVER_M <= x <= _LEVER_M):
            raise UsageError(
                f"{what} {x}: out of range; expected a finite value in [-{_LEVER_M:g}, {_LEVER_M:g}] m"
            )
    return xs


def _is_input(obj: Any) -> bool:
    return isinstance(obj, (str, os.PathLike))


def _named_estimates(estimates: Any) -> List[Tuple[Optional[str], Any]]:
    if estimates is None:
        return []
    if isinstance(estimates, Mapping):
        return [(str(k), v) for k, v in estimates.items()]
    if _is_input(estimates) or not isinstance(estimates, Sequence):
        estimates = [estimates]
    return [(None, e) for e in estimates]


def evaluate(
    recording: Union[PathLike, Sequence[PathLike], None] = None,
    reference: Any = None,
    estimates: Any = None,
    *,
    preset: Optional[str] = None,
    reference_lever: Any = None,
    estimate_lever: Any = None,
    text_format: Optional[str] = None,
    csv: Optional[str] = None,
    kitti_times: Optional[PathLike] = None,
    **parameters: Any,
) -> Report:
    """Evaluates estimates against a reference: each estimate's clock offset, its Drift Error at every
    window size and evo's APE/RPE — what ``trajdrift eval`` computes, with the same parameters, checks
    and numbers. ``Report.to_dict()`` equals ``trajdrift eval --json``'s report.

    - ``recording``: a recording (MCAP, ROS 1 bag, rosbag2 folder), the files of one mission (a list)
      or a folder of them; ``None`` when the inputs are files or trajectories.
    - ``reference``: with a recording, a topic (or ``/tf:PARENT:CHILD``); without, a text file; or a
      :class:`Trajectory` / evo trajectory in memory. ``None`` with a ``preset``: the preset's.
    - ``estimates``: the same kinds, one, a list (named by topic or file stem; ``"lio=/odom"`` names a
      topic) or a dict ``{name: input}``.
    - ``preset``: ``grandtour``, ``grandtour-prism``, ``fomo`` or a preset file: its topics and
      parameters (under the ones given here).
    - ``reference_lever`` / ``estimate_lever``: the sensors' positions in the body frame, ``(x, y, z)``
      metres or ``"tf-static:[BODY:]FRAME"``; ``estimate_lever`` may be a dict by estimate name.
    - ``text_format``, ``csv``, ``kitti_times``: how text files are read (see :func:`read`).

    A bad parameter value raises :class:`trajdrift.UsageError` (also a ``ValueError``) with the command
    line's message; an unknown parameter too (a ``UsageError`` that is also a ``TypeError``). Warnings are in ``Report.warnings``; a
    preset's estimate absent from the recording is skipped with a ``UserWarning`` (the command line's
    ``note:``).
    """
    params = _check_keys(parameters, "evaluate")
    named = _named_estimates(estimates)
    if preset is None and reference is None:
        raise UsageError(
            "evaluate(): give the reference (a topic of the recording, a text file or a Trajectory) or a preset"
        )
    if preset is None and not named:
        raise UsageError(
            "evaluate(): give at least one estimate (estimates=: a topic, a file, a Trajectory, a list or a dict)"
        )
    in_memory = not _is_input(reference) and reference is not None
    in_memory = in_memory or any(not _is_input(e) for _, e in named)
    if not in_memory:
        recordings = _paths(recording)
        kind = "topic" if recordings else "file"
        levers: List[Tuple[Optional[str], str]] = []
        if isinstance(estimate_lever, Mapping):
            levers = [(str(k), _lever(v, f"estimate_lever[{k!r}]")) for k, v in estimate_lever.items()]
        elif estimate_lever is not None:
            levers = [(None, _lever(estimate_lever))]
        text, notes = _trajdrift.evaluate(
            recordings,
            None if reference is None else (None, kind, os.fspath(reference)),
            [(n, kind, os.fspath(e)) for n, e in named],
            preset,
            params,
            text_format,
            csv,
            None if kitti_times is None else _path(kitti_times, "evaluate(): kitti_times"),
            None if reference_lever is None else _lever(reference_lever, "reference_lever"),
            levers,
        )
        # What the command line prints as `note:` (a preset's estimate absent from the recording).
        for note in notes:
            warnings.warn(note, stacklevel=2)
        return Report(json.loads(text))
    if preset is not None:
        raise UsageError("preset picks topics of a recording; it does not apply to trajectories in memory")
    if reference is None:
        raise UsageError("evaluate(): give the reference")

    def load(obj: Any, what: str) -> Trajectory:
        if _is_input(obj):
            return read(recording if recording is not None else obj,
                        os.fspath(obj) if recording is not None else None,
                        text_format=text_format, csv=csv, kitti_times=kitti_times)
        return as_trajectory(obj, what)

    def lever_in_memory(v: Any, what: str) -> Optional[List[float]]:
        if v is None:
            return None
        if isinstance(v, str):
            raise UsageError(f"{what}: a tf-static: lever needs the recording; give (x, y, z) for trajectories in memory")
        return _lever_xyz(v, what)

    def lever_of(name: str) -> Optional[List[float]]:
        if isinstance(estimate_lever, Mapping):
            return lever_in_memory(estimate_lever.get(name), f"estimate_lever[{name!r}]")
        return lever_in_memory(estimate_lever, "estimate_lever")

    ref = load(reference, "reference")
    ref_t, ref_xyz, ref_quat = arrays(ref, "reference")
    ests = []
    for i, (name, e) in enumerate(named):
        what = f"estimates[{name!r}]" if name is not None else f"estimates[{i}]"
        tr = load(e, what)
        label = name or tr.name or f"estimate{i + 1}"
        t, xyz, quat = arrays(tr, what)
        ests.append((label, tr.source, tr.type_name, t, xyz, quat, lever_of(label)))
    if isinstance(estimate_lever, Mapping):
        labels = [e[0] for e in ests]
        for k in estimate_lever:
            if str(k) not in labels:
                raise UsageError(
                    f"estimate_lever names {str(k)!r}, which is no estimate; estimates: {', '.join(labels)}"
                )
    ref_lever = lever_in_memory(reference_lever, "reference_lever")
    text = _trajdrift.evaluate_arrays(
        (ref.name or "reference", ref.source, ref.type_name, ref_t, ref_xyz, ref_quat, ref_lever),
        ests,
        params,
    )
    return Report(json.loads(text))


def _path(p: Any, what: str) -> str:
    if isinstance(p, bytes):
        return os.fsdecode(p)
    if not _is_input(p):
        raise UsageError(f"{what} must be a path (str or os.PathLike); got {type(p).__name__}")
    return os.fsdecode(os.fspath(p))


def _paths(recording: Any, what: str = "evaluate(): recording") -> List[str]:
    """A path or a list of paths (the files of one mission), as strings."""
    if recording is None:
        return []
    if _is_input(recording) or isinstance(recording, bytes):
        return [_path(recording, what)]
    if not isinstance(recording, Sequence):
        raise UsageError(
            f"{what} must be a path (str or os.PathLike) or a list of paths; got {type(recording).__name__}"
        )
    return [_path(r, f"{what}[{i}]") for i, r in enumerate(recording)]


def time_offset(
    reference: Any,
    estimate: Any,
    method: str = "auto",
    model: str = "auto",
    **parameters: Any,
) -> TimeOffset:
    """The clock offset of ``estimate`` against ``reference`` (``t_est + offset_s`` is the reference's
    clock), found as ``trajdrift eval`` finds it from the shape of the two paths: ``method`` ``auto``
    (speed and curvature profiles combined), ``speed``, ``signed-curvature`` or ``curvature``;
    ``model`` ``auto`` (constant unless the data refute it), ``constant``, ``linear`` (a clock drift) or
    ``piecewise`` (steps). Other evaluation parameters (``max_offset``, ``grid``, …) as in
    :func:`evaluate`. Returns ``offset_s``, ``sigma_s``, ``model``, ``status`` and every method's
    answer."""
    params = _check_keys(parameters, "time_offset")
    for key, keyword in (("offset_method", "method"), ("offset_model", "model")):
        if key in params:
            raise UsageError(
                f"time_offset() takes the {keyword} as {keyword}=, not {key}= (e.g. "
                f"time_offset(ref, est, {keyword}={params[key]!r}))"
            )
    params.update(offset_method=method, offset_model=model)
    text = _trajdrift.time_offset(arrays(reference, "reference"), arrays(estimate, "estimate"), params)
    return TimeOffset(json.loads(text))


@overload
def drift_error(reference: Any, estimate: Any, window_m: float = 5, **parameters: Any) -> DriftError: ...
@overload
def drift_error(reference: Any, estimate: Any, window_m: Sequence[float], **parameters: Any) -> Dict[float, DriftError]: ...
def drift_error(reference: Any, estimate: Any, window_m: Any = 5, **parameters: Any) -> Any:
    """The Drift Error of ``estimate`` against ``reference`` over windows of ``window_m`` metres of the
    reference's path, DE = |1 − α·Δs_est/Δs_ref|, after the clock offset (searched as in
    :func:`time_offset`, or ``time_offset=`` seconds). A list of window sizes gives a dict by size.
    Other parameters (``lever_correction``, ``overlap``, ``curvature_eps``, …) as in
    :func:`evaluate`."""
    params = _check_keys(parameters, "drift_error")
    if "window" in params:
        raise UsageError(
            f"drift_error() takes the window sizes as window_m=, not window= (e.g. "
            f"drift_error(ref, est, window_m={params['window']!r}))"
        )
    params["window"] = window_m
    text = _trajdrift.drift_error(arrays(reference, "reference"), arrays(estimate, "estimate"), params)
    results = [DriftError(d) for d in json.loads(text)]
    if isinstance(window_m, (int, float)):
        return results[0]
    return {r.window_m: r for r in results}


_RELATIONS = {
    "translation part": "trans_part",
    "rotation part": "rot_part",
    "full transformation": "full",
    "rotation angle in degrees": "angle_deg",
    "rotation angle in radians": "angle_rad",
    "point distance": "point_distance",
    "point distance error ratio": "point_distance_error_ratio",
    "translation_part": "trans_part",
    "rotation_part": "rot_part",
    "full_transformation": "full",
    "rotation_angle_deg": "angle_deg",
    "rotation_angle_rad": "angle_rad",
}

_UNITS = {"frames": "f", "meters": "m", "metres": "m", "degrees": "d", "radians": "r", "deg": "d", "rad": "r"}


def _word(v: Any, table: Dict[str, str]) -> str:
    """A string, or an evo enum member (its value or name), in the command line's word."""
    for w in (getattr(v, "value", None), getattr(v, "name", None), v):
        if isinstance(w, str):
            return table.get(w, w)
    return str(v)


def _options(
    pose_relation: Any,
    align: bool,
    correct_scale: bool,
    n_to_align: int,
    align_origin: bool,
    align_yaw: bool,
    t_max_diff: float,
    t_offset: float,
    sync_method: str,
    t_start: Optional[float],
    t_end: Optional[float],
    project_to_plane: Optional[str],
) -> Dict[str, Any]:
    plane = getattr(project_to_plane, "value", project_to_plane)
    return {
        "pose_relation": _word(pose_relation, _RELATIONS),
        "align": bool(align),
        "correct_scale": bool(correct_scale),
        "n_to_align": None if n_to_align is None else _n_to_align(n_to_align),
        "align_origin": bool(align_origin),
        "align_yaw": bool(align_yaw),
        "t_max_diff": _number(t_max_diff, "t_max_diff"),
        "t_offset": _number(t_offset, "t_offset"),
        "sync_method": str(sync_method),
        "t_start": None if t_start is None else _number(t_start, "t_start"),
        "t_end": None if t_end is None else _number(t_end, "t_end"),
        "project_to_plane": None if plane is None else str(plane),
    }


def _number(v: Any, name: str) -> float:
    try:
        return float(v)
    except (TypeError, ValueError):
        raise UsageError(f"{name} {v!r}: expected a number") from None


def _n_to_align(n: Any) -> int:
    """evo's ``n_to_align``: a whole number of poses (-1 or any negative: all)."""
    try:
        n = operator.index(n)
    except TypeError:
        raise UsageError(f"n_to_align {n!r}: expected a whole number of poses (-1: all)") from None
    # Beyond every trajectory's length means all of them, as a large count does.
    return max(min(n, 2**63 - 1), -1)


def _result(d: Dict[str, Any]) -> MetricResult:
    return MetricResult(json.loads(d.pop("json")), d)


def ape(
    reference: Any,
    estimate: Any,
    *,
    align: bool = True,
    correct_scale: bool = False,
    pose_relation: Any = "trans_part",
    t_max_diff: float = 0.01,
    t_offset: float = 0.0,
    n_to_align: int = -1,
    align_origin: bool = False,
    align_yaw: bool = False,
    sync_method: str = "nearest_time",
    t_start: Optional[float] = None,
    t_end: Optional[float] = None,
    project_to_plane: Optional[str] = None,
) -> MetricResult:
    """evo's absolute pose error, with evo's options and numbers (equal to ``evo_ape`` to its printed
    decimals): associate by time (for each stamp of the shorter trajectory the nearest of the other
    within ``t_max_diff`` seconds, after adding ``t_offset`` to the estimate's), align (``align``:
    Umeyama SE(3); with ``correct_scale``: Sim(3); ``correct_scale`` alone: the scale; ``n_to_align``
    first pairs only; ``align_origin``: first pose onto first pose; ``align_yaw``: yaw + translation,
    not in evo), then ``E_i = P_est,i⁻¹·P_ref,i`` reduced by ``pose_relation``: ``trans_part``,
    ``rot_part``, ``full``, ``angle_deg``, ``angle_rad``, ``point_distance`` (or evo's
    ``PoseRelation`` members).

    Unlike evo (whose default is no alignment), ``align`` defaults to ``True``: the APE of an
    unaligned odometry measures its starting frame, not its error; pass ``align=False`` for evo's
    default. ``sync_method="interpolation"`` resamples the longer trajectory at the matched stamps;
    ``t_start``/``t_end`` crop the reference (its own seconds); ``project_to_plane``: ``xy``, ``xz``,
    ``yz``.

    ``reference`` and ``estimate``: :class:`Trajectory` or evo trajectories (their own float stamps and
    matrices are used as they are). Returns a :class:`MetricResult`: ``stats`` (rmse, mean, median,
    std, min, max, sse), ``error_array`` and evo's ``np_arrays``.
    """
    d = _trajdrift.ape(
        poses(reference, "reference"),
        poses(estimate, "estimate"),
        _options(pose_relation, align, correct_scale, n_to_align, align_origin, align_yaw,
                 t_max_diff, t_offset, sync_method, t_start, t_end, project_to_plane),
    )
    return _result(d)


def rpe(
    reference: Any,
    estimate: Any,
    *,
    delta: float = 1,
    delta_unit: Any = "m",
    all_pairs: bool = False,
    rel_delta_tol: float = 0.1,
    pairs_from_reference: bool = False,
    align: bool = True,
    correct_scale: bool = False,
    pose_relation: Any = "trans_part",
    t_max_diff: float = 0.01,
    t_offset: float = 0.0,
    n_to_align: int = -1,
    align_origin: bool = False,
    align_yaw: bool = False,
    sync_method: str = "nearest_time",
    t_start: Optional[float] = None,
    t_end: Optional[float] = None,
    project_to_plane: Optional[str] = None,
) -> MetricResult:
    """evo's relative pose error, with evo's options and numbers (equal to ``evo_rpe`` to its printed
    decimals). Pose pairs ``(i, j)`` are chosen on the estimate (``pairs_from_reference``: on the
    reference) every ``delta`` ``delta_unit``: ``m`` metres of path (the default here; evo's is
    frames), ``f`` frames, ``d`` degrees or ``r`` radians of rotation (or evo's ``Unit`` members);
    consecutive pairs restart the accumulated length after each pair, ``all_pairs`` takes every pair at
    the delta within ``rel_delta_tol``. Per pair ``E = (Q_i⁻¹Q_j)⁻¹(P_i⁻¹P_j)`` reduced by
    ``pose_relation``, plus ``point_distance`` (|‖q_i − q_j‖ − ‖p_i − p_j‖, positions only) and
    ``point_distance_error_ratio`` (that over ‖q_i − q_j‖, percent).

    Association and alignment as in :func:`ape` (``align`` defaults to ``True``). Returns a
    :class:`MetricResult` with ``pairs``, the (i, j) indices of each value.
    """
    d = _trajdrift.rpe(
        poses(reference, "reference"),
        poses(estimate, "estimate"),
        _options(pose_relation, align, correct_scale, n_to_align, align_origin, align_yaw,
                 t_max_diff, t_offset, sync_method, t_start, t_end, project_to_plane),
        _number(delta, "delta"),
        _word(delta_unit, _UNITS),
        _number(rel_delta_tol, "rel_delta_tol"),
        bool(all_pairs),
        bool(pairs_from_reference),
    )
    return _result(d)


evaluate.__doc__ = (evaluate.__doc__ or "") + _parameters_doc()
