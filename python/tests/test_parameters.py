"""Parameters from Python go through the one parameter table: a bad value raises the command line's
message (a UsageError, which is a ValueError), an unknown key a TypeError; errors of inputs and
metrics are the command line's one line too."""

from __future__ import annotations

import re

import pytest

import trajdrift
from conftest import FIXTURE, run_cli

REF, EST = "/reference/position", "/estimate/odom"


def cli_error(*args: str) -> tuple[int, str]:
    r = run_cli(*args)
    lines = [l for l in r.stderr.splitlines() if l.startswith("error: ")]
    assert lines, r.stderr
    return r.returncode, lines[-1][len("error: "):]


@pytest.mark.parametrize(
    "kwargs,flags",
    [
        ({"grid": 1e-9}, ["--grid", "1e-9"]),
        ({"overlap": 1.0}, ["--overlap", "1"]),
        ({"max_offset": 0}, ["--max-offset", "0"]),
        ({"window": [5, -1]}, ["--window", "5,-1"]),
        ({"lever_arm": 1000}, ["--lever-arm", "1000"]),
        ({"origin": (91, 8, 400)}, ["--origin", "91,8,400"]),
        ({"t_start": 50, "t_end": 10}, ["--t-start", "50", "--t-end", "10"]),
        ({"theta_max": float("nan")}, ["--theta-max", "NaN"]),
    ],
)
def test_a_bad_value_raises_the_command_lines_message(kwargs, flags):
    code, message = cli_error("eval", str(FIXTURE), "--reference", REF, "--estimate", EST, *flags)
    assert code == 2
    with pytest.raises(trajdrift.UsageError) as e:
        trajdrift.evaluate(FIXTURE, REF, EST, **kwargs)
    assert str(e.value) == message
    assert isinstance(e.value, ValueError) and e.value.exit_code == 2
    # The same check wherever parameters are taken.
    ref = trajdrift.read(FIXTURE, REF)
    with pytest.raises(ValueError, match=re.escape(message.split(":")[0])):
        trajdrift.time_offset(ref, ref, **kwargs)


def test_a_wrong_word_lists_the_words():
    with pytest.raises(trajdrift.UsageError, match=r"--offset-method: `fast`: expected auto, speed, signed-curvature or curvature"):
        trajdrift.evaluate(FIXTURE, REF, EST, offset_method="fast")
    with pytest.raises(ValueError, match="expected auto, constant, linear or piecewise"):
        trajdrift.time_offset(trajdrift.read(FIXTURE, REF), trajdrift.read(FIXTURE, EST), model="cubic")
    with pytest.raises(ValueError, match="--window: `five`"):
        trajdrift.evaluate(FIXTURE, REF, EST, window="five")


def test_an_unknown_parameter_is_a_type_error_with_a_suggestion():
    with pytest.raises(TypeError, match="did you mean 'window'"):
        trajdrift.evaluate(FIXTURE, REF, EST, windw=5)


def test_dashes_and_values_as_the_command_line_writes_them():
    a = trajdrift.evaluate(FIXTURE, REF, EST, **{"max-offset": 5}, window="5,10", metrics=["de"])
    b = trajdrift.evaluate(FIXTURE, REF, EST, max_offset=5.0, window=(5, 10), metrics="de")
    assert a.to_dict() == b.to_dict()
    assert a.parameters["max_offset_s"] == 5 and a.parameters["windows_m"] == [5, 10]
    assert "standard_metrics" not in a.estimates["estimate/odom"].to_dict()


def test_input_errors_are_the_command_lines(tmp_path):
    missing = tmp_path / "nope.tum"
    code, message = cli_error("eval", "--reference-file", str(missing), "--estimate-file", str(missing))
    with pytest.raises(trajdrift.InputError) as e:
        trajdrift.evaluate(reference=str(missing), estimates=str(missing))
    assert str(e.value) == message and code == 1 and e.value.exit_code == 1
    with pytest.raises(trajdrift.InputError, match="topic /nope not found"):
        trajdrift.read(FIXTURE, "/nope")
    with pytest.raises(trajdrift.UsageError, match="name the topic .*/estimate/odom"):
        trajdrift.read(FIXTURE)


def test_metric_errors():
    ref = trajdrift.read(FIXTURE, REF)
    est = trajdrift.read(FIXTURE, EST)
    with pytest.raises(trajdrift.MetricError, match="needs orientations"):
        trajdrift.ape(ref, est, pose_relation="angle_deg")
    with pytest.raises(trajdrift.MetricError, match="0 pairs within t_max_diff"):
        trajdrift.ape(ref, est, t_offset=1000)
    with pytest.raises(trajdrift.UsageError, match="-r speed: expected trans_part"):
        trajdrift.ape(ref, est, pose_relation="speed")
    with pytest.raises(trajdrift.UsageError, match="-u x"):
        trajdrift.rpe(ref, est, delta_unit="x")


def test_a_presets_absent_estimate_is_a_warning_as_on_the_command_line(tmp_path):
    preset = tmp_path / "preset.toml"
    preset.write_text(
        'name = "mine"\ndescription = "a test preset"\nrobot = "wheeled"\n'
        '[reference]\ntopics = ["/reference/position"]\n'
        '[[estimate]]\nname = "lio"\ntopics = ["/estimate/odom"]\n'
        '[[estimate]]\nname = "leg"\ntopics = ["/estimate/legs"]\n'
    )
    r = run_cli("eval", str(FIXTURE), "--preset", str(preset), "--json", str(tmp_path / "r.json"))
    note = [l for l in r.stderr.splitlines() if l.startswith("note: ")]
    assert r.returncode in (0, 3) and note, r.stderr
    with pytest.warns(UserWarning) as w:
        report = trajdrift.evaluate(FIXTURE, preset=str(preset))
    assert [str(x.message) for x in w] == [n[len("note: "):] for n in note]
    assert list(report.estimates) == ["lio"]
