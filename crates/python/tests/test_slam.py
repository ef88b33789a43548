"""raypath.slam on the real intel log: the same relation errors as `raypath slam --relations`."""

import numpy as np
import pytest

import raypath

from conftest import need


@pytest.fixture(scope="module")
def intel(data):
    log = raypath.open(need(data / "carmen/raw/intel.clf.bz2"))
    calls = []
    result = raypath.slam(log, progress=lambda done, total: calls.append((done, total)))
    return log, result, calls


def test_relation_errors_equal_the_cli(data, intel, cli, tmp_path):
    _, result, _ = intel
    relations = need(data / "carmen/relations/intel.relations")
    ours = result.relation_errors(relations)
    theirs = cli("slam", data / "carmen/raw/intel.clf.bz2", "--out", tmp_path / "slam",
                 "--relations", relations)["relations_file"]
    assert ours["relations"] == theirs["summary"]["relations"]
    assert ours["unmatched"] == theirs["unmatched"]
    for key in ("trans_error_m", "trans_error_std_m", "rot_error_deg", "rot_error_std_deg"):
        assert ours[key] == theirs["summary"][key], key
    assert len(result.loops) == theirs_loops(tmp_path / "slam")


def theirs_loops(out):
    return len((out / "loop_closures.csv").read_text().splitlines()) - 1


def test_result_arrays(intel, tmp_path):
    log, result, calls = intel
    n = len(log)
    assert result.poses.shape == (n, 3) and result.poses.dtype == np.float64
    np.testing.assert_array_equal(result.poses[0], [0.0, 0.0, 0.0])
    np.testing.assert_array_equal(result.stamps, log.stamps)
    assert result.loops.shape == (len(result.loop_scores), 2) and result.loops.dtype == np.int64
    assert np.all((result.loops >= 0) & (result.loops < n))
    assert calls[-1] == (n, n) and len(calls) > 1
    m = result.map
    assert m.array.shape == m.shape
    assert m.resolution == 0.05
    known = m.array[~np.isnan(m.array)]
    assert known.size > 0 and known.min() >= 0 and known.max() <= 1
    pgm, yaml = m.save(tmp_path / "intel.pgm")
    header = open(pgm, "rb").read(2)
    assert header == b"P5"
    text = open(yaml).read()
    assert "resolution: 0.05" in text and "image: intel.pgm" in text


def test_progress_exception_stops_the_run(data):
    log = raypath.open(need(data / "carmen/raw/intel.clf.bz2"))

    def stop(done, total):
        raise KeyboardInterrupt("stop")

    with pytest.raises(KeyboardInterrupt):
        raypath.slam(log, scans=300, progress=stop)


def test_bad_arguments(data):
    log = raypath.open(need(data / "carmen/raw/intel.clf.bz2"))
    with pytest.raises(ValueError, match="resolution"):
        raypath.slam(log, resolution=-1.0)
    with pytest.raises(ValueError, match="max_range"):
        raypath.slam(log, max_range=float("nan"))
    with pytest.raises(ValueError, match="log"):
        raypath.slam(42)
    result = raypath.slam(log, scans=50, loops=False)
    assert len(result) == 50
    with pytest.raises(raypath.InputError):
        result.relation_errors(data / "carmen/relations/fr079.relations")
