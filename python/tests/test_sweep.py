"""sweep: the table of a sweep from Python is the table `slipfront sweep`
makes of the same sweep file."""

import csv
import subprocess

import numpy as np
import pytest

import slipfront
from conftest import REPO

SCENE = REPO / "scenarios" / "small_stick_slip.toml"


def test_the_table_is_the_clis(cli, tmp_path):
    v = slipfront.Scenario.load("small_stick_slip").get("loading.drive.velocity")
    speeds = [v, 1.5 * v]
    table = slipfront.sweep("small_stick_slip",
                            [{"loading.drive.velocity": s} for s in speeds],
                            seeds=[1, 2], set={"time.end": 0.1}, backend="cpu",
                            out_dir=tmp_path / "py", progress=False)
    (tmp_path / "s.toml").write_text(
        f'base = "{SCENE}"\ncombine = "zip"\nseeds = [1, 2]\n'
        f'[set]\n"time.end" = 0.1\n'
        f'[axes]\n"loading.drive.velocity" = [{speeds[0]!r}, {speeds[1]!r}]\n')
    subprocess.run([cli, "sweep", str(tmp_path / "s.toml"), "--backend", "cpu", "--out-dir",
                    str(tmp_path / "cli"), "--quiet"], check=True, capture_output=True)
    with open(tmp_path / "cli" / "summary.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(table) == len(rows) == 4
    assert list(table["status"]) == ["ok"] * 4
    timing = {"wall_s", "wall_seconds"}
    for k, row in enumerate(rows):
        for name, text in row.items():
            if name in timing or name.startswith("wall"):
                continue
            ours = table[name][k]
            if text == "":
                assert ours != ours or ours == "", (name, ours)  # NaN or blank
            elif isinstance(ours, str):
                assert ours == text, name
            else:
                assert float(ours) == float(text), (name, ours, text)
    # The points differ, and the table shows it (a negative control of the
    # comparison above: the rows are not all one run).
    assert len(set(table["first_full_time_s"])) == 4


def test_perturbation_ensembles_seeds_and_bad_points(tmp_path):
    table = slipfront.sweep("small_stick_slip", seeds=2,
                            perturb={"key": "loading.drive.velocity", "relative": 1e-6,
                                     "count": 2},
                            backend="cpu", progress=False, set={"time.end": 0.005})
    assert len(table) == 4
    assert "perturb(loading.drive.velocity)" in table.columns
    assert sorted(set(table["seed"])) == [1, 2]
    with pytest.raises(ValueError, match=r"points\[1\] sets"):
        slipfront.sweep("triggered_front", [{"time.seed": 1}, {"time.end": 1e-4}],
                        progress=False)
    with pytest.raises(ValueError, match="perturb"):
        slipfront.sweep("triggered_front", perturb={"key": "loading.drive.velocity"},
                        progress=False)
    with pytest.raises(ValueError, match="keep_runs"):
        slipfront.sweep("triggered_front", keep_runs=True, progress=False)
    slipfront.set_tables("numpy")
    try:
        t = slipfront.sweep("triggered_front", backend="cpu", progress=False,
                            set={"time.end": 5e-5})
        assert isinstance(t, np.ndarray) and t["status"][0] == "ok"
    finally:
        slipfront.set_tables("auto")
