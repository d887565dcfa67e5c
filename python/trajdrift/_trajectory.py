"""The trajectory as NumPy arrays, and the conversions from everything accepted where a trajectory is
(a :class:`Trajectory`, evo's ``PoseTrajectory3D``/``PosePath3D`` or any object with evo's attribute
names)."""

from __future__ import annotations

import json
from typing import Any, Optional

import numpy as np

__all__ = ["Trajectory", "STAMP_SECONDS"]

#: How a trajectory's nanosecond stamps become the float seconds evo compares, by the source's reader
#: in evo: ``decimal`` (TUM and CSV text: the decimal's nearest double), ``nanos_over_1e9`` (EuRoC's
#: CSV: nanoseconds as a double, over 1e9), ``sec_plus_nanos`` (ROS bags, rosbag2, MCAP:
#: ``sec + nanosec·1e-9``); ``None``: no stamps of its own (a KITTI pose file without times: frame
#: ``i`` is stamped ``i·0.1 s`` and evo's metrics pair poses by index).
STAMP_SECONDS = ("decimal", "nanos_over_1e9", "sec_plus_nanos", None)

_NS = 1_000_000_000


def _seconds_to_ns(s: np.ndarray) -> np.ndarray:
    """Float seconds to integer nanoseconds: for each stamp the shortest decimal (at most 9 digits after
    the point) whose ``decimal`` conversion back gives the same double (``1718460000.1`` → ``…100000000``
    ns, as a TUM file writes it), else the nearest nanosecond. Either way :attr:`Trajectory.timestamps`
    gives the stamps back exactly at Unix-epoch magnitudes (and within 0.5 ns below them)."""
    s = np.asarray(s, dtype=np.float64)
    if not np.all(np.isfinite(s)):
        raise ValueError("t: the stamps must be finite")
    whole = np.floor(s)
    frac = s - whole  # exact (Sterbenz)
    nsec = np.rint(frac * 1e9).astype(np.int64)
    done = np.zeros(s.shape, dtype=bool)
    for digits in range(10):
        step = 10 ** (9 - digits)
        cand = np.rint(frac * (1e9 / step)).astype(np.int64) * step
        ok = ~done & (cand < _NS) & (whole + cand / 1e9 == s)
        nsec[ok] = cand[ok]
        done |= ok
    return whole.astype(np.int64) * _NS + nsec


def _ns_to_seconds(t: np.ndarray, rule: Optional[str]) -> np.ndarray:
    """Nanoseconds to seconds as evo's reader of the source gives them (see :data:`STAMP_SECONDS`)."""
    sec, nsec = np.divmod(t, _NS)
    if rule == "nanos_over_1e9":
        return t.astype(np.float64) / 1e9
    if rule == "sec_plus_nanos":
        return sec.astype(np.float64) + nsec.astype(np.float64) * 1e-9
    return sec.astype(np.float64) + nsec.astype(np.float64) / 1e9


def _is_evo_like(obj: Any) -> bool:
    return hasattr(obj, "positions_xyz") and not isinstance(obj, Trajectory)


def _evo_rotation_matrices(obj: Any) -> Optional[np.ndarray]:
    """evo's pose matrices' rotations when the object was made from them (KITTI), else ``None`` (its
    quaternions are then the source of truth, and give evo's matrices exactly)."""
    cache = getattr(obj, "_cache", None)
    has = getattr(cache, "has_poses_se3", None)
    if has is None or not has():
        return None
    return np.asarray(obj.poses_se3, dtype=np.float64)[:, :3, :3]


def _evo_quat_xyzw(obj: Any) -> Optional[np.ndarray]:
    q = getattr(obj, "orientations_quat_wxyz", None)
    if q is None:
        return None
    q = np.asarray(q, dtype=np.float64)
    return np.ascontiguousarray(q[:, [1, 2, 3, 0]])


class Trajectory:
    """A trajectory: stamps, positions and, when the source has them, orientations, as NumPy arrays.

    - ``t``: int64 nanoseconds (Unix epoch for ROS stamps), shape (N,)
    - ``xyz``: float64 metres, shape (N, 3)
    - ``quat``: float64 unit quaternions ``x, y, z, w`` (ROS, TUM and scipy's order; evo's
      ``orientations_quat_wxyz`` is ``w`` first), shape (N, 4), or ``None`` (positions only: GNSS,
      prisms, total stations)
    - ``rot``: float64 rotation matrices as the file wrote them, shape (N, 3, 3), or ``None``; only a
      KITTI pose file has them (evo's metrics use them unchanged, ``quat`` holds their nearest
      rotations)
    - ``name``, ``source``, ``type_name``: what an evaluation calls it, the topic or file it came from,
      the message type or text format
    - ``stamp_seconds``: how evo's reader of the source turns ``t`` into seconds (see
      :data:`trajdrift.STAMP_SECONDS`); :attr:`timestamps` applies it

    Arrays read by :func:`trajdrift.read` are the library's own buffers, handed over without a copy.
    A trajectory is accepted, like evo's ``PoseTrajectory3D``, wherever trajdrift takes one.
    """

    __slots__ = ("t", "xyz", "quat", "rot", "name", "source", "type_name", "stamp_seconds", "rows")

    t: np.ndarray
    xyz: np.ndarray
    quat: Optional[np.ndarray]
    rot: Optional[np.ndarray]
    name: str
    source: str
    type_name: str
    stamp_seconds: Optional[str]
    rows: dict

    def __init__(
        self,
        t: Any,
        xyz: Any,
        quat: Any = None,
        *,
        rot: Any = None,
        name: str = "",
        source: str = "",
        type_name: str = "",
        stamp_seconds: Optional[str] = "decimal",
        rows: Optional[dict] = None,
    ) -> None:
        t = np.ascontiguousarray(t)
        if t.dtype.kind == "f":
            raise TypeError("t must hold int64 nanoseconds; for float seconds use Trajectory.from_arrays")
        t = np.ascontiguousarray(t, dtype=np.int64)
        xyz = np.ascontiguousarray(xyz, dtype=np.float64)
        n = t.shape[0] if t.ndim == 1 else -1
        if t.ndim != 1 or xyz.shape != (n, 3):
            raise ValueError(f"t must be (N,) and xyz (N, 3); got t {t.shape} and xyz {xyz.shape}")
        if quat is not None:
            quat = np.ascontiguousarray(quat, dtype=np.float64)
            if quat.shape != (n, 4):
                raise ValueError(f"quat must be (N, 4) x, y, z, w with N = {n}; got {quat.shape}")
        if rot is not None:
            rot = np.ascontiguousarray(rot, dtype=np.float64)
            if rot.shape != (n, 3, 3):
                raise ValueError(f"rot must be (N, 3, 3) with N = {n}; got {rot.shape}")
        if stamp_seconds not in STAMP_SECONDS:
            raise ValueError(f"stamp_seconds {stamp_seconds!r}: expected one of {STAMP_SECONDS}")
        self.t, self.xyz, self.quat, self.rot = t, xyz, quat, rot
        self.name, self.source, self.type_name = name, source, type_name
        self.stamp_seconds = stamp_seconds
        self.rows = rows if rows is not None else {}

    @classmethod
    def from_arrays(
        cls,
        t: Any,
        xyz: Any,
        quat: Any = None,
        *,
        quat_order: str = "xyzw",
        name: str = "",
    ) -> "Trajectory":
        """A trajectory from arrays: ``t`` int64 nanoseconds, or float seconds (evo's ``timestamps``,
        a TUM file's first column: to the nanoseconds of their shortest decimal, so that
        :attr:`timestamps` gives them back); ``xyz`` (N, 3); ``quat``
        (N, 4) in ``quat_order`` ``"xyzw"`` (default) or ``"wxyz"`` (evo's), or ``None``. Arrays that
        are already int64/float64 and contiguous are kept without a copy."""
        t = np.asarray(t)
        t = _seconds_to_ns(t) if t.dtype.kind == "f" else t
        if quat is not None:
            if quat_order == "wxyz":
                quat = np.asarray(quat, dtype=np.float64)[:, [1, 2, 3, 0]]
            elif quat_order != "xyzw":
                raise ValueError(f"quat_order {quat_order!r}: expected 'xyzw' or 'wxyz'")
        return cls(t, xyz, quat, name=name)

    @classmethod
    def from_evo(cls, traj: Any, name: str = "") -> "Trajectory":
        """evo's ``PoseTrajectory3D`` (or ``PosePath3D``, or any object with ``timestamps``,
        ``positions_xyz`` and ``orientations_quat_wxyz``) as a trajectory. A
        ``PosePath3D`` (no stamps) is stamped ``i·0.1 s`` and paired by index, as evo pairs it. Stamps
        become nanoseconds as in :meth:`from_arrays`; :attr:`timestamps` gives evo's back."""
        ts = getattr(traj, "timestamps", None)
        xyz = np.asarray(traj.positions_xyz, dtype=np.float64)
        rot = _evo_rotation_matrices(traj)
        quat = _evo_quat_xyzw(traj)
        if ts is None:
            t, rule = np.arange(xyz.shape[0], dtype=np.int64) * 100_000_000, None
        else:
            t, rule = _seconds_to_ns(ts), "decimal"
        return cls(
            t,
            xyz,
            quat,
            rot=rot,
            name=name or str(getattr(traj, "name", "") or ""),
            stamp_seconds=rule,
        )

    @property
    def timestamps(self) -> np.ndarray:
        """The stamps in float seconds as evo's reader of the source gives them (evo's
        ``timestamps``)."""
        return _ns_to_seconds(self.t, self.stamp_seconds)

    def to_evo(self) -> Any:
        """This trajectory as evo's ``PoseTrajectory3D`` (a ``PosePath3D`` for a KITTI path without
        times). Needs evo. Positions-only trajectories get identity orientations (evo requires
        some)."""
        from evo.core import trajectory as evo_trajectory  # type: ignore[import-not-found]

        if self.rot is not None:
            poses = np.zeros((len(self), 4, 4))
            poses[:, :3, :3] = self.rot
            poses[:, :3, 3] = self.xyz
            poses[:, 3, 3] = 1.0
            kw: dict = {"poses_se3": list(poses)}
        else:
            q = self.quat
            if q is None:
                q = np.tile([0.0, 0.0, 0.0, 1.0], (len(self), 1))
            kw = {"positions_xyz": self.xyz, "orientations_quat_wxyz": q[:, [3, 0, 1, 2]]}
        if self.stamp_seconds is None:
            return evo_trajectory.PosePath3D(**kw)
        return evo_trajectory.PoseTrajectory3D(timestamps=self.timestamps, **kw)

    def __len__(self) -> int:
        return int(self.t.shape[0])

    def __repr__(self) -> str:
        what = "poses" if self.quat is not None else "positions"
        span = (self.t[-1] - self.t[0]) / 1e9 if len(self) > 1 else 0.0
        label = f" {self.name!r}" if self.name else ""
        return f"<trajdrift.Trajectory{label}: {len(self)} {what} over {span:.1f} s>"

    @classmethod
    def _from_native(cls, d: dict) -> "Trajectory":
        return cls(
            d["t"],
            d["xyz"],
            d["quat"],
            rot=d["rot"],
            name=d["name"],
            source=d["source"],
            type_name=d["type_name"],
            stamp_seconds=d["stamp_seconds"],
            rows=json.loads(d["rows"]),
        )


def as_trajectory(obj: Any, what: str) -> Trajectory:
    """A :class:`Trajectory` from anything accepted where one is."""
    if isinstance(obj, Trajectory):
        return obj
    if _is_evo_like(obj):
        return Trajectory.from_evo(obj)
    raise TypeError(
        f"{what}: expected a trajdrift.Trajectory or an evo trajectory (timestamps, positions_xyz, "
        f"orientations_quat_wxyz), got {type(obj).__name__}"
    )


def arrays(obj: Any, what: str) -> tuple:
    """``(t, xyz, quat)`` for the native evaluation."""
    tr = as_trajectory(obj, what)
    return (tr.t, tr.xyz, tr.quat)


def poses(obj: Any, what: str) -> dict:
    """evo's form of a trajectory for the native APE/RPE: an evo object's own float stamps and
    matrices as they are (so that the numbers are evo's), a :class:`Trajectory`'s stamps by its
    source's rule."""
    if isinstance(obj, Trajectory):
        return {
            "t": obj.t,
            "stamp_seconds": obj.stamp_seconds,
            "seconds": None,
            "xyz": obj.xyz,
            "quat": obj.quat,
            "rot": obj.rot,
        }
    if _is_evo_like(obj):
        ts = getattr(obj, "timestamps", None)
        rot = _evo_rotation_matrices(obj)
        return {
            "t": None,
            "stamp_seconds": None,
            "seconds": None if ts is None else np.ascontiguousarray(ts, dtype=np.float64),
            "xyz": np.ascontiguousarray(obj.positions_xyz, dtype=np.float64),
            "quat": None if rot is not None else _evo_quat_xyzw(obj),
            "rot": rot,
        }
    raise TypeError(
        f"{what}: expected a trajdrift.Trajectory or an evo trajectory (timestamps, positions_xyz, "
        f"orientations_quat_wxyz), got {type(obj).__name__}"
    )
