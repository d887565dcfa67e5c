"""The trajectory as NumPy arrays, and the conversions from everything accepted where a trajectory is
(a :class:`Trajectory`, evo's ``PoseTrajectory3D``/``PosePath3D`` or any object with evo's attribute
names)."""

from __future__ import annotations

import json
from typing import Any, Optional

import numpy as np

from ._errors import UsageError

__all__ = ["Trajectory", "STAMP_SECONDS"]

#: How a trajectory's nanosecond stamps become the float seconds evo compares, by the source's reader
#: in evo: ``decimal`` (TUM and CSV text: the decimal's nearest double), ``nanos_over_1e9`` (EuRoC's
#: CSV: nanoseconds as a double, over 1e9), ``sec_plus_nanos`` (ROS bags, rosbag2, MCAP:
#: ``sec + nanosec·1e-9``); ``None``: no stamps of its own (a KITTI pose file without times: frame
#: ``i`` is stamped ``i·0.1 s`` and evo's metrics pair poses by index).
STAMP_SECONDS = ("decimal", "nanos_over_1e9", "sec_plus_nanos", None)

_NS = 1_000_000_000

#: The largest |seconds| a float stamp may hold: int64 nanoseconds end in April 2262.
_MAX_SECONDS = 9.2e9


def _seconds_to_ns(s: np.ndarray) -> np.ndarray:
    """Float seconds to integer nanoseconds: for each stamp the shortest decimal (at most 9 digits after
    the point) whose ``decimal`` conversion back gives the same double (``1718460000.1`` → ``…100000000``
    ns, as a TUM file writes it), else the nearest nanosecond. Either way :attr:`Trajectory.timestamps`
    gives the stamps back exactly at Unix-epoch magnitudes (and within 0.5 ns below them)."""
    s = np.asarray(s, dtype=np.float64)
    if not np.all(np.isfinite(s)):
        raise UsageError("t: the stamps must be finite")
    if s.size and np.max(np.abs(s)) > _MAX_SECONDS:
        big = s[np.argmax(np.abs(s))]
        raise UsageError(
            f"t: float stamps are seconds, and {big:.6g} s is beyond int64 nanoseconds (±{_MAX_SECONDS:.3g} s, "
            f"year 2262); give nanoseconds as int64"
        )
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


def _stamps_ns(t: Any, what: str) -> np.ndarray:
    """Integer nanosecond stamps as a contiguous int64 array; a float array, a value beyond int64 (an
    uint64 stamp after April 2262) or a non-number is refused rather than rounded or wrapped."""
    a = np.asarray(t)
    if a.dtype.kind == "f":
        raise UsageError(f"{what} must hold int64 nanoseconds; for float seconds use Trajectory.from_arrays")
    if a.dtype.kind == "u" and a.size and int(a.max()) > np.iinfo(np.int64).max:
        raise UsageError(
            f"{what}: stamp {int(a.max())} ns is beyond int64 nanoseconds (year 2262); give int64 nanoseconds"
        )
    if a.dtype.kind not in "iub" and a.size:
        try:
            a = np.array(a, dtype=np.int64)
        except (OverflowError, ValueError, TypeError):
            raise UsageError(
                f"{what} must hold int64 nanoseconds; got {a.dtype} values that are not such integers"
            ) from None
    return np.ascontiguousarray(a, dtype=np.int64)


def _floats(v: Any, what: str) -> np.ndarray:
    """A contiguous float64 array, or a :class:`UsageError` naming ``what``."""
    try:
        return np.ascontiguousarray(v, dtype=np.float64)
    except (ValueError, TypeError) as e:
        raise UsageError(f"{what} must hold numbers (float64): {e}") from None


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
    q = _floats(q, "orientations_quat_wxyz")
    if q.ndim != 2 or q.shape[1] != 4:
        raise UsageError(f"orientations_quat_wxyz must be (N, 4) w, x, y, z; got {q.shape}")
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
        t = _stamps_ns(t, "t")
        xyz = _floats(xyz, "xyz")
        n = t.shape[0] if t.ndim == 1 else -1
        if t.ndim != 1 or xyz.shape != (n, 3):
            raise UsageError(f"t must be (N,) and xyz (N, 3); got t {t.shape} and xyz {xyz.shape}")
        if quat is not None:
            quat = _floats(quat, "quat")
            if quat.shape != (n, 4):
                raise UsageError(f"quat must be (N, 4) x, y, z, w with N = {n}; got {quat.shape}")
        if rot is not None:
            rot = _floats(rot, "rot")
            if rot.shape != (n, 3, 3):
                raise UsageError(f"rot must be (N, 3, 3) with N = {n}; got {rot.shape}")
        if stamp_seconds not in STAMP_SECONDS:
            raise UsageError(f"stamp_seconds {stamp_seconds!r}: expected one of {STAMP_SECONDS}")
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
        if quat_order not in ("xyzw", "wxyz"):
            raise UsageError(f"quat_order {quat_order!r}: expected 'xyzw' or 'wxyz'")
        if quat is not None and quat_order == "wxyz":
            quat = _floats(quat, "quat")
            if quat.ndim != 2 or quat.shape[1] != 4:
                raise UsageError(f"quat must be (N, 4) w, x, y, z (quat_order='wxyz'); got {quat.shape}")
            quat = quat[:, [1, 2, 3, 0]]
        return cls(t, xyz, quat, name=name)

    @classmethod
    def from_evo(cls, traj: Any, name: str = "") -> "Trajectory":
        """evo's ``PoseTrajectory3D`` (or ``PosePath3D``, or any object with ``timestamps``,
        ``positions_xyz`` and ``orientations_quat_wxyz``) as a trajectory. A
        ``PosePath3D`` (no stamps) is stamped ``i·0.1 s`` and paired by index, as evo pairs it. Stamps
        become nanoseconds as in :meth:`from_arrays`; :attr:`timestamps` gives evo's back."""
        if not _is_evo_like(traj):
            raise UsageError(
                f"from_evo: expected an evo trajectory (timestamps, positions_xyz, orientations_quat_wxyz), "
                f"got {type(traj).__name__}"
            )
        ts = getattr(traj, "timestamps", None)
        xyz = _floats(traj.positions_xyz, "positions_xyz")
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
    raise UsageError(
        f"{what}: expected a trajdrift.Trajectory or an evo trajectory (timestamps, positions_xyz, "
        f"orientations_quat_wxyz), got {type(obj).__name__}"
    )


def _finite_positions(xyz: np.ndarray, what: str) -> None:
    """Refuses a position that is NaN or infinite, naming the trajectory and the row: the metrics would
    otherwise leave it out of some numbers and count it in others."""
    bad = ~np.all(np.isfinite(xyz), axis=1)
    if bad.any():
        i = int(np.argmax(bad))
        raise UsageError(
            f"{what}: position of row {i} is not finite ({', '.join(repr(float(x)) for x in xyz[i])}); "
            f"{int(bad.sum())} such rows: drop them (e.g. xyz[np.isfinite(xyz).all(axis=1)])"
        )


def _seconds(ts: Any, n: int, what: str) -> np.ndarray:
    s = _floats(ts, f"{what}.timestamps")
    if s.shape != (n,):
        raise UsageError(f"{what}: timestamps must be (N,) with N = {n} positions; got {s.shape}")
    return s


def _checked(tr: Trajectory, what: str) -> tuple:
    """``(t, xyz, quat, rot)`` of ``tr`` as the native layer takes them: its arrays may have been
    reassigned since it was made (another dtype, another shape), so they are checked and converted
    again here, a mismatch a :class:`UsageError` naming ``what``."""
    t = _stamps_ns(tr.t, f"{what}.t")
    xyz = _floats(tr.xyz, f"{what}.xyz")
    n = t.shape[0] if t.ndim == 1 else -1
    if t.ndim != 1 or xyz.shape != (n, 3):
        raise UsageError(f"{what}: t must be (N,) and xyz (N, 3); got t {t.shape} and xyz {xyz.shape}")
    quat = None if tr.quat is None else _floats(tr.quat, f"{what}.quat")
    if quat is not None and quat.shape != (n, 4):
        raise UsageError(f"{what}: quat must be (N, 4) x, y, z, w with N = {n}; got {quat.shape}")
    rot = None if tr.rot is None else _floats(tr.rot, f"{what}.rot")
    if rot is not None and rot.shape != (n, 3, 3):
        raise UsageError(f"{what}: rot must be (N, 3, 3) with N = {n}; got {rot.shape}")
    return t, xyz, quat, rot


def arrays(obj: Any, what: str) -> tuple:
    """``(t, xyz, quat)`` for the native evaluation."""
    t, xyz, quat, _ = _checked(as_trajectory(obj, what), what)
    return (t, xyz, quat)


def poses(obj: Any, what: str) -> dict:
    """evo's form of a trajectory for the native APE/RPE: an evo object's own float stamps and
    matrices as they are (so that the numbers are evo's), a :class:`Trajectory`'s stamps by its
    source's rule."""
    if isinstance(obj, Trajectory):
        t, xyz, quat, rot = _checked(obj, what)
        _finite_positions(xyz, what)
        return {
            "t": t,
            "stamp_seconds": obj.stamp_seconds,
            "seconds": None,
            "xyz": xyz,
            "quat": quat,
            "rot": rot,
        }
    if _is_evo_like(obj):
        ts = getattr(obj, "timestamps", None)
        rot = _evo_rotation_matrices(obj)
        xyz = _floats(obj.positions_xyz, f"{what}.positions_xyz")
        if xyz.ndim != 2 or xyz.shape[1] != 3:
            raise UsageError(f"{what}: positions_xyz must be (N, 3); got {xyz.shape}")
        _finite_positions(xyz, what)
        return {
            "t": None,
            "stamp_seconds": None,
            "seconds": None if ts is None else _seconds(ts, xyz.shape[0], what),
            "xyz": xyz,
            "quat": None if rot is not None else _evo_quat_xyzw(obj),
            "rot": rot,
        }
    raise UsageError(
        f"{what}: expected a trajdrift.Trajectory or an evo trajectory (timestamps, positions_xyz, "
        f"orientations_quat_wxyz), got {type(obj).__name__}"
    )
