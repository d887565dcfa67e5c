"""evo's own numbers through the Python API: every row of shared/evo-data/REFERENCE.md (evo 1.38.1's
printed statistics on real trajectories) computed with trajdrift.read and trajdrift.ape/rpe must print
the same six decimals."""

from __future__ import annotations

import shlex

import pytest

import trajdrift
from conftest import shared_dir

STATS = ("rmse", "mean", "median", "std", "min", "max", "sse")


def reference_rows():
    path = shared_dir() / "evo-data" / "REFERENCE.md"
    if not path.is_file():
        return [pytest.param(None, None, id="no-shared-evidence")]
    rows = []
    for line in path.read_text().splitlines():
        if line.startswith("| `evo_"):
            cells = [c.strip() for c in line.split("|")]
            rows.append(pytest.param(cells[1].strip("`"), cells[2:9], id=cells[1].strip("`")))
    return rows


def run(command: str, data):
    """The trajdrift call for one evo command line: the same inputs, read by trajdrift.read, and the
    same options under evo's names (evo's defaults where the row gives none)."""
    argv = shlex.split(command)
    tool, form, args = argv[0], argv[1], argv[2:]
    files = 3 if form in ("bag", "bag2", "mcap") else 2
    inputs, flags = args[:files], args[files:]
    if form in ("bag", "bag2", "mcap"):
        rec = data / inputs[0]
        ref, est = trajdrift.read(rec, inputs[1]), trajdrift.read(rec, inputs[2])
    else:
        ref, est = trajdrift.read(data / inputs[0]), trajdrift.read(data / inputs[1])
    kw = {"align": False, "correct_scale": False}
    rpe = {"delta": 1.0, "delta_unit": "f", "all_pairs": False}
    i = 0
    while i < len(flags):
        f = flags[i]
        if f in ("-a", "--align"):
            kw["align"] = True
        elif f in ("-s", "--correct_scale"):
            kw["correct_scale"] = True
        elif f == "-as":
            kw["align"] = kw["correct_scale"] = True
        elif f in ("-r", "--pose_relation"):
            kw["pose_relation"] = flags[i + 1]
            i += 1
        elif f == "--t_max_diff":
            kw["t_max_diff"] = float(flags[i + 1])
            i += 1
        elif f in ("-d", "--delta"):
            rpe["delta"] = float(flags[i + 1])
            i += 1
        elif f in ("-u", "--delta_unit"):
            rpe["delta_unit"] = flags[i + 1]
            i += 1
        elif f == "--all_pairs":
            rpe["all_pairs"] = True
        else:
            raise AssertionError(f"flag {f} of `{command}` is not mapped in this test")
        i += 1
    if tool == "evo_ape":
        return trajdrift.ape(ref, est, **kw)
    return trajdrift.rpe(ref, est, **kw, **rpe)


@pytest.mark.parametrize("command,printed", reference_rows())
def test_reference_row(command, printed, evo_data):
    r = run(command, evo_data)
    got = [f"{r.stats[k]:.6f}" for k in STATS]
    assert got == printed, f"{command}: trajdrift {got}, evo {printed}"
    assert len(r.error_array) == r.to_dict()["pairs"]
