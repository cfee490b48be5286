"""Runs: `run` a scene to its end, `open` a run file, and the `Run` both
return."""

from __future__ import annotations

import os
import shutil
import tempfile
from dataclasses import dataclass
from typing import Any, Optional, Union

import numpy as np

from . import _core
from ._core import Scenario
from ._progress import Progress, reporter
from ._tables import structured, table

PathLike = Union[str, "os.PathLike[str]"]
ScenarioLike = Union[Scenario, PathLike, None]

#: Ruptures less than this many seconds apart are one event (as `slipfront info`).
DEFAULT_QUIET_GAP = 1e-3


def as_scenario(scenario: ScenarioLike, set: Optional[dict] = None) -> Scenario:
    """A Scenario from a Scenario, a file, a shipped scene's name, or None
    (the built-in default scene), with `set` applied."""
    if isinstance(scenario, Scenario):
        return scenario.with_set(set) if set else scenario
    name = None if scenario is None else os.fspath(scenario)
    return Scenario.load(name, set=set)


@dataclass(frozen=True)
class Interface:
    """The /interface channel: one row per sample, one column per interface
    block (trailing edge first)."""

    time: np.ndarray  #: s since driving started, (samples,)
    step: np.ndarray  #: (samples,)
    x: np.ndarray  #: block positions along the interface, m, (blocks,)
    shear_stress: np.ndarray  #: Pa, (samples, blocks)
    normal_stress: np.ndarray  #: Pa
    pinned_fraction: np.ndarray  #: share of the block's junctions pinned
    slip: np.ndarray  #: m since the first sample
    slip_speed: np.ndarray  #: m/s


@dataclass(frozen=True)
class Bulk:
    """The /bulk channel: displacement and velocity fields, (samples, nz,
    nx) in f32, row 0 at the interface."""

    time: np.ndarray
    step: np.ndarray
    ux: np.ndarray
    uz: np.ndarray
    vx: np.ndarray
    vz: np.ndarray


class Run:
    """A run file read into numpy: what `run` and `open` return.

    Tables (`series`, `events`, `precursors`, `jumps`) are pandas DataFrames
    when pandas is installed, else numpy structured arrays
    (`slipfront.set_tables` chooses)."""

    def __init__(self, decoded: dict[str, Any], summary: Optional[dict] = None,
                 quiet_gap: float = DEFAULT_QUIET_GAP):
        self._d = decoded
        self._quiet_gap = quiet_gap
        self._events = None
        #: The run's summary (wall time, steps, throughput...) when this
        #: process ran it; None for a file opened.
        self.summary = summary
        i = decoded["interface"]
        nx = i["slip"].shape[1] if i["slip"].ndim == 2 else 0
        self.interface = Interface(
            time=i["time"], step=i["step"],
            x=np.arange(nx) * decoded["spacing"],
            shear_stress=i["shear_stress"], normal_stress=i["normal_stress"],
            pinned_fraction=i["pinned_fraction"], slip=i["slip"],
            slip_speed=i["slip_speed"])
        b = decoded["bulk"]
        if b:
            self.bulk: Optional[Bulk] = Bulk(time=b["time"], step=b["step"], ux=b["ux"],
                                             uz=b["uz"], vx=b["vx"], vz=b["vz"])
        else:
            self.bulk = None

    # -- what the file says about itself ---------------------------------
    @property
    def path(self) -> str:
        return self._d["path"]

    @property
    def metadata(self) -> dict[str, str]:
        """The run's metadata (engine, precision, dt, lattice, hashes...)."""
        return self._d["metadata"]

    @property
    def scenario_toml(self) -> Optional[str]:
        return self._d["scenario"]

    @property
    def scenario(self) -> Optional[Scenario]:
        """The scenario the run ran (None if the file holds none)."""
        text = self._d["scenario"]
        return None if text is None else Scenario.from_toml(text, name=self.path)

    @property
    def history(self) -> list[str]:
        """One line per start, resume and branch."""
        return self._d["history"]

    @property
    def truncated(self) -> bool:
        """The file was cut short (a killed run): everything before the cut is here."""
        return self._d["truncated"]

    @property
    def damage(self) -> Optional[str]:
        return self._d["damage"]

    @property
    def spacing(self) -> float:
        """Lattice spacing (m)."""
        return self._d["spacing"]

    # -- channels ---------------------------------------------------------
    @property
    def series(self):
        """The /global channel: time, step, drive_force, drive_ratio (F/F_N),
        friction_force, pinned_fraction, kinetic_energy, ruptures."""
        return table(self._d["series"])

    @property
    def jumps(self):
        """The quasi-static fast-forward's jumps (/fast_forward), if any."""
        return table(self._d["jumps"])

    def _analysed(self):
        if self._events is None:
            i, g = self._d["interface"], self._d["series"]
            if i["slip"].ndim != 2:
                empty = np.zeros((0, 0))
                args = (np.zeros(0), empty, empty, empty)
            else:
                args = (i["time"], i["pinned_fraction"], i["slip"], i["slip_speed"])
            self._events = _core.event_table(*args, self.spacing, g["time"],
                                             g["drive_ratio"], self._quiet_gap)
        return self._events

    @property
    def events(self):
        """Slip events, as `slipfront info` finds them: start, end (s), kind
        (full or partial), rupture_length, origin (m), mean_slip (m),
        drive_ratio (F/F_N at the start), front (its speed profile's class),
        v_front_min, v_front_max, v_front_unresolved_at_least (m/s; NaN
        where none)."""
        return table(self._analysed()[0])

    @property
    def precursors(self):
        """The partial events before the first full one: drive_ratio,
        length (m), origin (m), from_trailing_edge."""
        return table(self._analysed()[1])

    @property
    def first_full_ratio(self) -> Optional[float]:
        """F/F_N at the first full event (None without one)."""
        return self._analysed()[2]

    def to_numpy(self, name: str) -> np.ndarray:
        """A table (`series`, `events`, `precursors`, `jumps`) as a numpy
        structured array, whatever `set_tables` says."""
        sources = {
            "series": lambda: self._d["series"],
            "jumps": lambda: self._d["jumps"],
            "events": lambda: self._analysed()[0],
            "precursors": lambda: self._analysed()[1],
        }
        if name not in sources:
            raise ValueError(f"{name!r}: expected one of {', '.join(sources)}")
        return structured(sources[name]())

    def __repr__(self) -> str:
        n = len(self._d["series"]["time"])
        cut = ", cut short" if self.truncated else ""
        return (f"Run({self.path!r}: {n} global samples, "
                f"{len(self.interface.time)} interface rows, "
                f"{0 if self.bulk is None else len(self.bulk.time)} bulk fields{cut})")


def open(path: PathLike, quiet_gap: float = DEFAULT_QUIET_GAP) -> Run:
    """Reads a run file (complete, or cut short by a killed run) into a `Run`."""
    return Run(_core.read_run(os.fspath(path)), quiet_gap=quiet_gap)


class Interrupted(KeyboardInterrupt):
    """Ctrl-C stopped a run (or a sweep) after it saved its state.

    ``run`` is what the file holds up to the stop (a `Run`; for a sweep,
    the table so far), ``checkpoint`` the checkpoint written beside the run
    file (continue with ``slipfront run --resume FILE`` or
    `Simulation.from_checkpoint`); None without an output file."""

    def __init__(self, message: str, run=None, checkpoint: Optional[str] = None):
        super().__init__(message)
        self.run = run
        self.checkpoint = checkpoint


def run(scenario: ScenarioLike = None, *, backend: str = "auto",
        precision: Optional[str] = None, t_end: Optional[float] = None,
        output: Optional[PathLike] = None, progress: Progress = True,
        set: Optional[dict] = None, threads: int = 0, gpu_path: str = "auto",
        gpu_output: str = "device", force: bool = False,
        allow_unstable: bool = False, live: Optional[str] = None,
        live_wait: bool = False, gpu_run_ahead: Optional[int] = None,
        gpu_arithmetic: str = "leaner") -> Run:
    """Runs a scene to its end and returns its records as a `Run`.

    scenario: a `Scenario`, a scenario file, a shipped scene's name, or
    None for the built-in default scene. backend: auto, cpu,
    cpu-reference or gpu; precision: f64, f32 (mixed) or f32-plain (None:
    f64 wherever it runs). t_end: simulated seconds of driving (overrides
    time.end). output: the run file to keep (None: the records are read
    into memory and the file removed). progress: True (tqdm if installed),
    False, or a callable(done_steps, total_steps). The GIL is released
    while the scene steps. live: stream the run to Foxglove viewers over
    WebSocket at "HOST:PORT" (as `slipfront run --live`; port 0 takes a
    free one, and `summary["live"]` says where); live_wait: start once a
    viewer has subscribed. gpu_run_ahead: batches the GPU may run ahead of
    the output writer (as `--gpu-run-ahead`: 0 to 64, None for the
    default 4; 0 waits for every batch). gpu_arithmetic: as
    `--gpu-arithmetic`: "strict" forbids the GPU driver to fuse or regroup
    any operation (in f64 the CPU reference's numbers, to the bit where the
    GPU rounds division and square roots as IEEE does), "wgpu" leaves the
    kernels as wgpu writes them, "leaner" (the default) is strict in mixed
    f32 and wgpu's in f64.

    Ctrl-C stops the run at its next chunk; with an output file its
    checkpoint is written, then `Interrupted` (a KeyboardInterrupt) is
    raised carrying the partial `Run`. A blow-up raises `BlowUp` naming
    the step, time and block."""
    overrides = dict(set or {})
    if t_end is not None:
        overrides["time.end"] = float(t_end)
    sc = as_scenario(scenario, overrides)
    keep = output is not None
    folder = None if keep else tempfile.mkdtemp(prefix="slipfront-")
    path = os.fspath(output) if keep else os.path.join(folder, "run.mcap")
    callback, close = reporter(progress, sc.name, "steps")
    try:
        try:
            summary, stopped_by = _core.run_scene(
                sc, path, backend=backend, precision=precision, threads=threads,
                gpu_path=gpu_path, gpu_output=gpu_output,
                allow_unstable=allow_unstable, force=force, progress=callback,
                live=live, live_wait=live_wait, gpu_run_ahead=gpu_run_ahead,
                gpu_arithmetic=gpu_arithmetic)
        finally:
            close()
        result = Run(_core.read_run(path), summary=summary)
        if stopped_by is not None:
            if isinstance(stopped_by, KeyboardInterrupt):
                where = (f"; checkpoint {summary['checkpoint']}, continue with "
                         f"`slipfront run --resume {path}`") if keep else ""
                raise Interrupted(
                    f"run stopped at t = {summary['simulated_time']:.6e} s{where}",
                    run=result, checkpoint=summary["checkpoint"] if keep else None,
                ) from stopped_by
            raise stopped_by
        return result
    finally:
        if folder is not None:
            shutil.rmtree(folder, ignore_errors=True)
