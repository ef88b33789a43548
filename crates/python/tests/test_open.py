"""raypath.open: every reader the command line has, and errors that name the file and place."""

import numpy as np
import pytest

import raypath

from conftest import need


def test_carmen_log(data):
    log = raypath.open(need(data / "carmen/raw/intel.clf.bz2"))
    assert isinstance(log, raypath.PlanarLog)
    assert log.format == "carmen"
    assert len(log) == 13631  # the README's scan count of the raw intel log
    assert log.poses.shape == (len(log), 3) and log.poses.dtype == np.float64
    assert log.stamps.shape == (len(log),)
    scan = log[0]
    assert scan.ranges.shape == scan.angles.shape == (180,)
    assert log[-1].stamp == log.stamps[-1]
    with pytest.raises(IndexError):
        log[len(log)]


def test_kitti_sequence_and_bin(data):
    seq = raypath.open(need(data / "kitti/sequences/00"))
    assert isinstance(seq, raypath.SweepLog)
    assert len(seq) == 10
    assert seq.poses.shape == (10, 4, 4)
    np.testing.assert_allclose(seq.poses[:, 3], np.tile([0, 0, 0, 1.0], (10, 1)))
    sweep = seq[0]
    one = raypath.open(data / "kitti/sequences/00/velodyne/000000.bin")
    assert isinstance(one, raypath.Cloud)
    assert one.points.shape == (len(one), 3) and one.points.dtype == np.float32
    np.testing.assert_array_equal(sweep.points, one.points)
    raw = np.fromfile(data / "kitti/sequences/00/velodyne/000000.bin", dtype=np.float32).reshape(-1, 4)
    np.testing.assert_array_equal(one.points, raw[:, :3])
    np.testing.assert_array_equal(one.intensity, raw[:, 3])


def test_organized_pcd(data):
    cloud = raypath.open(need(data / "planes/synpeb-sample-100x100.pcd"))
    assert cloud.is_organized and (cloud.height, cloud.width) == (100, 100)
    grid = cloud.organized()
    assert grid.shape == (100, 100, 3)
    np.testing.assert_array_equal(grid.reshape(-1, 3), cloud.points)


def test_unsupported_file_is_a_format_error(data):
    with pytest.raises(raypath.FormatError) as info:
        raypath.open(data / "README.md")
    assert info.value.path.endswith("README.md")


def test_malformed_file_names_the_line(tmp_path):
    bad = tmp_path / "bad.pcd"
    bad.write_text("# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
                   "WIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA ascii\n1 2 3\n1 2 oops\n")
    with pytest.raises(raypath.FormatError) as info:
        raypath.open(bad)
    assert info.value.path == str(bad)
    assert info.value.line == 12
    assert "bad.pcd:12" in str(info.value)
    assert isinstance(info.value, raypath.RaypathError)


def test_missing_file():
    with pytest.raises(FileNotFoundError):
        raypath.open("/nonexistent/raypath/file.pcd")


def test_empty_file(tmp_path):
    empty = tmp_path / "empty.log"
    empty.write_bytes(b"")
    with pytest.raises(raypath.FormatError):
        raypath.open(empty)
