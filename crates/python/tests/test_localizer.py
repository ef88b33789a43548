"""raypath.Localizer, one scan at a time on a real log: the final pose of `raypath localize`."""

import numpy as np
import pytest

import raypath

from conftest import need

PARTICLES = 100
SEED = 3


@pytest.fixture(scope="module")
def aces(data):
    return raypath.open(need(data / "carmen/corrected/aces-corrected.log.gz"))


def run(log, sensor_map, seed=SEED):
    first = log[0]
    loc = raypath.Localizer(sensor_map, first.odometry, particles=PARTICLES, seed=seed,
                            robot_from_laser=first.robot_from_laser)
    for scan in log:
        loc.step(scan.odometry, scan)
    return loc


def test_log_equals_the_cli(aces, cli, tmp_path):
    cli("map", aces.path, "--model", "reflection", "--resolution", 0.1, "--out",
        tmp_path / "aces")
    theirs = cli("localize", "--map", tmp_path / "aces.rpmap", "--log", aces.path,
                 "--particles", PARTICLES, "--seed", SEED)
    ours = run(aces, raypath.sensor_models.load(tmp_path / "aces.rpmap"))
    # Poses reach the filter through (x, y, theta) arrays: equal to rounding (the Rust poses
    # keep cos and sin), not bit for bit.
    np.testing.assert_allclose(ours.pose, theirs["final_pose"], atol=1e-9, rtol=0)
    assert ours.updates == theirs["updates"]
    assert ours.resamplings == theirs["resamplings"]
    assert ours.failed_updates == theirs["failed_updates"]
    assert ours.model == theirs["model"]
    # A map built in Python is the same map.
    built = raypath.sensor_models.build(aces, resolution=0.1)
    np.testing.assert_array_equal(run(aces, built).pose, ours.pose)


def test_seeded_and_arrays(aces):
    m = raypath.sensor_models.build(aces, resolution=0.2, max_range=30.0)
    first = aces[0]
    a = raypath.Localizer(m, first.odometry, particles=50, seed=7)
    b = raypath.Localizer(m, first.odometry, particles=50, seed=7)
    c = raypath.Localizer(m, first.odometry, particles=50, seed=8)
    for loc in (a, b, c):
        for i in range(30):
            scan = aces[i]
            # Arrays instead of a Scan: the same update.
            loc.step(scan.odometry, scan.ranges, scan.angles, max_range=scan.max_range,
                     force=i == 0)
    np.testing.assert_array_equal(a.particles, b.particles)
    assert not np.array_equal(a.particles, c.particles)
    assert a.particles.shape == (50, 3) and len(a) == 50
    assert a.weights.shape == (50,) and abs(a.weights.sum() - 1) < 1e-9
    assert a.updates >= 1


def test_bad_input(aces):
    m = raypath.sensor_models.build(aces, resolution=0.5, max_range=30.0)
    with pytest.raises(ValueError, match=r"initial: expected a pose \(x, y, theta\)"):
        raypath.Localizer(m, [0.0, 0.0])
    with pytest.raises(ValueError, match="particles"):
        raypath.Localizer(m, [0, 0, 0], particles=0)
    with pytest.raises(ValueError, match="model"):
        raypath.Localizer(m, [0, 0, 0], model="sonar")
    with pytest.raises(ValueError, match="effective_beams"):
        raypath.Localizer(m, [0, 0, 0], effective_beams=float("nan"))
    loc = raypath.Localizer(m, [0, 0, 0], particles=10)
    with pytest.raises(ValueError, match="angles: expected an array"):
        loc.step([0, 0, 0], np.ones(10))
    with pytest.raises(ValueError, match="angles: must be None"):
        loc.step([0, 0, 0], aces[0], np.ones(10))
    with pytest.raises(ValueError, match="odometry"):
        loc.step([0, 0, np.inf], aces[0])
    with pytest.raises(TypeError):
        raypath.Localizer(np.zeros((10, 10)), [0, 0, 0])
