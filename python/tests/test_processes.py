"""Results and work across processes: a worker forked after the parent computed (rayon's pool does
not survive fork: the package's must), and results copied, pickled and returned from a process pool."""

from __future__ import annotations

import copy
import multiprocessing
import pickle
import sys

import numpy as np
import pytest

import trajdrift
from conftest import FIXTURE

REF, EST = "/reference/position", "/estimate/odom"


def _offset_in_child(_: int) -> float:
    r, e = trajdrift.read(FIXTURE, REF), trajdrift.read(FIXTURE, EST)
    return trajdrift.time_offset(r, e).offset_s


def _offset_object(_: int) -> trajdrift.TimeOffset:
    r, e = trajdrift.read(FIXTURE, REF), trajdrift.read(FIXTURE, EST)
    return trajdrift.time_offset(r, e)


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


def _results():
    r, e = trajdrift.read(FIXTURE, REF), trajdrift.read(FIXTURE, EST)
    rep = trajdrift.evaluate(reference=r, estimates={"lio": e}, metrics="de,ape,rpe")
    lio = rep.estimates["lio"]
    a = trajdrift.ape(r, e, t_offset=0.2, t_max_diff=0.05)
    return [rep, lio, lio.time_offset, lio.drift_error[5], lio.drift_error, a,
            trajdrift.time_offset(r, e), trajdrift.drift_error(r, e)]


def test_results_copy_and_pickle():
    for x in _results():
        for y in (copy.copy(x), copy.deepcopy(x), pickle.loads(pickle.dumps(x))):
            assert type(y) is type(x) and repr(y) == repr(x)
            if isinstance(x, trajdrift.MetricResult):
                assert y.to_dict() == x.to_dict()
                assert np.array_equal(y.error_array, x.error_array)
            elif isinstance(x, trajdrift.DriftErrors):
                assert dict(y) == dict(x)
            else:
                assert y == x and y.to_dict() == x.to_dict()
    # Copies do not share the JSON object they wrap.
    rep = _results()[0]
    deep = copy.deepcopy(rep)
    deep.to_dict()  # still usable
    assert deep._d is not rep._d
    # Private and special names are no JSON fields.
    assert not hasattr(rep, "_nope") and not hasattr(rep, "__getstate_nope__")


def test_a_result_returned_from_a_process_pool():
    ctx = multiprocessing.get_context("spawn")
    with ctx.Pool(1) as pool:
        [o] = pool.map_async(_offset_object, [0]).get(timeout=120)
    assert isinstance(o, trajdrift.TimeOffset) and o == _offset_object(0)
