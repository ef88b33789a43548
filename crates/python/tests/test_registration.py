"""raypath.registration.register on two real KITTI scans: the pose of `raypath register`."""

import numpy as np
import pytest

import raypath

from conftest import need


def quaternion_xyzw(r):
    """The unit quaternion of a rotation matrix (w ≥ 0)."""
    w = np.sqrt(max(0.0, 1.0 + np.trace(r))) / 2
    x = np.copysign(np.sqrt(max(0.0, 1 + r[0, 0] - r[1, 1] - r[2, 2])) / 2, r[2, 1] - r[1, 2])
    y = np.copysign(np.sqrt(max(0.0, 1 - r[0, 0] + r[1, 1] - r[2, 2])) / 2, r[0, 2] - r[2, 0])
    z = np.copysign(np.sqrt(max(0.0, 1 - r[0, 0] - r[1, 1] + r[2, 2])) / 2, r[1, 0] - r[0, 1])
    return np.array([x, y, z, w])


def test_kitti_pair_equals_the_cli(data, cli):
    velodyne = data / "kitti/sequences/00/velodyne"
    a, b = need(velodyne / "000000.bin"), need(velodyne / "000001.bin")
    found = raypath.registration.register(raypath.open(a).points, raypath.open(b).points)
    theirs = cli("register", a, b)
    np.testing.assert_array_equal(found.pose[:3, 3], theirs["target_from_source"]["translation_m"])
    q = np.array(theirs["target_from_source"]["rotation_xyzw"])
    q = q if q[3] >= 0 else -q
    np.testing.assert_allclose(quaternion_xyzw(found.pose[:3, :3]), q, atol=1e-12)
    assert found.fitness == theirs["fitness"]
    assert found.rmse == theirs["rmse_m"]
    assert found.iterations == theirs["iterations"]
    assert found.converged == theirs["converged"] is True
    assert found.correspondences == theirs["correspondences"]
    assert found.source_points == theirs["source_points"]
    np.testing.assert_array_equal(found.pose[3], [0, 0, 0, 1])


def test_known_motion():
    rng = np.random.default_rng(3)
    # Ground, two walls and a back wall, 0.2 m apart.
    u, v = np.meshgrid(np.arange(-10, 10, 0.2), np.arange(0, 8, 0.2))
    u, v = u.ravel(), v.ravel()
    target = np.vstack([
        np.column_stack([u, v - 4, np.full_like(u, -1.7)]),
        np.column_stack([u, np.full_like(u, 6.0), v - 1.7]),
        np.column_stack([u, np.full_like(u, -6.0), v - 1.7]),
        np.column_stack([np.full_like(u, 15.0), u / 2, v - 1.7]),
    ]) + rng.normal(scale=0.002, size=(4 * len(u), 3))
    yaw = np.radians(2.0)
    truth = np.eye(4)
    truth[:2, :2] = [[np.cos(yaw), -np.sin(yaw)], [np.sin(yaw), np.cos(yaw)]]
    truth[:3, 3] = [0.5, 0.1, 0.0]
    inverse = np.linalg.inv(truth)
    source = target @ inverse[:3, :3].T + inverse[:3, 3]
    found = raypath.registration.register(source, target.astype(np.float32), voxel_size=0.3)
    assert found.converged
    np.testing.assert_allclose(found.pose, truth, atol=0.01)
    again = raypath.registration.register(source, target.astype(np.float32), found.pose,
                                          voxel_size=0.3, kernel="huber")
    np.testing.assert_allclose(again.pose, truth, atol=0.01)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"source": np.zeros((5, 2))}, r"source: expected an array of shape \(N, 3 or 4\)"),
        ({"target": np.zeros((5, 3), dtype=np.int32)}, r"target: expected .*float32 or float64"),
        ({"target": np.empty((0, 3))}, r"target: .*no points"),
        ({"source": np.full((5, 3), np.nan)}, r"source: row 0 is not finite"),
        ({"initial": np.eye(3)}, r"initial: expected a rigid transform of shape \(4, 4\)"),
        ({"initial": 3 * np.eye(4)}, r"initial: the upper-left 3 × 3 block is not a rotation"),
        ({"kernel": "cauchy"}, r"kernel: expected"),
        ({"voxel_size": -1.0}, r"register: "),
    ],
)
def test_bad_input(kwargs, message):
    points = np.random.default_rng(0).normal(size=(50, 3))
    args = {"source": points, "target": points, **kwargs}
    with pytest.raises(ValueError, match=message):
        raypath.registration.register(**args)


def test_too_few_points_is_an_input_error():
    with pytest.raises(raypath.InputError):
        raypath.registration.register(np.zeros((3, 3)), np.zeros((3, 3)))


def test_odometry_equals_the_cli(data, cli):
    sequence = need(data / "kitti/sequences/00")
    theirs = cli("register", sequence, "--frames", 4)["steps"]
    seq = raypath.open(sequence)
    odometry = raypath.registration.Odometry()
    for k, step in enumerate(theirs):
        pose, found = odometry.register_frame(seq[k].points)
        np.testing.assert_array_equal(pose[:3, 3], step["translation_m"])
        if k == 0:
            assert found is None and step["iterations"] is None
        else:
            assert found.fitness == step["fitness"] and found.iterations == step["iterations"]
    assert odometry.poses.shape == (4, 4, 4) and len(odometry) == 4
    with pytest.raises(ValueError, match="kernel"):
        raypath.registration.Odometry(kernel="x")
    with pytest.raises(ValueError, match="points"):
        odometry.register_frame(np.zeros((4, 2)))
