"""The README fixture: trajdrift.evaluate gives the command line's JSON report, its numbers are the
README's, and the pieces (time_offset, drift_error, an evaluation of trajectories in memory) agree with
the whole."""

from __future__ import annotations

import json
import re

import numpy as np

import trajdrift
from conftest import FIXTURE, REPO, run_cli

REF, EST = "/reference/position", "/estimate/odom"


def cli_report(tmp_path, *extra: str) -> dict:
    out = tmp_path / "report.json"
    r = run_cli("eval", str(FIXTURE), "--reference", REF, "--estimate", EST, "--quiet",
                "--json", str(out), *extra)
    assert r.returncode in (0, 3), r.stderr
    return json.loads(out.read_text())


def test_report_is_the_command_lines_json(tmp_path):
    report = trajdrift.evaluate(str(FIXTURE), REF, EST)
    assert report.to_dict() == cli_report(tmp_path)


def test_parameters_reach_the_report_as_on_the_command_line(tmp_path):
    report = trajdrift.evaluate(FIXTURE, REF, {"odom": EST}, window=[5, 10], offset_method="speed",
                                metrics="de,ape")
    want = cli_report(tmp_path, "--window", "5,10", "--offset-method", "speed", "--metrics", "de,ape")
    want["estimates"][0]["name"] = "odom"
    assert report.to_dict() == want


def test_readme_numbers():
    readme = (REPO / "README.md").read_text()
    # The README's excerpt: "time offset  +0.1992 s" and the 5 m window's "2.01%".
    dt = re.search(r"time offset\s+([+-]\d+\.\d+) s", readme).group(1)
    de = re.search(r"^\s+5m\s+(\d+\.\d+)%", readme, re.M).group(1)
    e = trajdrift.evaluate(FIXTURE, REF, {"lio": EST}).estimates["lio"]
    assert f"{e.time_offset.offset_s:+.4f}" == dt
    assert f"{100 * e.drift_error[5].rmse:.2f}" == de
    assert e.time_offset.model == "constant" and e.time_offset.sigma_s < 0.01
    assert e.time_offset.status == "ok"


def test_in_memory_evaluation_equals_the_recordings():
    ref = trajdrift.read(FIXTURE, REF)
    est = trajdrift.read(FIXTURE, EST)
    assert ref.name == "reference/position" and est.type_name == "nav_msgs/msg/Odometry"
    from_recording = trajdrift.evaluate(FIXTURE, REF, {"lio": EST}).estimates["lio"]
    in_memory = trajdrift.evaluate(reference=ref, estimates={"lio": est}).estimates["lio"]
    for field in ("time_offset", "drift_error", "standard_metrics", "samples"):
        assert in_memory.to_dict()[field] == from_recording.to_dict()[field], field


def test_the_pieces_equal_the_whole():
    ref = trajdrift.read(FIXTURE, REF)
    est = trajdrift.read(FIXTURE, EST)
    whole = trajdrift.evaluate(reference=ref, estimates=[est], window=[5, 10]).estimates[est.name]
    dt = trajdrift.time_offset(ref, est)
    assert dt.to_dict() == whole.time_offset.to_dict()
    de = trajdrift.drift_error(ref, est, window_m=[5, 10])
    assert sorted(de) == [5.0, 10.0]
    assert de[10].to_dict() == whole.drift_error[10].to_dict()
    one = trajdrift.drift_error(ref, est)
    assert one.window_m == 5 and one.rmse == whole.drift_error[5].rmse
    assert len(one.values) == one.windows
    given = trajdrift.time_offset(ref, est, time_offset=0.25)
    assert (given.status, given.offset_s) == ("given", 0.25)


def test_arrays_come_from_the_library_without_a_copy():
    est = trajdrift.read(FIXTURE, EST)
    for a in (est.t, est.xyz, est.quat):
        # The library's Vec is the array's buffer (numpy's container of a Rust allocation).
        assert type(a.base).__name__ == "PySliceContainer" or type(a.base.base).__name__ == "PySliceContainer"
    assert est.t.dtype == np.int64 and est.xyz.shape == (len(est), 3) and est.quat.shape == (len(est), 4)
    assert np.allclose(np.linalg.norm(est.quat, axis=1), 1.0)
    assert np.all(np.diff(est.t) > 0)
    assert trajdrift.read(FIXTURE, REF).quat is None


def test_readme_example_runs(capsys, monkeypatch):
    """The README's "From Python" example, run as written (from the repository's root)."""
    readme = (REPO / "README.md").read_text()
    section = readme.split("## From Python", 1)[1]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    monkeypatch.chdir(REPO)
    exec(compile(code, "README.md", "exec"), {})
    out = capsys.readouterr().out
    # The fixture's truth is Δt = +0.2 s; the README promises the offset within 5 ms of it.
    dt = re.search(r"Δt ([+-]\d+\.\d+)", out)
    assert dt and abs(float(dt.group(1)) - 0.2) <= 0.005 and "2.01" in out, out
