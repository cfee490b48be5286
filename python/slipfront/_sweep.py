"""`sweep`: many runs of one scene, a table of their outcomes."""

from __future__ import annotations

import os
import shutil
import tempfile
from typing import Any, Optional, Sequence, Union

from . import _core
from ._progress import Progress, reporter
from ._run import Interrupted, PathLike, ScenarioLike, as_scenario
from ._tables import read_csv


def sweep(base: ScenarioLike = None, points: Optional[Sequence[dict]] = None, *,
          seeds: Union[int, Sequence[int], None] = None,
          perturb: Optional[dict] = None, backend: str = "auto",
          precision: Optional[str] = None, threads: int = 0, ensemble: int = 64,
          out_dir: Optional[PathLike] = None, keep_runs: bool = False,
          progress: Progress = True, set: Optional[dict] = None):
    """Runs `base` once per point and returns the outcomes, one row per run
    (the columns of ``slipfront sweep``'s ``summary.csv``: the point's
    values, status, first full event, F/F_N, precursors, events, slip...).

    points: dicts of scenario keys to values, every point setting the same
    keys (``[{"loading.drive.velocity": v} for v in speeds]``); None: the
    base alone. seeds: a count (seeds 1..n) or a list, each point run with
    each. perturb: a perturbation ensemble of every point, ``{"key":
    "loading.drive.velocity", "relative": 1e-6, "count": 32}``. backend:
    auto runs GPU ensembles (`ensemble` scenes per dispatch) where a
    hardware GPU computes in the precision, else the CPU's threads.
    out_dir: where the table and (with keep_runs) the run files go; a rerun
    into the same folder skips the points its table holds. None: a
    temporary folder, removed."""
    if keep_runs and out_dir is None:
        raise ValueError("keep_runs=True needs out_dir= (where the run files go)")
    sc = as_scenario(base, set)
    folder = None if out_dir is not None else tempfile.mkdtemp(prefix="slipfront-sweep-")
    where = os.fspath(out_dir) if out_dir is not None else folder
    callback, close = reporter(progress, "sweep", "runs")
    try:
        try:
            report, stopped_by = _core.run_sweep(
                sc, where, points=list(points) if points is not None else None,
                seeds=list(seeds) if isinstance(seeds, (list, tuple)) else seeds,
                perturb=perturb, backend=backend, precision=precision,
                threads=threads, ensemble=ensemble, keep_runs=keep_runs,
                progress=callback)
        finally:
            close()
        table = read_csv(report["table"]) if os.path.exists(report["table"]) else None
        if stopped_by is not None:
            if isinstance(stopped_by, KeyboardInterrupt):
                raise Interrupted(
                    f"sweep stopped after {report['ran']} of {report['points']} runs"
                    + (f"; rerun into {where} to finish it" if folder is None else ""),
                    run=table) from stopped_by
            raise stopped_by
        return table
    finally:
        if folder is not None:
            shutil.rmtree(folder, ignore_errors=True)
