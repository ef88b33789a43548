"""raypath.dct_map.fit on a real corrected log: the map and scores of `raypath dct-map`."""

import json

import numpy as np
import pytest

import raypath

from conftest import need


@pytest.fixture(scope="module")
def aces(data):
    return raypath.open(need(data / "carmen/corrected/aces-corrected.log.gz"))


def test_fit_equals_the_cli(aces, cli, tmp_path):
    ours = raypath.dct_map.fit(aces, (8, 8), rays=2000)
    out = tmp_path / "theirs.json"
    theirs = cli("dct-map", aces.path, "--coefficients", "8,8", "--rays", 2000, "--out", out)
    assert list(ours.patch) == theirs["patch"]
    s = ours.scores
    assert s["rays"] == theirs["rays"] and s["held_back_rays"] == theirs["held_back_rays"]
    assert s["iterations"] == theirs["iterations"]
    # The fit sums in parallel; the program's own runs differ in the last digits.
    for key in ("log_likelihood", "grid_log_likelihood", "rmse_p_ref", "grid_rmse_p_ref"):
        assert s[key] == pytest.approx(theirs[key], rel=1e-9), key
    ours.save(tmp_path / "ours.json")
    a = json.loads((tmp_path / "ours.json").read_text())
    b = json.loads(out.read_text())
    assert a["shape"] == b["shape"] and a["extent_m"] == b["extent_m"]
    np.testing.assert_allclose(a["coefficients"], b["coefficients"], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(ours.coefficients.ravel(), a["coefficients"])


def test_arrays(aces):
    m = raypath.dct_map.fit(aces, (4, 6), patch=(-7.0, -25.0, 10.0, 8.0), rays=1000)
    assert m.coefficients.shape == (4, 6)
    rows, cols = m.baseline.shape
    assert rows * cols >= 24 and m.baseline_cell > 0 and np.all(m.baseline > 0)
    rates = m.rates(0.5)
    assert rates.shape == (16, 20) and np.all(rates >= 0)
    inside = m.rate_at([[-6.75, -24.75], [100.0, 0.0]])
    assert inside[0] == pytest.approx(rates[0, 0]) and np.isnan(inside[1])


def test_bad_input(aces):
    with pytest.raises(ValueError, match="coefficients"):
        raypath.dct_map.fit(aces, (0, 4))
    with pytest.raises(ValueError, match="patch"):
        raypath.dct_map.fit(aces, (4, 4), patch=(0, 0, -1, 1))
    with pytest.raises(ValueError, match="rays"):
        raypath.dct_map.fit(aces, (4, 4), rays=0)
    with pytest.raises(raypath.InputError, match="no ray reaches the patch"):
        raypath.dct_map.fit(aces, (4, 4), patch=(1e4, 1e4, 1, 1))
    m = raypath.dct_map.fit(aces, (2, 2), rays=200)
    with pytest.raises(ValueError, match=r"points: expected an array of shape \(N, 2\)"):
        m.rate_at(np.zeros((3, 3)))
    with pytest.raises(ValueError, match="cell"):
        m.rates(0.0)
