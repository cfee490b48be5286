"""Space-time map of the fraction of junctions pinned, with matplotlib.

    pip install -r examples/requirements.txt
    python3 examples/spacetime_map.py run.mcap [-o map.png] [--t0 MS --t1 MS]

x in mm across, time in ms down on a true time axis (the output cadence
switches between 20 us and 1 us, so each sample is drawn over its own
interval, not as an image row), white all pinned, black none: the picture
of Rubinstein et al. (2007) and `slipfront plot --kind spacetime`, to
restyle as you like.
"""
import argparse
import pathlib
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from read_interface import read_interface  # noqa: E402


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("run", type=pathlib.Path)
    p.add_argument("-o", "--output", type=pathlib.Path)
    p.add_argument("--t0", type=float, help="start of the window (ms)")
    p.add_argument("--t1", type=float, help="end of the window (ms)")
    p.add_argument("--dpi", type=int, default=150)
    a = p.parse_args()
    if not a.run.is_file():
        sys.exit(f"{a.run}: no such file")
    try:
        t, spacing, fields = read_interface(a.run)
    except Exception as e:  # a clear message, not a traceback
        sys.exit(f"{a.run}: cannot read it ({e}); if the run was killed, "
                 f"run `slipfront recover {a.run}` first")
    pinned = fields["pinned_fraction"]
    t_ms = t * 1e3
    keep = np.ones(len(t), bool)
    if a.t0 is not None:
        keep &= t_ms >= a.t0
    if a.t1 is not None:
        keep &= t_ms <= a.t1
    if keep.sum() < 2:
        sys.exit("fewer than two samples in the window")
    t_ms, pinned = t_ms[keep], pinned[keep]
    # Cell edges: each sample holds until the next one.
    t_edges = np.append(t_ms, t_ms[-1] + np.median(np.diff(t_ms)))
    nx = pinned.shape[1]
    x_edges = (np.arange(nx + 1) - 0.5) * spacing * 1e3
    fig, ax = plt.subplots(figsize=(7, 5), constrained_layout=True)
    mesh = ax.pcolormesh(x_edges, t_edges, pinned, cmap="gray",
                         vmin=0, vmax=1, shading="flat", rasterized=True)
    ax.invert_yaxis()  # time runs down
    ax.set_xlabel("position along the interface x (mm)")
    ax.set_ylabel("time t (ms)")
    ax.set_title(f"Fraction of junctions pinned — {a.run.name}")
    fig.colorbar(mesh, ax=ax, label="fraction of junctions pinned")
    out = a.output or a.run.with_name(a.run.stem + "_spacetime_py.png")
    fig.savefig(out, dpi=a.dpi)
    print(out)


if __name__ == "__main__":
    main()
