"""Mutated files and hostile arrays give Python exceptions, never a panic or a crash."""

import random

import numpy as np
import pytest

import raypath

from conftest import need

ALLOWED = (raypath.RaypathError, ValueError, FileNotFoundError)

PCD = (b"# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
       b"WIDTH 3\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 3\nDATA ascii\n1 2 3\n4 5 6\n7 8 9\n")
CARMEN = (b"ODOM 0.0 0.0 0.0 0 0 0 1.0 host 1.0\n"
          b"FLASER 3 1.0 2.0 3.0 0.0 0.0 0.0 0.0 0.0 0.0 1.1 host 1.1\n")


def mutations(seed, data, count):
    rng = random.Random(seed)
    for _ in range(count):
        b = bytearray(data)
        for _ in range(rng.randint(1, 4)):
            kind = rng.randrange(3)
            i = rng.randrange(len(b))
            if kind == 0:
                b[i] = rng.randrange(256)
            elif kind == 1:
                del b[i:i + rng.randint(1, 8)]
            else:
                b[i:i] = bytes(rng.randrange(256) for _ in range(rng.randint(1, 8)))
        yield bytes(b)


@pytest.mark.parametrize("name, data", [("m.pcd", PCD), ("m.log", CARMEN)])
def test_mutated_files(tmp_path, name, data):
    path = tmp_path / name
    for k, mutated in enumerate(mutations(7, data, 300)):
        path.write_bytes(mutated)
        try:
            raypath.open(path)
        except ALLOWED:
            pass
        except BaseException as e:  # a pyo3 PanicException is a BaseException
            pytest.fail(f"mutation {k}: {type(e).__name__}: {e}")


def test_mutated_kitti_bin(data, tmp_path):
    raw = need(data / "kitti/sequences/00/velodyne/000000.bin").read_bytes()[:4000]
    path = tmp_path / "000000.bin"
    for mutated in (raw[:-3], raw[:1], b"", raw + b"\x00"):
        path.write_bytes(mutated)
        try:
            cloud = raypath.open(path)
            assert cloud.points.shape[1] == 3
        except ALLOWED:
            pass


@pytest.mark.parametrize(
    "call",
    [
        lambda a: raypath.poles.extract(a),
        lambda a: raypath.planes.ppe(a.reshape(-1, 1, 3) if a.ndim == 2 and a.shape[1] == 3 else a),
        lambda a: raypath.place_recognition.ScanContext().add(a),
        lambda a: raypath.OccupancyTree().insert(a, [0, 0, 0]),
        lambda a: raypath.registration.register(a, a),
        lambda a: raypath.place_recognition.Ibuild().add(a),
        lambda a: raypath.poles.PoleFilter(a[:, :2], [0, 0, 0], particles=10),
        lambda a: raypath.scan_match.ScanMatcher().match_scan(
            a.ravel(), np.linspace(0.0, 1.0, a.size)),
    ],
)
def test_hostile_arrays(call):
    arrays = [
        np.array([[1e308, -1e308, 1e308]]),
        np.array([[1e30, 1e30, 1e30]], dtype=np.float32),
        np.full((5, 3), np.nan),
        np.zeros((1, 3)),
        np.array([[0.0, 0.0, 0.0]] * 3),
        np.empty((0, 3)),
        np.ones((2, 3), dtype=np.float16),
        np.ones((2, 3), dtype=complex),
        np.array([["a", "b", "c"]]),
    ]
    for a in arrays:
        try:
            call(a)
        except ALLOWED:
            pass
        except BaseException as e:
            pytest.fail(f"{a.dtype} {a.shape}: {type(e).__name__}: {e}")
