"""raypath.polylines.ple on a real scan: the polylines of `raypath polylines`."""

import numpy as np
import pytest

import raypath

from conftest import need


def test_intel_scan_equals_the_cli(data, cli):
    path = need(data / "carmen/corrected/intel-corrected.log.gz")
    scan = raypath.open(path)[5]
    lines = raypath.polylines.ple(scan.ranges, scan.angles, max_range=scan.max_range)
    theirs = cli("polylines", path, "--scans", "5")["scans"][0]["polylines"]
    assert len(lines) == len(theirs) > 0
    for ours, t in zip(lines, theirs):
        np.testing.assert_allclose(ours.vertices, t, rtol=0, atol=1e-9)


def test_synthetic_square():
    angles = np.linspace(-np.pi, np.pi, 721)[:-1]
    # A 4 m × 4 m room around the sensor.
    ranges = 2.0 / np.maximum(np.abs(np.cos(angles)), np.abs(np.sin(angles)))
    lines = raypath.polylines.ple(ranges, angles, max_vertices=8)
    assert 1 <= len(lines) <= 2
    vertices = np.vstack([l.vertices for l in lines])
    assert np.all(np.abs(np.abs(vertices).max(axis=1) - 2.0) < 0.05)


@pytest.mark.parametrize(
    "ranges, angles, message",
    [
        (np.ones(10), np.linspace(0, 1, 9), r"angles: expected shape \(10,\)"),
        (np.ones(10), np.r_[np.linspace(0, 1, 9), 5.0], "evenly spaced"),
        (np.ones(10), np.linspace(1, 0, 10), "evenly spaced and increasing"),
        (np.r_[np.ones(9), np.nan], np.linspace(0, 1, 10), "ranges: value 9 is NaN"),
        (np.r_[np.ones(9), -1.0], np.linspace(0, 1, 10), "ranges: value 9 is negative"),
        (np.ones(1), np.zeros(1), "at least 2"),
        (np.ones((2, 5)), np.linspace(0, 1, 10), r"ranges: expected an array of shape \(N,\)"),
        (np.ones(10, dtype=int), np.linspace(0, 1, 10), "ranges: .*int64"),
    ],
)
def test_bad_input(ranges, angles, message):
    with pytest.raises(ValueError, match=message):
        raypath.polylines.ple(ranges, angles)


def test_bad_parameters():
    with pytest.raises(ValueError, match="method"):
        raypath.polylines.ple(np.ones(10), np.linspace(0, 1, 10), method="x")
    with pytest.raises(ValueError, match="max_vertices"):
        raypath.polylines.ple(np.ones(10), np.linspace(0, 1, 10), max_vertices=1)
