"""run and open: the records of a run from Python are those of the same run
from the command line, and `open` decodes a file as the mcap package does."""

import os
import subprocess

import numpy as np
import pytest

import slipfront
import mcap_route
from conftest import REPO


def test_open_decodes_every_channel_as_the_mcap_package_does(stick_slip):
    run, path = stick_slip
    ref = mcap_route.read(path)
    again = slipfront.open(path)
    for name in mcap_route.GLOBAL:
        np.testing.assert_array_equal(again.to_numpy("series")[name], ref["series"][name])
    for name in mcap_route.INTERFACE + ("time",):
        np.testing.assert_array_equal(getattr(again.interface, name), ref["interface"][name])
    for name in mcap_route.BULK + ("time",):
        np.testing.assert_array_equal(getattr(again.bulk, name), ref["bulk"][name])
    # What `run` returned is what the file holds.
    np.testing.assert_array_equal(run.interface.slip, again.interface.slip)
    assert run.summary["steps"] > 0 and again.summary is None
    assert again.metadata["nx"] == "15" and not again.truncated
    assert again.interface.shear_stress.shape == (len(again.interface.time), 15)
    assert again.bulk.ux.shape[1:] == (8, 15) and again.bulk.ux.dtype == np.float32
    assert again.scenario == slipfront.Scenario.load("small_stick_slip")


def test_a_python_run_records_what_the_cli_records(stick_slip, cli, tmp_path):
    run, _ = stick_slip
    out = tmp_path / "cli.mcap"
    subprocess.run([cli, "run", str(REPO / "scenarios" / "small_stick_slip.toml"),
                    "--backend", "cpu", "-o", str(out), "--quiet"], check=True,
                   capture_output=True)
    cli_run = slipfront.open(out)
    for name in ("time", "drive_ratio", "friction_force", "ruptures"):
        np.testing.assert_array_equal(run.to_numpy("series")[name],
                                      cli_run.to_numpy("series")[name])
    np.testing.assert_array_equal(run.interface.shear_stress, cli_run.interface.shear_stress)
    # Negative control: another seed is another run, and the comparison sees it.
    other = slipfront.run("small_stick_slip", backend="cpu", t_end=0.12,
                          set={"time.seed": 2}, progress=False)
    n = len(other.interface.time)
    assert not np.array_equal(other.interface.shear_stress, cli_run.interface.shear_stress[:n])


def test_a_gpu_run_from_python_records_what_the_cli_records(cli, tmp_path):
    """The GPU engine (lavapipe in CI, where a missing adapter fails this
    test): the same records from Python as from the command line."""
    scene = REPO / "scenarios" / "small_stick_slip.toml"
    out = tmp_path / "gpu.mcap"
    subprocess.run([cli, "run", str(scene), "--backend", "gpu", "--t-end", "0.01", "-o",
                    str(out), "--quiet"], check=True, capture_output=True)
    ours = slipfront.run(scene, backend="gpu", t_end=0.01, progress=False)
    theirs = slipfront.open(out)
    assert "gpu" in ours.summary["backend"] and ours.summary["dispatches"] > 0
    assert len(ours.interface.time) == len(theirs.interface.time) > 100
    np.testing.assert_array_equal(ours.interface.shear_stress, theirs.interface.shear_stress)
    np.testing.assert_array_equal(ours.to_numpy("series")["drive_ratio"],
                                  theirs.to_numpy("series")["drive_ratio"])
    # Waiting for every batch (no running ahead) records the same.
    waiting = slipfront.run(scene, backend="gpu", t_end=0.01, progress=False,
                            gpu_run_ahead=0)
    np.testing.assert_array_equal(waiting.interface.shear_stress,
                                  theirs.interface.shear_stress)
    # Negative control: a drive 1e-9 faster is another run, and the
    # comparison sees it.
    v = slipfront.Scenario.load(scene).get("loading.drive.velocity")
    other = slipfront.run(scene, backend="gpu", t_end=0.01, progress=False,
                          set={"loading.drive.velocity": v * (1 + 1e-9)})
    assert not np.array_equal(other.to_numpy("series")["drive_ratio"],
                              theirs.to_numpy("series")["drive_ratio"])


def test_events_and_precursors_are_the_clis_table(stick_slip, cli):
    run, path = stick_slip
    done = subprocess.run([cli, "info", str(path), "--csv"], check=True,
                          capture_output=True, text=True)
    lines = done.stdout.strip().splitlines()
    header, rows = lines[0].split(","), [l.split(",") for l in lines[1:]]
    events = run.to_numpy("events")
    assert len(events) == len(rows) >= 10
    col = {name: k for k, name in enumerate(header)}
    for e, row in zip(events, rows):
        assert e["start"] == float(row[col["start_s"]])
        assert e["kind"] == row[col["kind"]]
        assert e["front"] == row[col["front"]]
        assert e["rupture_length"] == float(row[col["rupture_length_m"]])
        assert e["drive_ratio"] == float(row[col["drive_ratio"]])
        assert e["mean_slip"] == float(row[col["mean_slip_m"]])
    first_full = next(e for e in events if e["kind"] == "full")
    assert run.first_full_ratio == first_full["drive_ratio"]
    precursors = run.to_numpy("precursors")
    assert len(precursors) == list(events["kind"]).index("full")
    # Tables are DataFrames with pandas, structured arrays without.
    slipfront.set_tables("numpy")
    try:
        assert isinstance(run.events, np.ndarray)
    finally:
        slipfront.set_tables("auto")
    import pandas
    assert isinstance(run.events, pandas.DataFrame)
    assert list(run.events["kind"]) == list(events["kind"])


def test_a_file_cut_short_reads_up_to_the_cut(stick_slip, tmp_path):
    _, path = stick_slip
    whole = slipfront.open(path)
    data = open(path, "rb").read()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) // 2])
    part = slipfront.open(cut)
    assert part.truncated and not whole.truncated
    n = len(part.interface.time)
    assert 0 < n < len(whole.interface.time)
    np.testing.assert_array_equal(part.interface.slip, whole.interface.slip[:n])
    assert len(part.series) < len(whole.series)


def test_output_files_are_kept_only_when_asked_and_never_overwritten(tmp_path):
    out = tmp_path / "r.mcap"
    r = slipfront.run("triggered_front", output=out, progress=False)
    assert out.exists() and os.path.exists(r.summary["checkpoint"])
    with pytest.raises(FileExistsError, match="force=True"):
        slipfront.run("triggered_front", output=out, progress=False)
    slipfront.run("triggered_front", output=out, progress=False, force=True, t_end=1e-4)
    assert slipfront.open(out).interface.time[-1] < r.interface.time[-1]
    # Without an output the records are read and the file removed.
    temp = slipfront.run("triggered_front", progress=False)
    assert not os.path.exists(temp.path)
    with pytest.raises(FileNotFoundError):
        slipfront.open(tmp_path / "none.mcap")
    (tmp_path / "junk.mcap").write_bytes(b"not an mcap file at all")
    with pytest.raises(ValueError, match="junk.mcap"):
        slipfront.open(tmp_path / "junk.mcap")


def test_options_are_checked_and_progress_is_reported():
    with pytest.raises(ValueError, match='backend = "cuda": expected one of cpu, cpu-reference, gpu, auto'):
        slipfront.run("triggered_front", backend="cuda", progress=False)
    with pytest.raises(ValueError, match="precision"):
        slipfront.run("triggered_front", precision="f16", progress=False)
    for bad in (-1, 65):
        with pytest.raises(ValueError, match=f"gpu_run_ahead = {bad} is not a count of batches from 0 to 64"):
            slipfront.run("triggered_front", gpu_run_ahead=bad, progress=False)
    with pytest.raises(ValueError, match='gpu_arithmetic = "exact": expected one of leaner, strict, wgpu'):
        slipfront.run("triggered_front", gpu_arithmetic="exact", progress=False)
    seen = []
    slipfront.run("triggered_front", progress=lambda done, total: seen.append((done, total)))
    assert seen and all(t == seen[0][1] for _, t in seen)
    assert [d for d, _ in seen] == sorted(d for d, _ in seen)
    assert seen[-1][0] == seen[-1][1]
