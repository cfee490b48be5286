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


def test_strict_gpu_arithmetic_gives_the_cpu_references_f64_numbers():
    """`gpu_arithmetic="strict"` forbids the GPU driver to fuse or regroup
    any operation: in f64 each kernel then computes the CPU reference's
    operations as written, so on lavapipe (CI), which rounds division and
    square roots as IEEE does, the GPU's state is the CPU reference's to
    the bit through junction ruptures; elsewhere to 1e-12. The control: the
    default f64 build, which llvmpipe fuses, differs."""
    def state_at(t, **engine):
        sim = slipfront.Simulation("small_stick_slip", precision="f64", **engine)
        sim.advance(t)
        return sim, sim.state()
    t = 0.08  # 100,000 steps, 140 junction ruptures
    reference, ref = state_at(t, backend="cpu-reference")
    assert ref["ruptures"].sum() > 100
    gpu, got = state_at(t, backend="gpu", gpu_arithmetic="strict")
    assert "strict arithmetic" in gpu.engine
    for field in ("disp", "vel", "friction", "anchor", "pinned", "ruptures", "slip_steps_left"):
        if "llvmpipe" in gpu.engine:
            np.testing.assert_array_equal(got[field], ref[field], err_msg=field)
        else:
            np.testing.assert_allclose(got[field], ref[field], rtol=1e-12, err_msg=field)
    if "llvmpipe" in gpu.engine:
        plain, other = state_at(t, backend="gpu")
        assert "strict arithmetic" not in plain.engine
        assert not np.array_equal(other["disp"], ref["disp"])
    with pytest.raises(ValueError, match='gpu_arithmetic = "exact": expected one of leaner, strict, wgpu'):
        slipfront.Simulation("small_stick_slip", backend="gpu", gpu_arithmetic="exact")
