"""Shared fixtures: one short stick-slip run file made through the Python
API, and the `slipfront` command-line program the Python results are
checked against."""

import os
import pathlib
import shutil

import pytest

import slipfront

REPO = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def cli() -> str:
    """The `slipfront` program: $SLIPFRONT_BIN, else the repository's release
    build (`cargo build --release`). Missing, the tests that compare with it
    fail: they are not skipped."""
    path = os.environ.get("SLIPFRONT_BIN") or str(REPO / "target" / "release" / "slipfront")
    if not os.path.isfile(path):
        found = shutil.which("slipfront")
        if found is None:
            pytest.fail(f"no slipfront program at {path} (set SLIPFRONT_BIN or build it with "
                        "`cargo build --release`)")
        path = found
    return path


@pytest.fixture(scope="session")
def stick_slip(tmp_path_factory):
    """small_stick_slip (15 x 8 blocks, 0.3 s, about 16 events) run to its
    end on the CPU, kept in a file: (Run, path)."""
    path = tmp_path_factory.mktemp("stick_slip") / "run.mcap"
    r = slipfront.run("small_stick_slip", backend="cpu", output=path, progress=False)
    return r, path
