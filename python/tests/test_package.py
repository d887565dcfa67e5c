"""The package itself: the command in the wheel, help() and the typing files, Trajectory's
conversions, and the interpreter's lock released during long work."""

from __future__ import annotations

import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import trajdrift
from conftest import FIXTURE, run_cli


def test_the_command_is_the_command_line():
    r = run_cli("--version")
    assert r.returncode == 0 and r.stdout.strip() == f"trajdrift {trajdrift.__version__}"
    r = subprocess.run([sys.executable, "-m", "trajdrift", "--version"], capture_output=True, text=True)
    assert r.returncode == 0 and r.stdout.startswith("trajdrift ")
    r = run_cli("eval", str(FIXTURE), "--reference", "/reference/position", "--estimate",
                "/estimate/odom", "--grid", "1e-9")
    assert r.returncode == 2 and "--grid 1e-9: out of range" in r.stderr
    r = run_cli("nonsense")
    assert r.returncode == 2


def test_typed_and_documented():
    pkg = Path(trajdrift.__file__).parent
    assert (pkg / "py.typed").is_file() and (pkg / "_trajdrift.pyi").is_file()
    doc = trajdrift.evaluate.__doc__
    for key in trajdrift.PARAMETERS:  # every parameter of the table, in help(trajdrift.evaluate)
        assert f"    {key} (" in doc, key
    assert "Default: 30" in doc  # max_offset's default, from the table
    for f in (trajdrift.read, trajdrift.time_offset, trajdrift.drift_error, trajdrift.ape, trajdrift.rpe,
              trajdrift.Trajectory, trajdrift.Trajectory.from_arrays, trajdrift.Report):
        assert f.__doc__ and len(f.__doc__) > 80, f


def test_from_arrays_seconds_nanoseconds_and_quaternion_order():
    t_s = np.array([1718460000.1, 1718460000.2, 1718460000.3])
    xyz = np.arange(9.0).reshape(3, 3)
    q_wxyz = np.tile([1.0, 0.0, 0.0, 0.0], (3, 1))
    a = trajdrift.Trajectory.from_arrays(t_s, xyz, q_wxyz, quat_order="wxyz")
    assert a.t.tolist() == [1718460000100000000, 1718460000200000000, 1718460000300000000]
    assert a.quat[0].tolist() == [0.0, 0.0, 0.0, 1.0]
    assert np.array_equal(a.timestamps, t_s)
    b = trajdrift.Trajectory.from_arrays(a.t, xyz)
    assert b.t is a.t and b.xyz is not None and b.quat is None  # int64 contiguous: no copy
    with pytest.raises(ValueError, match=r"xyz \(N, 3\)"):
        trajdrift.Trajectory(a.t, xyz[:2])
    with pytest.raises(TypeError, match="trajdrift.Trajectory or an evo trajectory"):
        trajdrift.ape(a, "not a trajectory")


def test_long_work_releases_the_interpreter_lock():
    n = 400_000
    t = np.arange(n, dtype=np.int64) * 10_000_000
    s = np.linspace(0, 40 * np.pi, n)
    xyz = np.c_[50 * np.cos(s / 20), 50 * np.sin(s / 20), np.zeros(n)]
    ref = trajdrift.Trajectory(t, xyz)
    est = trajdrift.Trajectory(t, xyz * 1.01 + 0.1)
    span = {}

    def work():
        span["start"] = time.perf_counter()
        for _ in range(3):
            trajdrift.rpe(ref, est, pose_relation="point_distance", delta=0.5, all_pairs=True)
        span["end"] = time.perf_counter()

    worker = threading.Thread(target=work)
    ticks = []
    worker.start()
    while worker.is_alive():
        ticks.append(time.perf_counter())
        time.sleep(0.001)
    worker.join()
    inside = [x for x in ticks if span["start"] + 0.05 < x < span["end"] - 0.05]
    # The main thread kept running while the worker was in Rust.
    assert span["end"] - span["start"] > 0.2, "too short to tell"
    assert len(inside) > 10, (len(inside), span)
