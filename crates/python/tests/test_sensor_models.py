"""raypath.sensor_models on a real corrected log: the statistics of `raypath map`."""

import numpy as np
import pytest

import raypath

from conftest import need


@pytest.fixture(scope="module")
def aces(data):
    return raypath.open(need(data / "carmen/corrected/aces-corrected.log.gz"))


@pytest.mark.parametrize("model", ["reflection", "decay-rate", "log-odds"])
def test_map_equals_the_cli(aces, cli, tmp_path, model):
    ours = raypath.sensor_models.build(aces, model=model, resolution=0.1)
    report = cli("map", aces.path, "--model", model, "--resolution", 0.1, "--out",
                 tmp_path / "aces")
    theirs = raypath.sensor_models.load(tmp_path / "aces.rpmap")
    assert ours.shape == theirs.shape == tuple(report["grid"][::-1])
    assert ours.origin == theirs.origin and ours.resolution == theirs.resolution == 0.1
    assert ours.model == theirs.model == model
    np.testing.assert_array_equal(ours.hits, theirs.hits)
    np.testing.assert_array_equal(ours.misses, theirs.misses)
    np.testing.assert_array_equal(ours.path_length, theirs.path_length)
    np.testing.assert_array_equal(ours.array(), theirs.array())
    assert int(ours.hits.sum()) == report["hits"]
    assert ours.range == (0.0, 80.0)


def test_pictures_and_save(aces, tmp_path):
    m = raypath.sensor_models.build(aces, resolution=0.2, max_range=30.0)
    reflection = m.array()
    np.testing.assert_array_equal(reflection, m.array("reflection"))
    known = ~np.isnan(reflection)
    h, mi = m.hits[known], m.misses[known]
    np.testing.assert_allclose(reflection[known], h / (h + mi))
    decay = m.array("decay-rate")
    assert np.nanmin(decay) >= 0 and np.nanmax(decay) <= 1
    m.save(tmp_path / "m.rpmap")
    back = raypath.sensor_models.load(tmp_path / "m.rpmap")
    np.testing.assert_array_equal(back.hits, m.hits)
    # Poses given explicitly: the log's own poses give the same map.
    again = raypath.sensor_models.build(aces, aces.poses, resolution=0.2, max_range=30.0)
    np.testing.assert_array_equal(again.hits, m.hits)


def test_bad_input(aces, tmp_path):
    with pytest.raises(ValueError, match="model"):
        raypath.sensor_models.build(aces, model="sonar")
    with pytest.raises(ValueError, match="posterior"):
        raypath.sensor_models.build(aces, model="log-odds", posterior=True)
    with pytest.raises(ValueError, match=r"poses: expected an array of shape \(440, 3\)"):
        raypath.sensor_models.build(aces, np.zeros((3, 3)))
    with pytest.raises(ValueError, match="resolution"):
        raypath.sensor_models.build(aces, resolution=0)
    with pytest.raises(ValueError, match="picture"):
        raypath.sensor_models.build(aces, resolution=0.5).array("sonar")
    with pytest.raises(FileNotFoundError):
        raypath.sensor_models.load(tmp_path / "missing.rpmap")
    bad = tmp_path / "bad.rpmap"
    bad.write_bytes(b"not a map")
    with pytest.raises(raypath.FormatError) as error:
        raypath.sensor_models.load(bad)
    assert error.value.path == str(bad)
