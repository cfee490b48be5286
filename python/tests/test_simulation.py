"""Simulation: stepping by hand gives the run's records; checkpoints
continue bit for bit."""

import numpy as np
import pytest

import slipfront


def test_stepping_by_hand_reaches_the_runs_global_samples(stick_slip):
    run, _ = stick_slip
    series = run.to_numpy("series")
    sim = slipfront.Simulation("small_stick_slip", backend="cpu")
    assert sim.step == 0 and sim.time < 0  # the normal-load phase comes first
    for k in (10, 3000, len(series) - 1):
        sim.advance_steps(int(series["step"][k]) - sim.step)
        s = sim.sample()
        assert s["step"] == series["step"][k]
        assert s["time"] == series["time"][k]
        assert s["drive_ratio"] == series["drive_ratio"][k]
        assert s["ruptures"] == series["ruptures"][k]


def test_state_shapes_and_units():
    sim = slipfront.Simulation("small_stick_slip", backend="cpu")
    sim.advance(0.01)
    assert sim.time >= 0.01 and sim.time - 0.01 < sim.dt
    st = sim.state()
    assert st["disp"].shape == (8, 15, 2) and st["vel"].shape == (8, 15, 2)
    assert st["friction"].shape == (15,) and st["normal"].shape == (15,)
    assert st["anchor"].shape == (15, 20) and st["pinned"].dtype == bool
    assert st["pinned"].mean() > 0.5
    # The state and the global sample describe one instant.
    s = sim.sample()
    assert st["step"] == s["step"] == sim.step
    assert st["friction"].sum() == pytest.approx(s["friction_force"], rel=1e-12)
    with pytest.raises(ValueError, match="only goes forward"):
        sim.advance(0.0)


def test_a_checkpoint_continues_bit_for_bit(tmp_path):
    a = slipfront.Simulation("small_stick_slip", backend="cpu")
    a.advance(0.02)
    a.checkpoint(tmp_path / "s.ckpt")
    b = slipfront.Simulation.from_checkpoint(tmp_path / "s.ckpt", backend="cpu")
    assert b.step == a.step
    a.advance(0.05)
    b.advance(0.05)
    sa, sb = a.state(), b.state()
    for key in ("disp", "vel", "anchor", "slip_steps_left"):
        np.testing.assert_array_equal(sa[key], sb[key])
    assert a.sample() == b.sample()
    # Negative control: a drive 1e-9 faster, from the same start, differs.
    v = slipfront.Scenario.load("small_stick_slip").get("loading.drive.velocity")
    c = slipfront.Simulation("small_stick_slip", backend="cpu",
                             set={"loading.drive.velocity": v * (1 + 1e-9)})
    c.advance(0.05)
    assert not np.array_equal(c.state()["disp"], sa["disp"])


def test_a_runs_checkpoint_continues_in_python(tmp_path):
    out = tmp_path / "r.mcap"
    slipfront.run("small_stick_slip", backend="cpu", t_end=0.03, output=out, progress=False)
    sim = slipfront.Simulation.from_checkpoint(out)  # the checkpoint beside it
    whole = slipfront.Simulation("small_stick_slip", backend="cpu")
    whole.advance_steps(sim.step)
    assert sim.sample() == whole.sample()
    sim.advance(0.04)
    whole.advance(0.04)
    np.testing.assert_array_equal(sim.state()["disp"], whole.state()["disp"])
