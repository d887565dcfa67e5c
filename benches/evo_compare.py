#!/usr/bin/env python3
"""trajdrift ape/rpe next to evo 1.38.1 — not run by CI (it takes minutes and needs evo).

    python3 benches/evo_compare.py            # everything below
    python3 benches/evo_compare.py --rows     # only the extra rows on shared/evo-data
    python3 benches/evo_compare.py --speed    # only the 1 M-pose speed and memory bench

1. Extra rows: relations, alignments and options beyond REFERENCE.md (which tests/it/evo_reference.rs
   checks in CI), run with evo and with trajdrift on $TRAJDRIFT_SHARED/evo-data; the seven statistics
   must print the same 6 decimals.
2. Speed and memory: a TUM pair of 1 M poses (100 Hz, 10 000 s; written once into target/bench-evo/),
   `ape … -a` and `rpe … -d 1 -u m -a` with both tools, wall time and peak RSS (wait4) of each process,
   and the rmse of each, printed from one run.

evo is installed into a venv under target/evo-venv (pip install evo==1.38.1) when missing; evo runs at
nice 10. Build trajdrift first: cargo build --release.
"""
import os
import re
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
VENV = ROOT / "target" / "evo-venv"
BIN = Path(os.environ.get("TRAJDRIFT_BIN", ROOT / "target" / "release" / "trajdrift")).resolve()
DATA = ROOT / "target" / "bench-evo"
SHARED = Path(os.environ.get("TRAJDRIFT_SHARED", ROOT.parent / "shared"))
STATS = ["rmse", "mean", "median", "std", "min", "max", "sse"]

EXTRA_ROWS = [
    "ape tum fr2_desk_groundtruth.txt fr2_desk_ORB.txt -a -r rot_part",
    "ape tum fr2_desk_groundtruth.txt fr2_desk_ORB.txt -a -r full",
    "ape tum fr2_desk_groundtruth.txt fr2_desk_ORB.txt -a -r angle_rad",
    "ape tum fr2_desk_groundtruth.txt fr2_desk_ORB.txt -as",
    "ape tum fr2_desk_groundtruth.txt fr2_desk_ORB.txt -s",
    "ape tum fr2_desk_groundtruth.txt fr2_desk_ORB.txt --align_origin",
    "ape tum fr2_desk_groundtruth.txt fr2_desk_ORB.txt -a --n_to_align 500",
    "ape tum fr2_desk_groundtruth.txt fr2_desk_ORB.txt -a --project_to_plane xy",
    "ape tum fr2_desk_groundtruth.txt fr2_desk_ORB.txt -a --sync_method interpolation",
    "ape tum fr2_desk_groundtruth.txt fr2_desk_ORB.txt -a --t_offset 0.02 --t_max_diff 0.02",
    "rpe tum fr2_desk_groundtruth.txt fr2_desk_ORB.txt -a -r rot_part",
    "rpe tum fr2_desk_groundtruth.txt fr2_desk_ORB.txt -a -r full -d 10",
    "rpe tum fr2_desk_groundtruth.txt fr2_desk_ORB.txt -a -d 10 -u d",
    "rpe tum fr2_desk_groundtruth.txt fr2_desk_ORB.txt -a -d 5 -u d -r angle_deg --all_pairs",
    "rpe tum fr2_desk_groundtruth.txt fr2_desk_ORB.txt -a -d 0.2 -u r --all_pairs",
    "rpe tum fr2_desk_groundtruth.txt fr2_desk_ORB.txt -a -d 1 -u m --pairs_from_reference",
    "rpe tum fr2_desk_groundtruth.txt fr2_desk_ORB.txt -as -d 1 -u m -r point_distance_error_ratio",
    "rpe tum fr2_desk_groundtruth.txt fr2_desk_ORB.txt -a -d 1 -u m --sync_method interpolation",
    "rpe tum freiburg1_xyz-groundtruth.txt freiburg1_xyz-rgbdslam.txt -a -d 20 --all_pairs -r angle_deg",
    "rpe kitti KITTI_00_gt.txt KITTI_00_ORB.txt -d 100 -u m -r angle_deg",
    "rpe kitti KITTI_00_gt.txt KITTI_00_SPTAM.txt -d 200 -u m --all_pairs",
    "ape kitti KITTI_00_gt.txt KITTI_00_SPTAM.txt -as",
    "ape euroc V102_groundtruth.csv V102.txt -a -r angle_deg",
    "rpe euroc V102_groundtruth.csv V102.txt -a -d 1 -u m",
    "ape bag ROS_example.bag groundtruth S-PTAM -a",
    "rpe bag ROS_example.bag groundtruth S-PTAM -d 1 -u m -a",
    "ape bag ROS_example.bag groundtruth S-PTAM -as -r angle_deg",
    "ape mcap nav2_turtlebot.mcap /amcl_pose /odom -a --t_max_diff 0.05 -r angle_deg",
]


def ensure_evo():
    if not (VENV / "bin" / "evo_ape").exists():
        subprocess.run([sys.executable, "-m", "venv", str(VENV)], check=True)
        subprocess.run([str(VENV / "bin" / "pip"), "install", "-q", "evo==1.38.1"], check=True)


def run(cmd, cwd, nice=0):
    """Runs cmd; returns (stdout, wall seconds, peak RSS bytes, exit code, CPU seconds)."""
    start = time.perf_counter()
    p = subprocess.Popen(cmd, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                         preexec_fn=(lambda: os.nice(nice)) if nice else None)
    out = p.stdout.read().decode(errors="replace")
    _, status, usage = os.wait4(p.pid, 0)
    wall = time.perf_counter() - start
    p.returncode = os.waitstatus_to_exitcode(status)
    return out, wall, usage.ru_maxrss * 1024, p.returncode, usage.ru_utime + usage.ru_stime


def stats(out):
    found = {}
    for line in out.splitlines():
        m = re.match(r"\s*(\w+)\s+(-?[\d.]+(?:e[-+]?\d+)?)\s*$", line)
        if m and m.group(1) in STATS:
            found[m.group(1)] = m.group(2)
    return [found.get(s, "?") for s in STATS]


def evo_cmd(row):
    tool, *rest = row.split()
    return [str(VENV / "bin" / f"evo_{tool}"), *rest, "--no_warnings"]


def rows():
    data = SHARED / "evo-data"
    bad = 0
    for row in EXTRA_ROWS:
        e, _, _, ec, _ = run(evo_cmd(row), data, nice=10)
        t, _, _, tc, _ = run([str(BIN), *row.split()], data)
        se, st = stats(e), stats(t)
        same = se == st and ec == 0 and tc == 0
        bad += not same
        print(f"{'same' if same else 'DIFF'}  {row}")
        if not same:
            print(f"      evo       {se} (exit {ec})\n      trajdrift {st} (exit {tc})")
            if ec or tc:
                print("      " + (e if ec else t).strip().splitlines()[-1])
    print(f"extra rows: {len(EXTRA_ROWS) - bad} of {len(EXTRA_ROWS)} equal to 6 decimals")
    return bad


def generate(n=1_000_000):
    DATA.mkdir(parents=True, exist_ok=True)
    ref, est = DATA / "ref_1M.txt", DATA / "est_1M.txt"
    if ref.exists() and est.exists():
        return ref, est
    import numpy as np
    rng = np.random.default_rng(11)
    t = 1_700_000_000.0 + np.arange(n) * 0.01
    s = np.arange(n) * 0.01
    xyz = np.column_stack([50 * np.cos(s / 60), 30 * np.sin(s / 45), 2 * np.sin(s / 20)])
    yaw = s / 60
    q = np.column_stack([np.zeros(n), np.zeros(n), np.sin(yaw / 2), np.cos(yaw / 2)])
    np.savetxt(ref, np.column_stack([t, xyz, q]), fmt="%.6f " + " ".join(["%.6f"] * 3 + ["%.9f"] * 4))
    drift = np.column_stack([1e-4 * s, -5e-5 * s, np.zeros(n)])
    xyz_e = xyz + drift + rng.normal(0, 0.02, (n, 3))
    te = t + rng.uniform(-0.002, 0.002, n)
    yaw_e = yaw + rng.normal(0, 0.002, n)
    qe = np.column_stack([np.zeros(n), np.zeros(n), np.sin(yaw_e / 2), np.cos(yaw_e / 2)])
    np.savetxt(est, np.column_stack([te, xyz_e, qe]), fmt="%.6f " + " ".join(["%.6f"] * 3 + ["%.9f"] * 4))
    return ref, est


def speed():
    ref, est = generate()
    print(f"1 M-pose TUM pair: {ref} / {est}  (load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores)")
    print(f"{'command':<24} {'tool':<10} {'wall s':>8} {'CPU s':>8} {'peak MB':>9} {'rmse':>10}")
    for args in (["ape", "tum", str(ref), str(est), "-a"],
                 ["rpe", "tum", str(ref), str(est), "-d", "1", "-u", "m", "-a"]):
        e_out, e_wall, e_rss, e_code, e_cpu = run(evo_cmd(" ".join(args)), ROOT, nice=10)
        t_out, t_wall, t_rss, t_code, t_cpu = run([str(BIN), *args], ROOT)
        label = " ".join(args[:1] + args[4:])
        for tool, wall, cpu, rss, out, code in (("evo", e_wall, e_cpu, e_rss, e_out, e_code),
                                                ("trajdrift", t_wall, t_cpu, t_rss, t_out, t_code)):
            print(f"{label:<24} {tool:<10} {wall:>8.3f} {cpu:>8.3f} {rss / 1e6:>9.1f} {stats(out)[0]:>10}"
                  + ("" if code == 0 else f"  (exit {code})"))
        same = stats(e_out)[0] == stats(t_out)[0]
        print(f"{label:<24} evo/ours   {e_wall / t_wall:>7.0f}x {e_cpu / t_cpu:>7.0f}x {e_rss / t_rss:>8.1f}x"
              f" {'same rmse' if same else 'RMSE DIFFERS'}")


if __name__ == "__main__":
    ensure_evo()
    which = sys.argv[1:] or ["--rows", "--speed"]
    bad = rows() if "--rows" in which else 0
    if "--speed" in which:
        speed()
    sys.exit(1 if bad else 0)
