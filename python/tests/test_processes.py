"""Work across processes: a worker forked after the parent computed (rayon's pool does not survive
fork: the package's must)."""

from __future__ import annotations

import multiprocessing
import sys

import pytest

import trajdrift
from conftest import FIXTURE

REF, EST = "/reference/position", "/estimate/odom"


def _offset_in_child(_: int) -> float:
    r, e = trajdrift.read(FIXTURE, REF), trajdrift.read(FIXTURE, EST)
    return trajdrift.time_offset(r, e).offset_s


@pytest.mark.skipif(sys.platform == "win32" or "fork" not in multiprocessing.get_all_start_methods(),
                    reason="needs the fork start method")
def test_a_forked_worker_computes_after_the_parent_did():
    r, e = trajdrift.read(FIXTURE, REF), trajdrift.read(FIXTURE, EST)
    here = trajdrift.time_offset(r, e).offset_s  # the parent's thread pool now exists
    trajdrift.drift_error(r, e)
    with multiprocessing.get_context("fork").Pool(1) as pool:
        result = pool.map_async(_offset_in_child, [0, 1])
        # A child waiting for the parent's pool threads never returns: fail instead of hanging.
        there = result.get(timeout=120)
    assert there == [here, here]
