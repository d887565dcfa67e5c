"""Shared fixtures of the Python package's tests: the repository, its fixture recording, the shared
evidence folder ($TRAJDRIFT_SHARED, default ../shared; required in CI, skipped elsewhere) and the
``trajdrift`` command installed beside this interpreter."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
FIXTURE = REPO / "fixtures" / "sim_ground" / "mission.mcap"


def shared_dir() -> Path:
    return Path(os.environ.get("TRAJDRIFT_SHARED", REPO.parent / "shared")).resolve()


@pytest.fixture(scope="session")
def shared() -> Path:
    d = shared_dir()
    if not (d / "evo-data" / "REFERENCE.md").is_file():
        if os.environ.get("CI"):
            pytest.fail(f"the shared evidence is missing at {d}; the tests that read it must run in CI")
        pytest.skip(f"no shared evidence at {d} (set TRAJDRIFT_SHARED)")
    return d


@pytest.fixture(scope="session")
def evo_data(shared: Path) -> Path:
    return shared / "evo-data"


def trajdrift_command() -> str:
    """The ``trajdrift`` command of the environment under test (the wheel's entry point)."""
    here = Path(sys.executable).parent / "trajdrift"
    if here.exists():
        return str(here)
    found = shutil.which("trajdrift")
    assert found, "the trajdrift command is not installed beside this Python"
    return found


def run_cli(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess:
    return subprocess.run(
        [trajdrift_command(), *args], cwd=cwd, capture_output=True, text=True, timeout=600
    )
