"""raypath.OccupancyTree (Rtree grid, OctoMap .bt) and Scan Context."""

import numpy as np
import pytest

import raypath

from conftest import need


def test_occupancy_tree(data, tmp_path):
    cloud = raypath.open(need(data / "kitti/sequences/00/velodyne/000000.bin")).points
    tree = raypath.OccupancyTree(resolution=0.2, max_range=30.0)
    near = cloud[np.linalg.norm(cloud, axis=1) < 20]
    assert tree.insert(near, np.zeros(3)) == len(near)
    assert tree.scans == 1 and tree.leaves > 0
    occ = tree.occupancy(np.array([[0.1, 0.1, 0.1], [1000.0, 0.0, 0.0]]))
    assert occ[0] < 0.5 and np.isnan(occ[1])
    out = tmp_path / "map.bt"
    tree.save(out)
    assert out.read_bytes().startswith(b"# Octomap OcTree binary file")


def test_occupancy_tree_bad_input():
    with pytest.raises(ValueError, match="resolution"):
        raypath.OccupancyTree(resolution=0)
    tree = raypath.OccupancyTree()
    with pytest.raises(ValueError, match="origin"):
        tree.insert(np.ones((3, 3)), [0, 0])
    with pytest.raises(ValueError, match="origin"):
        tree.insert(np.ones((3, 3)), [0, 0, np.nan])
    with pytest.raises(ValueError, match="points"):
        tree.insert(np.ones((3, 2)), [0, 0, 0])


def test_scan_context(data):
    seq = raypath.open(need(data / "kitti/sequences/00"))
    pr = raypath.place_recognition.ScanContext()
    for i in (0, 3, 6, 9):
        assert pr.add(seq[i].points) == len(pr) - 1
    best = pr.query(seq[3].points)
    assert best[0][0] == 1 and best[0][1] == pytest.approx(1.0)
    assert [s for _, s in best] == sorted((s for _, s in best), reverse=True)
    assert len(pr.query(seq[4].points, k=2)) == 2
    with pytest.raises(ValueError, match="frame: .*no points"):
        pr.add(np.zeros((0, 3)))
    with pytest.raises(ValueError, match="ScanContext"):
        raypath.place_recognition.ScanContext(num_sectors=0)
