"""raypath.planes.ppe on the SynPEB sample: the planes and labels of `raypath planes`."""

import numpy as np
import pytest

import raypath

from conftest import need


def test_synpeb_equals_the_cli(data, cli, tmp_path):
    pcd = need(data / "planes/synpeb-sample-100x100.pcd")
    labels, planes = raypath.planes.ppe(raypath.open(pcd).organized())
    out = tmp_path / "labels.txt"
    theirs = cli("planes", pcd, "--out", out)
    assert labels.shape == (100, 100) and labels.dtype == np.int32
    assert len(planes) == len(theirs["planes"]) > 0
    for ours, t in zip(planes, theirs["planes"]):
        np.testing.assert_array_equal(ours.normal, t["normal"])
        assert ours.distance == t["distance"]
        assert ours.points == t["points"]
        assert ours.rmse == t["rmse"]
    # The CLI writes label + 1 per point, 0 for none.
    cli_labels = np.loadtxt(out, dtype=np.int64).reshape(100, 100) - 1
    np.testing.assert_array_equal(labels, cli_labels)
    for i, p in enumerate(planes):
        assert np.all(labels.reshape(-1)[p.indices] == i)


def test_no_returns_as_nan(data):
    grid = raypath.open(need(data / "planes/synpeb-sample-100x100.pcd")).organized().astype(np.float64)
    grid[:10] = np.nan
    labels, planes = raypath.planes.ppe(grid)
    assert np.all(labels[:10] == -1)
    assert len(planes) > 0


@pytest.mark.parametrize(
    "xyz, message",
    [
        (np.zeros((10, 10)), r"organized_xyz: expected an organized scan of shape \(H, W, 3\), got shape \[10, 10\]"),
        (np.zeros((10, 10, 4)), r"got shape \[10, 10, 4\]"),
        (np.zeros((0, 10, 3)), r"H, W ≥ 1"),
        (np.zeros((4, 4, 3), dtype=np.int32), r"float32 or float64.*int32"),
        (np.full((4, 4, 3), np.inf), r"point \[0, 0\] is infinite"),
    ],
)
def test_bad_input(xyz, message):
    with pytest.raises(ValueError, match=message):
        raypath.planes.ppe(xyz)


def test_bad_preset():
    with pytest.raises(ValueError, match="preset"):
        raypath.planes.ppe(np.zeros((4, 4, 3)), preset="nope")
