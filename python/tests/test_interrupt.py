"""Ctrl-C: a run stops at its next chunk, writes its checkpoint, closes its
file, and raises KeyboardInterrupt (`slipfront.Interrupted`); Python's own
SIGINT handling is left as it was. And the GIL is released while stepping."""

import json
import os
import signal
import subprocess
import sys
import textwrap
import threading
import time

import numpy as np

import slipfront


def interrupted(script: str, *args: str, after: float = 2.0) -> dict:
    """Runs `script` in a new Python, sends SIGINT `after` seconds after it
    prints "ready", and returns the JSON it prints last."""
    # A child of a background job starts with SIGINT ignored, and Python then
    # keeps it ignored: give the child the default disposition, so Python
    # installs its own handler as in a terminal.
    child = subprocess.Popen([sys.executable, "-c", textwrap.dedent(script), *args],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                             preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    assert child.stdout.readline().strip() == "ready"
    time.sleep(after)
    sent = time.monotonic()
    child.send_signal(signal.SIGINT)
    try:
        out, err = child.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        child.kill()  # not left stepping beside the tests that follow
        child.communicate()
        raise
    stopped_in = time.monotonic() - sent
    assert child.returncode == 0, err
    result = json.loads(out.strip().splitlines()[-1])
    result["stopped_in"] = stopped_in
    return result


def test_ctrl_c_stops_a_run_after_its_checkpoint(tmp_path):
    out = tmp_path / "r.mcap"
    r = interrupted("""
        import json, signal, sys, slipfront
        # "ready" once the slider is driven (past its normal-load steps, which
        # record no samples): a slow machine may spend seconds loading.
        loaded = slipfront.Scenario.load().model()["normal_load_steps"]
        said = []
        def progress(done, total):
            if done > loaded and not said:
                said.append(done)
                print("ready", flush=True)
        try:
            slipfront.run(None, backend="cpu", output=sys.argv[1], progress=progress)
            print(json.dumps({"finished": True}))
        except slipfront.Interrupted as e:
            print(json.dumps({
                "keyboard_interrupt": isinstance(e, KeyboardInterrupt),
                "checkpoint": e.checkpoint,
                "samples": len(e.run.series),
                "last": float(e.run.to_numpy("series")["time"][-1]),
                "python_handler": signal.getsignal(signal.SIGINT) is signal.default_int_handler,
            }))
        """, str(out))
    assert r["keyboard_interrupt"] and r["python_handler"]
    assert r["stopped_in"] < 10
    assert r["checkpoint"] == str(out) + ".ckpt" and os.path.exists(r["checkpoint"])
    # The file is whole (closed, not cut), and the checkpoint continues it.
    run = slipfront.open(out)
    assert not run.truncated and len(run.series) == r["samples"] > 0
    sim = slipfront.Simulation.from_checkpoint(out)
    assert sim.time >= r["last"] - 1e-3
    sim.advance_steps(100)


def test_ctrl_c_stops_advance_and_the_simulation_goes_on():
    r = interrupted("""
        import json, slipfront
        sim = slipfront.Simulation(None, backend="cpu")
        print("ready", flush=True)
        try:
            sim.advance(1.0)
            print(json.dumps({"finished": True}))
        except KeyboardInterrupt:
            step = sim.step
            sim.advance_steps(10)
            print(json.dumps({"step": step, "after": sim.step, "total": sim.total_steps}))
        """)
    assert 0 < r["step"] < r["total"] and r["after"] == r["step"] + 10
    assert r["stopped_in"] < 10


def test_ctrl_c_stops_a_sweep(tmp_path):
    r = interrupted("""
        import json, sys, slipfront
        print("ready", flush=True)
        try:
            slipfront.sweep(None, [{"time.seed": s} for s in range(1, 9)], backend="cpu",
                            threads=1, out_dir=sys.argv[1], progress=False)
            print(json.dumps({"finished": True}))
        except slipfront.Interrupted as e:
            print(json.dumps({"rows": 0 if e.run is None else len(e.run)}))
        """, str(tmp_path / "sweep"), after=3.0)
    assert r["rows"] < 8 and r["stopped_in"] < 20


def test_the_gil_is_released_while_a_run_steps():
    counted = 0
    done = threading.Event()

    def count_for(seconds):
        nonlocal counted
        end = time.monotonic() + seconds
        n = 0
        while time.monotonic() < end and not done.is_set():
            n += 1
        return n

    alone = count_for(0.5) / 0.5  # loop turns per second with the GIL to itself

    def background():
        slipfront.run("small_stick_slip", backend="cpu", threads=1, t_end=0.1, progress=False)
        done.set()

    worker = threading.Thread(target=background)
    started = time.monotonic()
    worker.start()
    counted = count_for(60)
    took = time.monotonic() - started
    worker.join()
    assert took > 0.3, "the run was too short to tell"
    # Held, the GIL would leave this thread a sliver of the run's time.
    assert counted / took > 0.3 * alone, (counted / took, alone)
    assert np.isfinite(took)
