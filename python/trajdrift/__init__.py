"""trajdrift: evaluate robot trajectories from positions alone.

trajdrift finds the clock offset between an estimate and its reference from the shape of the path,
then measures how the estimate's travelled distance drifts (the Drift Error); beside it, evo's APE and
RPE with evo's numbers. This package is the Rust library's API, with evo's nouns:

- :func:`read` — a trajectory from an MCAP file, a ROS 1 bag, a rosbag2 folder, a mission of several
  recordings, a TF chain (``/tf:PARENT:CHILD``) or a TUM/KITTI/EuRoC/CSV file;
- :class:`Trajectory` — ``t`` (int64 ns), ``xyz`` (N×3), ``quat`` (N×4 ``x, y, z, w``, or None) as
  NumPy arrays; ``from_arrays``, ``from_evo``, ``to_evo``; evo's ``PoseTrajectory3D`` is accepted
  wherever a trajectory is;
- :func:`evaluate` — what ``trajdrift eval`` computes, as a typed :class:`Report`;
- :func:`time_offset`, :func:`drift_error`, :func:`ape`, :func:`rpe` — each piece alone.

Example::

    import trajdrift
    rec = "fixtures/sim_ground/mission.mcap"
    report = trajdrift.evaluate(rec, "/reference/position", {"lio": "/estimate/odom"})
    lio = report.estimates["lio"]
    print(lio.time_offset.offset_s, lio.time_offset.sigma_s, lio.drift_error[5].rmse)

The ``trajdrift`` command installed with this package is the command line itself
(``trajdrift --help``). Errors are :class:`Error` subclasses carrying the command line's one-line
message.
"""

from __future__ import annotations

from ._errors import Error, InputError, MetricError, UsageError
from ._trajdrift import __version__
from ._trajectory import STAMP_SECONDS, Trajectory
from ._report import (
    STATISTICS,
    DriftError,
    DriftErrors,
    EstimateReport,
    MetricResult,
    Report,
    TimeOffset,
)
from ._api import PARAMETERS, ape, drift_error, evaluate, read, rpe, time_offset

__all__ = [
    "__version__",
    "read",
    "evaluate",
    "time_offset",
    "drift_error",
    "ape",
    "rpe",
    "Trajectory",
    "Report",
    "EstimateReport",
    "TimeOffset",
    "DriftError",
    "DriftErrors",
    "MetricResult",
    "Error",
    "UsageError",
    "InputError",
    "MetricError",
    "PARAMETERS",
    "STATISTICS",
    "STAMP_SECONDS",
]
