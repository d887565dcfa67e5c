"""evo objects in and out: with evo 1.38.1 installed, trajdrift.ape/rpe equal evo.main_ape.ape /
evo.main_rpe.rpe on the shared data (evo's trajectories passed in as they are, or trajdrift's), and a
PoseTrajectory3D round-trips through trajdrift.Trajectory."""

from __future__ import annotations

import copy

import numpy as np
import pytest

import trajdrift

evo = pytest.importorskip("evo", reason="evo is installed in CI's test environment")
from evo.core import metrics, sync  # noqa: E402
from evo.core.trajectory import PosePath3D, PoseTrajectory3D  # noqa: E402
from evo.tools import file_interface  # noqa: E402
import evo.main_ape as main_ape  # noqa: E402
import evo.main_rpe as main_rpe  # noqa: E402

PAIRS = [
    ("fr2_desk_groundtruth.txt", "fr2_desk_ORB.txt"),
    ("freiburg1_xyz-groundtruth.txt", "freiburg1_xyz-rgbdslam.txt"),
]


def evo_tum(path):
    return file_interface.read_tum_trajectory_file(str(path))


def same(a: float, b: float) -> bool:
    return abs(a - b) <= 1e-9 * max(1.0, abs(b))


def assert_same_result(ours, theirs):
    for k in trajdrift.STATISTICS:
        assert same(ours.stats[k], theirs.stats[k]), (k, ours.stats[k], theirs.stats[k])
    a, b = ours.error_array, theirs.np_arrays["error_array"]
    assert a.shape == b.shape and np.allclose(a, b, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("ref_file,est_file", PAIRS)
@pytest.mark.parametrize(
    "relation,align,scale",
    [
        (metrics.PoseRelation.translation_part, True, False),
        (metrics.PoseRelation.translation_part, True, True),
        (metrics.PoseRelation.rotation_angle_deg, True, False),
        (metrics.PoseRelation.full_transformation, False, False),
    ],
)
def test_ape_equals_evo_main_ape(evo_data, ref_file, est_file, relation, align, scale):
    ref, est = evo_tum(evo_data / ref_file), evo_tum(evo_data / est_file)
    r, e = sync.associate_trajectories(copy.deepcopy(ref), copy.deepcopy(est), max_diff=0.01)
    theirs = main_ape.ape(r, e, relation, align=align, correct_scale=scale)
    # evo's objects as they are, and the same files read by trajdrift.
    for a, b in ((ref, est), (trajdrift.read(evo_data / ref_file), trajdrift.read(evo_data / est_file))):
        ours = trajdrift.ape(a, b, pose_relation=relation, align=align, correct_scale=scale)
        assert_same_result(ours, theirs)
        assert np.allclose(ours.np_arrays["timestamps"], theirs.np_arrays["timestamps"], rtol=0, atol=1e-9)


def test_ape_on_kitti_paths_equals_evo(evo_data):
    ref = file_interface.read_kitti_poses_file(str(evo_data / "KITTI_00_gt.txt"))
    est = file_interface.read_kitti_poses_file(str(evo_data / "KITTI_00_ORB.txt"))
    theirs = main_ape.ape(ref, est, metrics.PoseRelation.translation_part, align=True)
    assert_same_result(trajdrift.ape(ref, est), theirs)
    ours = trajdrift.ape(trajdrift.read(evo_data / "KITTI_00_gt.txt"),
                         trajdrift.read(evo_data / "KITTI_00_ORB.txt"))
    assert_same_result(ours, theirs)


def test_rpe_equals_evo_main_rpe(evo_data):
    ref = evo_tum(evo_data / "fr2_desk_groundtruth.txt")
    est = evo_tum(evo_data / "fr2_desk_ORB.txt")
    for unit, delta in ((metrics.Unit.meters, 0.5), (metrics.Unit.frames, 1)):
        # evo's rpe aligns its arguments in place: fresh copies each time.
        r, e = sync.associate_trajectories(copy.deepcopy(ref), copy.deepcopy(est), max_diff=0.01)
        theirs = main_rpe.rpe(r, e, metrics.PoseRelation.translation_part, delta=delta, delta_unit=unit,
                             align=True)
        ours = trajdrift.rpe(ref, est, delta=delta, delta_unit=unit, align=True)
        assert_same_result(ours, theirs)
        assert ours.pairs.shape == (len(ours.error_array), 2)


def test_pose_trajectory_round_trips(evo_data):
    theirs = evo_tum(evo_data / "fr2_desk_ORB.txt")
    ours = trajdrift.Trajectory.from_evo(theirs)
    assert ours.t.dtype == np.int64 and ours.quat.shape == (theirs.num_poses, 4)
    back = ours.to_evo()
    assert isinstance(back, PoseTrajectory3D)
    assert np.array_equal(back.timestamps, theirs.timestamps)
    assert np.array_equal(back.positions_xyz, theirs.positions_xyz)
    assert np.array_equal(back.orientations_quat_wxyz, theirs.orientations_quat_wxyz)
    # trajdrift's reader gives evo's reader's stamps, positions and (normalised) quaternions.
    read = trajdrift.read(evo_data / "fr2_desk_ORB.txt").to_evo()
    assert np.array_equal(read.timestamps, theirs.timestamps)
    assert np.array_equal(read.positions_xyz, theirs.positions_xyz)
    assert np.allclose(read.orientations_quat_wxyz, theirs.orientations_quat_wxyz, rtol=0, atol=1e-6)


def test_kitti_path_round_trips_with_its_matrices(evo_data):
    theirs = file_interface.read_kitti_poses_file(str(evo_data / "KITTI_00_ORB.txt"))
    ours = trajdrift.Trajectory.from_evo(theirs)
    assert ours.stamp_seconds is None and ours.rot is not None
    back = ours.to_evo()
    assert isinstance(back, PosePath3D) and not isinstance(back, PoseTrajectory3D)
    assert np.array_equal(np.array(back.poses_se3), np.array(theirs.poses_se3))


def test_evo_objects_are_accepted_by_the_evaluation(evo_data):
    ref = evo_tum(evo_data / "fr2_desk_groundtruth.txt")
    est = evo_tum(evo_data / "fr2_desk_ORB.txt")
    report = trajdrift.evaluate(reference=ref, estimates={"orb": est}, metrics="ape")
    ape = report.estimates["orb"].standard_metrics["ape"]
    assert ape["stats"]["rmse"] > 0
