"""Arguments from Python: every wrong one is a trajdrift error naming it (never an IndexError, an
extraction failure of the native layer, a wrapped integer, a keyword silently ignored), and what the
library learns while reading (a truncated recording) reaches the caller."""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest

import trajdrift
from conftest import FIXTURE

REF, EST = "/reference/position", "/estimate/odom"


@pytest.fixture(scope="module")
def ref():
    return trajdrift.read(FIXTURE, REF)


@pytest.fixture(scope="module")
def est():
    return trajdrift.read(FIXTURE, EST)


def test_the_exceptions_are_named_as_the_package_exports_them():
    for cls in (trajdrift.Error, trajdrift.UsageError, trajdrift.InputError, trajdrift.MetricError):
        assert cls.__module__ == "trajdrift" and getattr(trajdrift, cls.__name__) is cls
    assert issubclass(trajdrift.UsageError, ValueError) and issubclass(trajdrift.UsageError, TypeError)


def test_keywords_of_the_evaluation_under_another_name_are_refused(ref, est):
    with pytest.raises(trajdrift.UsageError, match=r"method=, not offset_method="):
        trajdrift.time_offset(ref, est, offset_method="curvature")
    with pytest.raises(trajdrift.UsageError, match=r"model=, not offset_model="):
        trajdrift.time_offset(ref, est, offset_model="linear")
    with pytest.raises(trajdrift.UsageError, match=r"window_m=, not window="):
        trajdrift.drift_error(ref, est, window=10)
    # The right keywords work.
    assert trajdrift.time_offset(ref, est, method="curvature").method == "curvature"
    assert trajdrift.drift_error(ref, est, window_m=10).window_m == 10
    with pytest.raises(trajdrift.UsageError, match="did you mean 'window'"):
        trajdrift.evaluate(FIXTURE, REF, EST, windw=5)


def test_stamps_beyond_int64_nanoseconds_are_refused():
    xyz = np.zeros((2, 3))
    # Nanoseconds held as float: float stamps are seconds.
    with pytest.raises(trajdrift.UsageError, match="float stamps are seconds.*int64"):
        trajdrift.Trajectory.from_arrays(np.array([1.718e18, 1.7180000001e18]), xyz)
    with pytest.raises(trajdrift.UsageError, match="beyond int64 nanoseconds"):
        trajdrift.Trajectory(np.array([2**63 + 5, 2**63 + 6], dtype=np.uint64), xyz)
    with pytest.raises(trajdrift.UsageError, match="int64 nanoseconds"):
        trajdrift.Trajectory(np.array([2**70, 2**70 + 1], dtype=object), xyz)
    with pytest.raises(trajdrift.UsageError, match="finite"):
        trajdrift.Trajectory.from_arrays(np.array([0.0, np.nan]), xyz)
    # What fits is kept exactly.
    ok = trajdrift.Trajectory(np.array([2**63 - 2, 2**63 - 1], dtype=np.uint64), xyz)
    assert ok.t.tolist() == [2**63 - 2, 2**63 - 1]
    assert trajdrift.Trajectory.from_arrays(np.array([9.1e9, 9.1e9 + 1]), xyz).t[0] == 9_100_000_000 * 10**9


def test_read_checks_origin_as_evaluate_does():
    with pytest.raises(trajdrift.UsageError) as e:
        trajdrift.evaluate(FIXTURE, REF, EST, origin=(91, 8, 400))
    assert "latitude 91: out of range" in str(e.value)
    for origin, what in [((100, 8, 400), "latitude 100"), ((float("nan"), 8, 400), "latitude NaN"),
                         ((47, 200, 400), "longitude 200")]:
        with pytest.raises(trajdrift.UsageError, match=f"origin {what}: out of range"):
            trajdrift.read(FIXTURE, "/reference/position", origin=origin)
    with pytest.raises(trajdrift.UsageError, match="origin takes three numbers"):
        trajdrift.read(FIXTURE, "/reference/position", origin=(47, 8))
    with pytest.raises(trajdrift.UsageError, match="origin takes three numbers"):
        trajdrift.read(FIXTURE, "/reference/position", origin="47,8,400")


def test_read_warns_of_a_truncated_recording(tmp_path):
    data = FIXTURE.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) // 2])
    with pytest.warns(UserWarning, match="cut short at byte"):
        part = trajdrift.read(cut, EST)
    assert 0 < len(part) < len(trajdrift.read(FIXTURE, EST))
    report = trajdrift.evaluate(cut, REF, EST)
    assert "truncated_recording" in [w["code"] for w in report.warnings]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        trajdrift.read(FIXTURE, EST)  # a whole recording: no warning


def test_wrong_arguments_are_usage_errors_naming_them(ref, est):
    cases = [
        (lambda: trajdrift.read(None), "source"),
        (lambda: trajdrift.read(42), "source"),
        (lambda: trajdrift.read([]), "source is empty"),
        (lambda: trajdrift.read(FIXTURE, 5), "topic"),
        (lambda: trajdrift.evaluate(42, REF, EST), "recording"),
        (lambda: trajdrift.evaluate(reference=ref, estimates=42), r"estimates\[0\]"),
        (lambda: trajdrift.Trajectory.from_arrays([1, 2], np.zeros((2, 3)), np.zeros((2, 3)), quat_order="wxyz"),
         r"quat must be \(N, 4\)"),
        (lambda: trajdrift.Trajectory.from_arrays([1, 2], np.zeros((2, 3)), quat_order="zyxw"), "quat_order"),
        (lambda: trajdrift.ape(ref, est, n_to_align=1.5), "n_to_align"),
        (lambda: trajdrift.ape(ref, est, t_max_diff=None), "t_max_diff"),
        (lambda: trajdrift.ape(ref, "not a trajectory"), "estimate"),
    ]
    for call, what in cases:
        with pytest.raises(trajdrift.UsageError, match=what):
            call()
    # evo's n_to_align beyond any length: all pairs, as a large count.
    a = trajdrift.ape(ref, est, t_offset=0.2, t_max_diff=0.05, n_to_align=10**6)
    b = trajdrift.ape(ref, est, t_offset=0.2, t_max_diff=0.05, n_to_align=2**70)
    assert a.to_dict() == b.to_dict()


def test_arrays_reassigned_after_construction_are_checked_again(ref, est):
    e = trajdrift.Trajectory(est.t, est.xyz.copy(), est.quat)
    e.xyz = e.xyz.astype(np.float32)  # another dtype: converted
    assert trajdrift.time_offset(ref, e).offset_s == pytest.approx(trajdrift.time_offset(ref, est).offset_s, abs=1e-3)
    e.xyz = e.xyz[:, :2]
    with pytest.raises(trajdrift.UsageError, match=r"estimate: t must be \(N,\) and xyz \(N, 3\)"):
        trajdrift.time_offset(ref, e)
    with pytest.raises(trajdrift.UsageError, match=r"estimate: t must be \(N,\) and xyz \(N, 3\)"):
        trajdrift.ape(ref, e)


def test_levers_in_memory_are_checked_as_on_the_recording_path(ref, est):
    for lever in [(0, 5000, 0), (0, float("nan"), 0)]:
        with pytest.raises(trajdrift.UsageError, match="out of range"):
            trajdrift.evaluate(FIXTURE, REF, {"lio": EST}, estimate_lever=lever)
        with pytest.raises(trajdrift.UsageError, match="out of range"):
            trajdrift.evaluate(reference=ref, estimates={"lio": est}, estimate_lever=lever)
        with pytest.raises(trajdrift.UsageError, match="out of range"):
            trajdrift.evaluate(reference=ref, estimates={"lio": est}, reference_lever=lever)
    with pytest.raises(trajdrift.UsageError, match="names `LIO`, which is no estimate"):
        trajdrift.evaluate(FIXTURE, REF, {"lio": EST}, estimate_lever={"LIO": (0, 0.5, 0)})
    with pytest.raises(trajdrift.UsageError, match="names 'LIO', which is no estimate; estimates: lio"):
        trajdrift.evaluate(reference=ref, estimates={"lio": est}, estimate_lever={"LIO": (0, 0.5, 0)})
    with pytest.raises(trajdrift.UsageError, match=r"takes \(x, y, z\)"):
        trajdrift.evaluate(reference=ref, estimates={"lio": est}, estimate_lever=(0, 0.5))


def test_non_finite_positions_are_refused_with_their_row():
    n = 200
    t = np.arange(n, dtype=np.int64) * 100_000_000 + 1_700_000_000_000_000_000
    s = np.linspace(0, 6 * np.pi, n)
    xyz = np.c_[10 * np.cos(s), 5 * np.sin(2 * s), np.zeros(n)]
    r = trajdrift.Trajectory(t, xyz)
    bad = xyz.copy()
    bad[3] = np.nan
    e = trajdrift.Trajectory(t, bad)
    for call in (lambda: trajdrift.ape(r, e, align=False), lambda: trajdrift.ape(r, e),
                 lambda: trajdrift.rpe(r, e, pose_relation="point_distance")):
        with pytest.raises(trajdrift.UsageError, match=re.escape("estimate: position of row 3 is not finite")):
            call()
    evo_like = type("Evo", (), {"timestamps": t / 1e9, "positions_xyz": bad, "orientations_quat_wxyz": None})()
    with pytest.raises(trajdrift.UsageError, match="estimate: position of row 3"):
        trajdrift.ape(r, evo_like)


def test_objects_that_are_no_evo_trajectory_are_usage_errors(ref):
    with pytest.raises(trajdrift.UsageError, match="from_evo: expected an evo trajectory"):
        trajdrift.Trajectory.from_evo(42)
    n = len(ref)
    bad_quat = type("Evo", (), {"timestamps": ref.timestamps, "positions_xyz": ref.xyz,
                                "orientations_quat_wxyz": np.zeros((n, 3))})()
    with pytest.raises(trajdrift.UsageError, match=r"orientations_quat_wxyz must be \(N, 4\)"):
        trajdrift.ape(ref, bad_quat)
    bad_ts = type("Evo", (), {"timestamps": ref.timestamps.reshape(-1, 1), "positions_xyz": ref.xyz,
                              "orientations_quat_wxyz": None})()
    with pytest.raises(trajdrift.UsageError, match=r"estimate: timestamps must be \(N,\)"):
        trajdrift.ape(ref, bad_ts)


def test_drift_errors_membership_of_any_key():
    rep = trajdrift.evaluate(FIXTURE, REF, {"lio": EST}, metrics="de")
    de = rep.estimates["lio"].drift_error
    assert 5 in de and 7 not in de and None not in de and "abc" not in de
    with pytest.raises(KeyError, match="no Drift Error at 7 m"):
        de[7]


def test_a_missing_reference_or_estimate_is_named_as_python_writes_it():
    for call, what in [(lambda: trajdrift.evaluate(FIXTURE), r"evaluate\(\): give the reference"),
                       (lambda: trajdrift.evaluate(FIXTURE, REF), r"evaluate\(\): give at least one estimate"),
                       (lambda: trajdrift.evaluate(FIXTURE, REF, {}), "estimates="),
                       (lambda: trajdrift.evaluate(), "give the reference")]:
        with pytest.raises(trajdrift.UsageError, match=what) as e:
            call()
        assert "--" not in str(e.value)
