"""The thesis-figure example runs and draws (on a short scene here; the
figure in the README is the default scene's)."""

import subprocess
import sys

from conftest import REPO


def test_the_figure_example_runs_and_draws(tmp_path):
    out = tmp_path / "fig.png"
    done = subprocess.run([sys.executable, str(REPO / "examples" / "python_figure.py"),
                           "--scenario", "small_stick_slip", "--t-end", "0.15",
                           "--backend", "cpu", "-o", str(out)],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert "full" in done.stdout and out.stat().st_size > 20_000
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
