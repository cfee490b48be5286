"""A thesis figure from Python: the side-driven stick-slip run of PNAS 2014
(Trømborg et al., Table S1; the thesis's Publication 1, Fig. 1D and
Appendix C), run with the `slipfront` package and drawn with matplotlib.

(a) the loading curve F/F_N against time, with the slip events marked
    (partial events grey, full events red);
(b) the fraction of pinned junctions along the interface around the first
    full event (the model's counterpart of the real contact area in the
    experiments: thesis Figs. C.1 and C.2);
(c) the precursors before it: rupture length against F/F_N at their start
    (PNAS 2014: those from the trailing edge grow with the load).

    pip install ./python matplotlib
    python examples/python_figure.py -o stick_slip.png            # about 0.5 s of driving
    python examples/python_figure.py --open run.mcap -o fig.png   # a run file made before
"""

import argparse

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import slipfront  # noqa: E402


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scenario", default=None, help="a scenario file or shipped name "
                   "(default: the built-in Table S1 stick-slip scene)")
    p.add_argument("--t-end", type=float, default=0.5, help="seconds of driving")
    p.add_argument("--backend", default="auto")
    p.add_argument("--open", help="draw this run file instead of running")
    p.add_argument("--keep", help="keep the run's file here")
    p.add_argument("-o", "--output", default="stick_slip.png")
    a = p.parse_args()

    if a.open:
        run = slipfront.open(a.open)
    else:
        run = slipfront.run(a.scenario, t_end=a.t_end, backend=a.backend, output=a.keep,
                            force=a.keep is not None)
        print(f"ran {run.summary['steps']} steps on {run.summary['backend']} in "
              f"{run.summary['wall_seconds']:.1f} s")
    series, events = run.to_numpy("series"), run.to_numpy("events")
    full = events[events["kind"] == "full"]
    print(f"{len(events)} events, {len(full)} full; "
          f"{len(run.to_numpy('precursors'))} precursors before the first full one")

    fig, (ax_a, ax_b, ax_c) = plt.subplots(1, 3, figsize=(15, 4.2),
                                           gridspec_kw={"width_ratios": [1.4, 1.2, 1]})
    ax_a.plot(series["time"], series["drive_ratio"], lw=0.8, color="k")
    for kind, colour in (("partial", "0.6"), ("full", "tab:red")):
        e = events[events["kind"] == kind]
        ax_a.plot(e["start"], e["drive_ratio"], "v", color=colour, ms=5, label=f"{kind} event")
    ax_a.set(xlabel="time since driving started (s)", ylabel="$F/F_N$",
             title="(a) loading curve")
    ax_a.legend(frameon=False, loc="lower right")

    i = run.interface
    if len(full):
        e = full[0]
        window = (i.time >= e["start"] - 2e-4) & (i.time <= e["end"] + 5e-4)
        image = ax_b.imshow(i.pinned_fraction[window], aspect="auto", origin="lower",
                            cmap="gray", vmin=0, vmax=1,
                            extent=(0, i.x[-1], i.time[window][0] * 1e3,
                                    i.time[window][-1] * 1e3))
        fig.colorbar(image, ax=ax_b, label="fraction of pinned junctions")
        ax_b.set(xlabel="position along the interface, x (m)", ylabel="time (ms)",
                 title=f"(b) first full event ({e['front']} front)")
    else:
        ax_b.text(0.5, 0.5, "no full event in this run", ha="center",
                  transform=ax_b.transAxes)

    pre = run.to_numpy("precursors")
    edge = pre[pre["from_trailing_edge"]]
    inside = pre[~pre["from_trailing_edge"]]
    ax_c.plot(edge["drive_ratio"], edge["length"] * 1e3, "o-", color="tab:blue",
              label="from the trailing edge")
    if len(inside):
        ax_c.plot(inside["drive_ratio"], inside["length"] * 1e3, "o", mfc="none",
                  color="tab:blue", label="from inside")
    if run.first_full_ratio is not None:
        ax_c.axvline(run.first_full_ratio, color="tab:red", ls="--", lw=0.8,
                     label="first full event")
    ax_c.legend(frameon=False, loc="upper left")
    ax_c.set(xlabel="$F/F_N$ at the start", ylabel="rupture length (mm)",
             title="(c) precursors")
    fig.tight_layout()
    fig.savefig(a.output, dpi=130)
    print(f"wrote {a.output}")


if __name__ == "__main__":
    main()
