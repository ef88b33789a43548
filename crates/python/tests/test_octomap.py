"""raypath.open on OctoMap files: a `.bt` tree and a `.graph`, as `raypath info` reads them."""

import numpy as np

import raypath

from conftest import need


def test_bt_equals_info(data, cli):
    path = need(data / "octomap/geb079.bt")
    tree = raypath.open(path)
    info = cli("info", path)
    assert isinstance(tree, raypath.OctreeMap)
    assert len(tree) == info["leaves"]
    assert tree.occupied_leaves == info["occupied_leaves"] == int(tree.occupied.sum())
    assert tree.inner_nodes == info["inner_nodes"]
    assert tree.resolution == info["resolution"] and tree.tree_type == info["tree_type"]
    lo, hi = tree.bounding_box()
    assert list(lo) == info["bbox"]["min"] and list(hi) == info["bbox"]["max"]
    assert tree.centers.shape == (len(tree), 3)
    assert np.all(tree.sizes >= tree.resolution) and tree.depths.max() == 16


def test_graph_equals_info(data, cli):
    path = need(data / "octomap/spherical_scan.graph")
    graph = raypath.open(path)
    info = cli("info", path)
    assert isinstance(graph, raypath.ScanGraph)
    assert len(graph) == info["nodes"] and len(graph.edges) == info["edges"]
    assert sum(len(graph[i]) for i in range(len(graph))) == info["points"]
    assert graph.poses.shape == (len(graph), 4, 4)
    assert graph.edge_poses.shape == (info["edges"], 4, 4)


def test_saved_tree_reads_back(tmp_path):
    tree = raypath.OccupancyTree(resolution=0.5)
    points = np.array([[5.0, 0.0, 0.0], [0.0, 5.0, 0.0]])
    tree.insert(points, np.zeros(3))
    tree.save(tmp_path / "t.bt")
    back = raypath.open(tmp_path / "t.bt")
    assert back.resolution == 0.5 and back.occupied_leaves >= 2
