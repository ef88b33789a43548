"""raypath.poles.extract on a real KITTI scan: the poles of `raypath poles extract`."""

import numpy as np
import pytest

import raypath

from conftest import need


def test_kitti_scan_equals_the_cli(data, cli):
    seq = raypath.open(need(data / "kitti/sequences/00"))
    poles = raypath.poles.extract(seq[0].points, pose=seq.poses[0])
    theirs = cli("poles", "extract", data / "kitti/sequences/00", "--max-scans", "1",
                 "--sweep-timing", "origin")["poles"]
    assert len(poles) == len(theirs) > 0
    np.testing.assert_array_equal(poles.xy, [[p["x"], p["y"]] for p in theirs])
    np.testing.assert_array_equal(poles.width, [p["width"] for p in theirs])
    np.testing.assert_array_equal(poles.height, [p["height"] for p in theirs])
    np.testing.assert_array_equal(poles.score, [p["score"] for p in theirs])
    assert poles.array.shape == (len(poles), 3)
    np.testing.assert_array_equal(poles.array[:, 2], poles.width / 2)


def test_float64_and_four_columns(data):
    cloud = raypath.open(need(data / "kitti/sequences/00/velodyne/000000.bin"))
    single = raypath.poles.extract(cloud.points)
    double = raypath.poles.extract(cloud.points.astype(np.float64))
    with_intensity = raypath.poles.extract(np.column_stack([cloud.points, cloud.intensity]))
    np.testing.assert_array_equal(single.array, double.array)
    np.testing.assert_array_equal(single.array, with_intensity.array)
    # A non-contiguous view reads the same.
    wide = np.zeros((len(cloud), 6), dtype=np.float32)
    wide[:, ::2] = cloud.points
    np.testing.assert_array_equal(raypath.poles.extract(wide[:, ::2]).array, single.array)


@pytest.mark.parametrize(
    "points, message",
    [
        (np.zeros((10, 3), dtype=np.int64), r"points: expected .*float32 or float64.*int64"),
        (np.zeros((10, 2)), r"points: expected an array of shape \(N, 3 or 4\), got shape \(10, 2\)"),
        (np.zeros(30), r"points: expected an array of shape \(N, 3 or 4\), got shape \[30\]"),
        (np.zeros((0, 3)), r"points: .*no points"),
        (np.array([[1.0, 2.0, np.nan]]), r"points: row 0 is not finite"),
        (np.array([[1.0, np.inf, 0.0]]), r"points: row 0 is not finite"),
        ("not an array", r"points: expected"),
    ],
)
def test_bad_points(points, message):
    with pytest.raises(ValueError, match=message):
        raypath.poles.extract(points)


def test_bad_pose_and_preset():
    points = np.random.default_rng(1).normal(size=(100, 3))
    with pytest.raises(ValueError, match=r"pose: expected a rigid transform of shape \(4, 4\)"):
        raypath.poles.extract(points, pose=np.eye(3))
    with pytest.raises(ValueError, match="pose: the upper-left 3 × 3 block is not a rotation"):
        raypath.poles.extract(points, pose=2 * np.eye(4))
    with pytest.raises(ValueError, match="preset"):
        raypath.poles.extract(points, preset="nope")
    assert len(raypath.poles.extract(points, pose=np.eye(4, dtype=int), preset="nclt")) == 0
