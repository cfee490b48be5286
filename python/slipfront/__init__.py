"""slipfront from Python: run the 2D spring-block model of the onset of
frictional sliding (Trømborg et al., PNAS 2014), its sweeps and
perturbation ensembles, and read run files as numpy arrays.

    import slipfront
    r = slipfront.run(slipfront.Scenario.load("triggered_front"), t_end=0.002)
    r.events                      # the slip events, as `slipfront info` finds them
    r.interface.shear_stress      # (samples, blocks)

The TOML scenarios are the one configuration: `Scenario.load(path or
shipped name, set={...})`.
"""

from ._core import BlowUp, Scenario, __version__
from ._core import built_in_names as _built_in_names
from ._run import DEFAULT_QUIET_GAP, Bulk, Interface, Interrupted, Run, open, run
from ._simulation import Simulation
from ._sweep import sweep
from ._tables import set_tables


def scenarios() -> list[str]:
    """The shipped scenes `Scenario.load` takes by name."""
    return _built_in_names()


# (`open` is slipfront.open, not in `import *`: it would hide the builtin.)
__all__ = [
    "BlowUp", "Bulk", "DEFAULT_QUIET_GAP", "Interface", "Interrupted", "Run",
    "Scenario", "Simulation", "__version__", "run", "scenarios", "set_tables",
    "sweep",
]
