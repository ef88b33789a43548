"""raypath.scan_match on a real CARMEN log: the trajectory of `raypath scan-match`."""

import numpy as np
import pytest

import raypath

from conftest import need

SCANS = 150


@pytest.fixture(scope="module")
def aces(data):
    return raypath.open(need(data / "carmen/corrected/aces-corrected.log.gz"))


def test_log_equals_the_cli(data, aces, cli, tmp_path):
    ours = raypath.scan_match.match_log(aces, scans=SCANS)
    out = tmp_path / "aces.tum"
    theirs = cli("scan-match", aces.path, "--scans", SCANS, "--out", out)
    assert theirs["scans"] == SCANS == len(ours)
    tum = np.loadtxt(out)
    # The TUM file prints 6 decimals of x, y and 9 of the quaternion.
    np.testing.assert_allclose(ours[:, :2], tum[:, 1:3], atol=5e-7, rtol=0)
    yaw = 2 * np.arctan2(tum[:, 6], tum[:, 7])
    np.testing.assert_allclose(np.angle(np.exp(1j * (ours[:, 2] - yaw))), 0, atol=2e-8)


def test_step_by_step_equals_the_log_run(aces):
    whole = raypath.scan_match.match_log(aces, scans=40, odometry=True)
    matcher = raypath.scan_match.ScanMatcher()
    previous = None
    for i in range(40):
        scan = aces[i]
        delta = None
        if previous is not None:
            delta = relative(previous, scan.pose)
        previous = scan.pose
        pose, covariance = matcher.match_scan(scan.ranges, scan.angles, delta)
        assert pose.shape == (3,) and covariance.shape == (3, 3)
        np.testing.assert_allclose(pose, whole[i], atol=1e-9)
    np.testing.assert_array_equal(matcher.pose, pose)
    assert matcher.updates > 0
    grid = matcher.map
    assert grid.ndim == 2 and np.nanmax(grid) > 0.5
    assert matcher.map_origin[2] == 0.05


def relative(a, b):
    """`a⁻¹ · b` of planar poses (x, y, theta)."""
    c, s = np.cos(a[2]), np.sin(a[2])
    dx, dy = b[0] - a[0], b[1] - a[1]
    return np.array([c * dx + s * dy, -s * dx + c * dy, b[2] - a[2]])


def test_bad_input():
    matcher = raypath.scan_match.ScanMatcher()
    angles = np.linspace(-1.5, 1.5, 10)
    with pytest.raises(ValueError, match="angles: must be evenly spaced"):
        matcher.match_scan(np.ones(10), angles[::-1])
    with pytest.raises(ValueError, match=r"angles: expected shape \(10,\)"):
        matcher.match_scan(np.ones(10), angles[:5])
    with pytest.raises(ValueError, match="ranges: value 3 is NaN"):
        matcher.match_scan(np.where(np.arange(10) == 3, np.nan, 1.0), angles)
    with pytest.raises(ValueError, match=r"odometry_delta: expected a pose \(x, y, theta\)"):
        matcher.match_scan(np.ones(10), angles, [1.0, 2.0])
    with pytest.raises(ValueError, match="max_range"):
        raypath.scan_match.ScanMatcher(max_range=0)
    with pytest.raises(ValueError, match="ScanMatcher"):
        raypath.scan_match.ScanMatcher(levels=0)
