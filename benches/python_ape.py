"""Speed of trajdrift.ape against evo's Python API on the same arrays already in memory.

One synthetic mission of N poses at 100 Hz (a smooth 3-D path with yaw, positions and orientations),
and an estimate of it: rotated, shifted, scaled by 1 %, noisy, on the same clock. Both libraries get
the same NumPy arrays, built before any clock starts. Timed:

- evo: ``sync.associate_trajectories(ref, est, 0.01)`` then
  ``main_ape.ape(ref, est, PoseRelation.translation_part, align=True)`` — what ``evo_ape tum REF EST -a``
  runs, and what ``trajdrift.ape`` does in one call;
- trajdrift: ``trajdrift.ape(ref, est)`` on ``trajdrift.Trajectory.from_arrays`` objects (the arrays
  converted inside the call), and on the evo objects themselves.

Both give the same statistics (checked, to 1e-9). Run in a venv with the wheel, evo and NumPy:

    python benches/python_ape.py            # N = 1 000 000, each timed once
    python benches/python_ape.py --n 100000 --repeat 3

It prints the timings, the ratio and the versions, with the date and commit, for docs/evidence.md.
"""

from __future__ import annotations

import argparse
import copy
import datetime
import os
import platform
import subprocess
import time

import numpy as np


def mission(n: int, seed: int = 1):
    rng = np.random.default_rng(seed)
    t = 1_718_460_000.0 + np.arange(n) * 0.01
    s = np.linspace(0.0, 1.0, n) * n * 0.01  # seconds of travel at about 1 m/s
    xyz = np.c_[40 * np.sin(s / 30), 25 * np.sin(s / 17) + 0.02 * s, 2 * np.sin(s / 50)]
    yaw = np.arctan2(np.gradient(xyz[:, 1]), np.gradient(xyz[:, 0]))
    q_wxyz = np.c_[np.cos(yaw / 2), np.zeros(n), np.zeros(n), np.sin(yaw / 2)]
    a = 0.3
    rz = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
    est_xyz = 1.01 * xyz @ rz.T + [5.0, -3.0, 0.5] + rng.normal(0, 0.02, (n, 3))
    ya = yaw + a
    est_q = np.c_[np.cos(ya / 2), np.zeros(n), np.zeros(n), np.sin(ya / 2)]
    return t, xyz, q_wxyz, est_xyz, est_q


def timed(f, repeat: int):
    best, out = float("inf"), None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = f()
        best = min(best, time.perf_counter() - t0)
    return best, out


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--n", type=int, default=1_000_000, help="poses per trajectory")
    p.add_argument("--repeat", type=int, default=1, help="runs of each, the best is kept")
    a = p.parse_args()

    import evo
    import evo.main_ape as main_ape
    from evo.core import metrics, sync
    from evo.core.trajectory import PoseTrajectory3D

    import trajdrift

    t, xyz, q, est_xyz, est_q = mission(a.n)
    evo_ref = PoseTrajectory3D(positions_xyz=xyz, orientations_quat_wxyz=q, timestamps=t)
    evo_est = PoseTrajectory3D(positions_xyz=est_xyz, orientations_quat_wxyz=est_q, timestamps=t)
    td_ref = trajdrift.Trajectory.from_arrays(t, xyz, q, quat_order="wxyz")
    td_est = trajdrift.Trajectory.from_arrays(t, est_xyz, est_q, quat_order="wxyz")

    def run_evo():
        r, e = sync.associate_trajectories(evo_ref, evo_est, max_diff=0.01)
        return main_ape.ape(r, e, metrics.PoseRelation.translation_part, align=True).stats

    t_td, r_td = timed(lambda: trajdrift.ape(td_ref, td_est), a.repeat)
    t_td_evo, r_td_evo = timed(lambda: trajdrift.ape(evo_ref, evo_est), a.repeat)
    t_evo, s_evo = timed(run_evo, a.repeat)
    for r in (r_td, r_td_evo):
        for k in trajdrift.STATISTICS:
            assert abs(r.stats[k] - s_evo[k]) <= 1e-9 * max(1.0, abs(s_evo[k])), (k, r.stats[k], s_evo[k])

    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                            cwd=os.path.dirname(os.path.abspath(__file__))).stdout.strip()
    print(f"date {datetime.date.today()}, commit {commit}, {platform.machine()}, {os.cpu_count()} cores, "
          f"Python {platform.python_version()}, NumPy {np.__version__}, evo {evo.__version__}, "
          f"trajdrift {trajdrift.__version__}")
    print(f"command: python benches/python_ape.py --n {a.n} --repeat {a.repeat}")
    print(f"APE (SE(3) alignment, translation part) of {a.n} poses, rmse {r_td.rmse:.6f} m, {r_td.to_dict()['pairs']} pairs")
    print(f"  evo (associate_trajectories + main_ape.ape)     {t_evo:9.3f} s")
    print(f"  trajdrift.ape on trajdrift.Trajectory           {t_td:9.3f} s   {t_evo / t_td:6.1f}x")
    print(f"  trajdrift.ape on the evo objects                {t_td_evo:9.3f} s   {t_evo / t_td_evo:6.1f}x")


if __name__ == "__main__":
    main()
