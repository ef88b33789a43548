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


def test_pole_map_equals_the_cli(data, cli, tmp_path):
    sequence = need(data / "kitti/sequences/00")
    theirs = cli("poles", "map", sequence, "--out", tmp_path / "map.csv")["poles"]
    ours = raypath.poles.map(raypath.open(sequence))
    assert len(ours) == len(theirs) > 0
    np.testing.assert_array_equal(ours.xy, [[p["x"], p["y"]] for p in theirs])
    np.testing.assert_array_equal(ours.width, [p["width"] for p in theirs])
    np.testing.assert_array_equal(ours.height, [p["height"] for p in theirs])
    np.testing.assert_array_equal(ours.score, [p["score"] for p in theirs])
    # A path is the same input.
    np.testing.assert_array_equal(raypath.poles.map(sequence).xy, ours.xy)


def test_pole_filter_on_a_map():
    rng = np.random.default_rng(5)
    poles = rng.uniform(-30, 30, size=(40, 2))
    truth = np.array([1.0, -2.0, 0.3])
    pf = raypath.poles.PoleFilter(poles, truth + [0.5, -0.5, 0.05], particles=500, seed=4)
    again = raypath.poles.PoleFilter(poles, truth + [0.5, -0.5, 0.05], particles=500, seed=4)
    c, s = np.cos(truth[2]), np.sin(truth[2])
    d = poles - truth[:2]
    seen = np.column_stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]])
    seen = seen[np.linalg.norm(seen, axis=1) < 25]
    for f in (pf, again):
        for _ in range(5):
            f.predict([0.0, 0.0, 0.0], [0.05, 0.05, 0.01])
            f.update(seen)
    np.testing.assert_array_equal(pf.particles, again.particles)
    assert np.linalg.norm(pf.pose[:2] - truth[:2]) < 0.3
    assert pf.particles.shape == (500, 3) and len(pf) == 500


def test_pole_filter_bad_input(data):
    with pytest.raises(ValueError, match=r"map: expected Poles or an array of shape \(M, 2\)"):
        raypath.poles.PoleFilter(np.zeros((3, 3)), [0, 0, 0])
    with pytest.raises(ValueError, match="start"):
        raypath.poles.PoleFilter(np.zeros((3, 2)), [0, 0])
    with pytest.raises(ValueError, match="preset"):
        raypath.poles.PoleFilter(np.zeros((3, 2)), [0, 0, 0], preset="mars")
    pf = raypath.poles.PoleFilter(np.zeros((3, 2)), [0, 0, 0], particles=10)
    with pytest.raises(ValueError, match=r"poles: expected an array of shape \(K, 2\)"):
        pf.update(np.zeros(4))
    with pytest.raises(ValueError, match=r"std: expected shape \(3,\)"):
        pf.predict([0, 0, 0], [1, 1])
    with pytest.raises(ValueError, match="sweep_timing"):
        raypath.poles.map(data / "kitti/sequences/00", sweep_timing="late")
    with pytest.raises(ValueError, match="sequence"):
        raypath.poles.map(3)
