"""IBuILD and DBoW2-style place recognition on a real log: the candidates of
`raypath loop-closure`; one interface for the three methods."""

import numpy as np
import pytest

import raypath
from raypath.place_recognition import Dbow, Ibuild, ScanContext

from conftest import need

FRAMES = 200


@pytest.fixture(scope="module")
def aces(data):
    return raypath.open(need(data / "carmen/corrected/aces-corrected.log.gz"))


def online(recognizer, log):
    found = []
    for t in range(FRAMES):
        best = recognizer.add_and_query(log[t], exclusion_frames=50, k=1)
        if best:
            found.append({"query": t, "match": best[0][0], "score": best[0][1]})
    return found


def test_ibuild_equals_the_cli(aces, cli):
    theirs = cli("loop-closure", aces.path, "--method", "ibuild", "--max-frames", FRAMES)
    pr = Ibuild()
    assert online(pr, aces) == theirs["candidates"] != []
    assert len(pr) == FRAMES


def test_dbow_equals_the_cli(aces, cli, tmp_path):
    vocabulary = tmp_path / "aces.voc"
    theirs = cli("loop-closure", aces.path, "--method", "dbow", "--max-frames", FRAMES,
                 "--save-vocabulary", vocabulary)
    assert online(Dbow(vocabulary), aces) == theirs["candidates"] != []
    trained = Dbow.train([aces[t] for t in range(FRAMES)])
    assert online(trained, aces) == theirs["candidates"]
    trained.save_vocabulary(tmp_path / "again.voc")
    assert (tmp_path / "again.voc").read_bytes() == vocabulary.read_bytes()


def test_frames_of_every_kind(aces):
    image = (np.arange(200 * 160) % 251).astype(np.uint8).reshape(160, 200)
    pr = Ibuild()
    assert pr.add(aces[0]) == 0
    assert pr.add(image) == 1
    assert isinstance(pr.query(aces[1]), list)
    sc = ScanContext()
    cloud = np.random.default_rng(2).uniform(-20, 20, size=(2000, 3))
    assert sc.add(cloud) == 0
    assert sc.query(cloud, k=1)[0][0] == 0
    assert sc.query(cloud, before=0) == []
    with pytest.raises(raypath.InputError):
        sc.add(aces[0])  # Scan Context needs a point cloud


@pytest.mark.parametrize("make", [Ibuild, ScanContext])
def test_bad_frames(make):
    pr = make()
    for bad in (np.zeros((4, 2)), np.zeros((2, 2, 2)), "scan", np.zeros((3, 3), dtype=np.int16)):
        with pytest.raises(ValueError, match="frame: expected"):
            pr.add(bad)


def test_bad_settings(tmp_path):
    with pytest.raises(ValueError, match="score"):
        Ibuild(score="best")
    with pytest.raises(FileNotFoundError):
        Dbow(tmp_path / "missing.voc")
    (tmp_path / "bad.voc").write_bytes(b"nonsense")
    with pytest.raises(raypath.FormatError):
        Dbow(tmp_path / "bad.voc")
    with pytest.raises(ValueError, match="frames"):
        Dbow.train([])
