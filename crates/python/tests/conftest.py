"""Shared fixtures: the real data folder and the `raypath` command line to compare with."""

import json
import os
import pathlib
import subprocess

import pytest

REPO = pathlib.Path(__file__).resolve().parents[3]


def data_dir():
    """The real-data folder (`RAYPATH_DATA`), or None."""
    value = os.environ.get("RAYPATH_DATA")
    return pathlib.Path(value) if value else None


@pytest.fixture(scope="session")
def data():
    """`RAYPATH_DATA` as a path; the test skips, saying why, when it is not set."""
    d = data_dir()
    if d is None or not d.is_dir():
        if os.environ.get("RAYPATH_REQUIRE_DATA"):
            pytest.fail(f"RAYPATH_REQUIRE_DATA is set but RAYPATH_DATA ({d}) is not a folder")
        pytest.skip("RAYPATH_DATA is not set: real-data test skipped")
    return d


def need(path):
    """`path` if it exists; with the data folder set, a missing file fails the test."""
    if not path.exists():
        pytest.fail(f"{path} is missing from RAYPATH_DATA")
    return path


@pytest.fixture(scope="session")
def cli():
    """Runs the `raypath` program (`RAYPATH_CLI`, else target/release/raypath) with `--json`
    and returns the parsed document; skips when the default program is not built (fails when
    `RAYPATH_CLI` names a missing one)."""
    named = os.environ.get("RAYPATH_CLI")
    exe = pathlib.Path(named) if named else REPO / "target" / "release" / "raypath"
    if not exe.is_file():
        if named:
            pytest.fail(f"RAYPATH_CLI={named} does not exist")
        pytest.skip(f"{exe} is not built (cargo build --release -p raypath-cli)")

    def run(*args):
        out = subprocess.run(
            [str(exe), *map(str, args), "--json", "-q"],
            check=True,
            capture_output=True,
            text=True,
        )
        return json.loads(out.stdout)

    return run
