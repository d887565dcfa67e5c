"""evo 1.38.1 and trajdrift read each other's result files (.ci/run).

For each command below (rows of shared/evo-data/REFERENCE.md), evo_ape/evo_rpe and trajdrift ape/rpe
write `--save_results` zips of the same command, into E/ and T/ under the same names. Then:

1. evo_res prints the same table for trajdrift's zips as for evo's (its text, 6 decimals), one zip at
   a time and all together (`--use_filenames`);
2. trajdrift res prints evo_res's text for evo's zips (one at a time, all together, `--merge`), and
   `--save_table` writes the same CSV;
3. evo's loader (`file_interface.load_res_file`) finds the same members and array shapes in both;
4. evo_traj and trajdrift traj write the same TUM file for --transform_left/right (with
   --propagate_transform, --invert_transform), --motion_filter, --t_offset and -a/-s --sync onto --ref.

Usage: check_evo_res.py --trajdrift BIN --evo-bin VENV/bin --data shared/evo-data --work DIR
"""

import argparse
import os
import subprocess
import sys
from pathlib import Path

COMMANDS = [
    "ape tum fr2_desk_groundtruth.txt fr2_desk_ORB.txt -a",
    "ape tum fr2_desk_groundtruth.txt fr2_desk_ORB.txt -a -r angle_deg",
    "rpe tum fr2_desk_groundtruth.txt fr2_desk_ORB.txt -d 1 -u m -a",
    "rpe tum fr2_desk_groundtruth.txt fr2_desk_ORB.txt -d 0.5 -u m -a -r point_distance",
    "ape tum freiburg1_xyz-groundtruth.txt freiburg1_xyz-rgbdslam.txt -a --t_max_diff 0.02",
    "ape kitti KITTI_00_gt.txt KITTI_00_ORB.txt -a",
    "rpe kitti KITTI_00_gt.txt KITTI_00_ORB.txt -d 100 -u m -r point_distance_error_ratio",
    "ape euroc V102_groundtruth.csv V102.txt -as",
    "ape bag ROS_example.bag groundtruth ORB-SLAM -a",
    "ape mcap nav2_turtlebot.mcap /amcl_pose /odom -a --t_max_diff 0.05",
]


def run(cmd, cwd):
    p = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, stdin=subprocess.DEVNULL)
    if p.returncode != 0:
        sys.exit(f"FAIL: {' '.join(map(str, cmd))} (exit {p.returncode})\n{p.stdout}\n{p.stderr}")
    return p.stdout


def table(text):
    """evo_res's output without its log lines ([WARNING] ..., merge notes)."""
    keep = [
        l
        for l in text.splitlines()
        if not l.startswith("[") and not l.startswith(("Averaging", "Appending", "Using info"))
    ]
    return "\n".join(keep).strip("\n")


def same(what, a, b):
    if table(a) != table(b):
        sys.exit(f"FAIL: {what}\n--- expected\n{a}\n--- got\n{b}")
    print(f"ok: {what}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--trajdrift", required=True)
    ap.add_argument("--evo-bin", required=True)
    ap.add_argument("--data", required=True)
    ap.add_argument("--work", required=True)
    a = ap.parse_args()
    trajdrift = str(Path(a.trajdrift).resolve())
    evo = Path(a.evo_bin).resolve()
    data = Path(a.data).resolve()
    work = Path(a.work).resolve()
    e_dir, t_dir = work / "E", work / "T"
    e_dir.mkdir(parents=True, exist_ok=True)
    t_dir.mkdir(parents=True, exist_ok=True)
    os.environ["MPLBACKEND"] = "Agg"

    names = []
    for i, command in enumerate(COMMANDS):
        tool, *args = command.split()
        name = f"r{i:02d}_{tool}.zip"
        names.append(name)
        run([str(evo / f"evo_{tool}"), *args, "--save_results", str(e_dir / name), "--no_warnings"], data)
        run([trajdrift, tool, *args, "--save_results", str(t_dir / name), "--silent"], data)
        print(f"ok: both wrote {name} for `{command}`")

    evo_res = str(evo / "evo_res")
    for name in names:
        same(
            f"evo_res {name}: trajdrift's zip gives evo's table",
            run([evo_res, name], e_dir),
            run([evo_res, name], t_dir),
        )
        same(
            f"trajdrift res {name} prints evo_res's table",
            run([evo_res, name], e_dir),
            run([trajdrift, "res", name], e_dir),
        )
    group = ["--use_filenames", "--no_warnings"]
    same(
        "evo_res over all of trajdrift's zips (--use_filenames)",
        run([evo_res, *names, *group], e_dir),
        run([evo_res, *names, *group], t_dir),
    )
    same(
        "trajdrift res over all of evo's zips (--use_filenames)",
        run([evo_res, *names, *group], e_dir),
        run([trajdrift, "res", *names, *group], e_dir),
    )
    ape_fr2 = [names[0], names[4]]
    same(
        "trajdrift res --merge over evo's zips",
        run([evo_res, *ape_fr2, "--merge", "--no_warnings"], e_dir),
        run([trajdrift, "res", *ape_fr2, "--merge", "--no_warnings"], e_dir),
    )
    run([evo_res, *names, *group, "--save_table", str(work / "evo.csv")], e_dir)
    run([trajdrift, "res", *names, *group, "--save_table", str(work / "trajdrift.csv")], e_dir)
    same(
        "--save_table CSV of evo's zips",
        (work / "evo.csv").read_text(),
        (work / "trajdrift.csv").read_text(),
    )

    # evo's own loader on both: the same members, the same array shapes.
    sys.path.insert(0, "")
    from evo.tools import file_interface

    for name in names:
        e = file_interface.load_res_file(str(e_dir / name))
        t = file_interface.load_res_file(str(t_dir / name))
        if e.info != t.info or list(e.stats) != list(t.stats):
            sys.exit(f"FAIL: {name}: info or stats keys differ\n{e.info}\n{t.info}")
        shapes = lambda r: {k: v.shape for k, v in r.np_arrays.items()}
        if shapes(e) != shapes(t):
            sys.exit(f"FAIL: {name}: arrays differ\n{shapes(e)}\n{shapes(t)}")
        worst = max(abs(e.stats[k] - t.stats[k]) / max(1.0, abs(e.stats[k])) for k in e.stats)
        if worst > 1e-9:
            sys.exit(f"FAIL: {name}: statistics differ by {worst} (relative)")
    print(f"ok: evo's load_res_file reads {len(names)} trajdrift zips with evo's info, members and shapes")

    # evo_traj and trajdrift traj write the same TUM file for the same transformations.
    import json

    import numpy as np

    tf = work / "t.json"
    tf.write_text(json.dumps({"x": 0.5, "y": -1.0, "z": 0.2, "qx": 0.0, "qy": 0.0,
                              "qz": 0.3826834, "qw": 0.9238795, "scale": 1.0}))
    est, ref = str(data / "freiburg1_xyz-rgbdslam.txt"), str(data / "freiburg1_xyz-groundtruth.txt")
    modes = [
        ["--transform_left", str(tf)],
        ["--transform_right", str(tf)],
        ["--transform_right", str(tf), "--propagate_transform"],
        ["--transform_left", str(tf), "--invert_transform"],
        ["--motion_filter", "0.05", "5"],
        ["--t_offset", "0.25"],
        ["--ref", ref, "-a", "--sync"],
        ["--ref", ref, "-as", "--sync", "--n_to_align", "100"],
    ]
    for k, mode in enumerate(modes):
        e, t = work / f"traj{k}" / "E", work / f"traj{k}" / "T"
        e.mkdir(parents=True)
        t.mkdir(parents=True)
        run([str(evo / "evo_traj"), "tum", est, *mode, "--save_as_tum", "--no_warnings"], e)
        run([trajdrift, "traj", "tum", est, *mode, "--save_as_tum", "--silent"], t)
        a = np.loadtxt(e / "freiburg1_xyz-rgbdslam.tum")
        b = np.loadtxt(t / "freiburg1_xyz-rgbdslam.tum")
        if a.shape != b.shape:
            sys.exit(f"FAIL: evo_traj {' '.join(mode)}: {a.shape} poses, trajdrift {b.shape}")
        dq = np.minimum(abs(a[:, 4:] - b[:, 4:]).max(axis=1), abs(a[:, 4:] + b[:, 4:]).max(axis=1))
        worst = max(abs(a[:, :4] - b[:, :4]).max(), dq.max())
        if worst > 1e-6:
            sys.exit(f"FAIL: evo_traj {' '.join(mode)}: the TUM files differ by {worst}")
        print(f"ok: evo_traj and trajdrift traj {' '.join(mode)} write the same TUM (within {worst:.1e})")
    print(f"{3 * len(names) + 5 + len(modes)} passed, 0 failed")


if __name__ == "__main__":
    main()
