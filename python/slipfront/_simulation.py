"""`Simulation`: a scene stepped by hand."""

from __future__ import annotations

import os
from typing import Any, Optional

from . import _core
from ._run import PathLike, ScenarioLike, as_scenario


class Simulation:
    """A scene stepped by hand: ``advance(t)``, ``advance_steps(n)``,
    ``state()``, ``sample()``, ``checkpoint(path)``.

    Steps run with the GIL released, a quarter second of wall time at a
    time; Ctrl-C raises KeyboardInterrupt at a chunk's end, with the
    simulation whole (its `step` says where it stopped)."""

    def __init__(self, scenario: ScenarioLike = None, *, backend: str = "auto",
                 precision: Optional[str] = None, set: Optional[dict] = None,
                 threads: int = 0, gpu_path: str = "auto",
                 allow_unstable: bool = False, gpu_arithmetic: str = "leaner",
                 _core_sim=None):
        if _core_sim is not None:
            self._sim = _core_sim
            return
        self._sim = _core.Simulation(as_scenario(scenario, set), backend=backend,
                                     precision=precision, threads=threads,
                                     gpu_path=gpu_path, allow_unstable=allow_unstable,
                                     gpu_arithmetic=gpu_arithmetic)

    @classmethod
    def from_checkpoint(cls, path: PathLike, *, backend: str = "auto",
                        precision: Optional[str] = None, threads: int = 0,
                        gpu_path: str = "auto",
                        gpu_arithmetic: str = "leaner") -> "Simulation":
        """Continues a saved state: a run's checkpoint (``RUN.mcap.ckpt``, or
        the run file with one beside it) or one `checkpoint` wrote."""
        path = os.fspath(path)
        beside = path + ".ckpt"
        if not path.endswith(".ckpt") and os.path.exists(beside):
            path = beside
        return cls(_core_sim=_core.Simulation.from_checkpoint(
            path, backend=backend, precision=precision, threads=threads,
            gpu_path=gpu_path, gpu_arithmetic=gpu_arithmetic))

    def advance(self, t: float) -> None:
        """Steps to time `t` (s since driving started; the normal-load phase
        is at negative times)."""
        self._sim.advance(float(t))

    def advance_steps(self, n: int) -> None:
        """Steps `n` steps."""
        self._sim.advance_steps(int(n))

    def run_to_end(self) -> None:
        """Steps to the scenario's end (time.end)."""
        self._sim.run_to_end()

    def state(self) -> dict[str, Any]:
        """The state now, as numpy copies: disp, vel, force (nz, nx, 2);
        friction, normal (nx,); anchor, junction_stiffness, pinned,
        slip_steps_left, ruptures (nx, Ns); step, time."""
        return self._sim.state()

    def sample(self) -> dict[str, float]:
        """The global series now, as /global records it (time, step,
        drive_force, drive_ratio, friction_force, pinned_fraction,
        kinetic_energy, ruptures)."""
        return self._sim.sample()

    def checkpoint(self, path: PathLike) -> None:
        """Saves the state (`from_checkpoint` continues it; ``slipfront run
        --from PATH`` branches from it)."""
        self._sim.checkpoint(os.fspath(path))

    @property
    def step(self) -> int:
        return self._sim.step

    @property
    def time(self) -> float:
        """Seconds since driving started."""
        return self._sim.time

    @property
    def dt(self) -> float:
        return self._sim.dt

    @property
    def total_steps(self) -> int:
        return self._sim.total_steps

    @property
    def engine(self) -> str:
        return self._sim.engine

    def __repr__(self) -> str:
        return repr(self._sim)
