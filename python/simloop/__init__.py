"""simloop: the chapter's MuJoCo simulation loop, from Python.

    >>> import simloop
    >>> result = simloop.run(seed=0)
    >>> result.metrics["lateral_drift"]
    0.045015

The loop itself is C++ (simloop._core); this package checks arguments, gives
numpy views of the trajectory, and writes the rerun recording.
"""

from typing import TYPE_CHECKING

from ._api import Sim, draw_shove, load_model, run, run_batch, sweep
from .scenario import Scenario, ScenarioResult, run_scenario, run_scenario_batch
from ._core import (
    COLUMN_NAMES,
    ENERGY_COLUMN_NAMES,
    MAX_RECORD_EVERY,
    MAX_STEPS,
    MUJOCO_VERSION,
    Contact,
    Model,
    MujocoError,
    MujocoWarning,
    RunResult,
    Shove,
    SweepPoint,
    SweepResult,
    __version__,
)

__all__ = [
    "BatchTable",
    "COLUMN_NAMES",
    "ENERGY_COLUMN_NAMES",
    "MAX_RECORD_EVERY",
    "MAX_STEPS",
    "MUJOCO_VERSION",
    "Contact",
    "Model",
    "MujocoError",
    "MujocoWarning",
    "RunResult",
    "Scenario",
    "ScenarioResult",
    "Shove",
    "Sim",
    "SweepPoint",
    "SweepResult",
    "__version__",
    "draw_shove",
    "load_model",
    "run",
    "run_batch",
    "run_scenario",
    "run_scenario_batch",
    "sweep",
    "table",
    "to_arrow",
    "to_pandas",
]

# Scenario sweeps: sweep(scenario=...) returns a ScenarioSweepResult.
from ._core import SCENARIO_SWEEP_TOLERANCE, ScenarioSweepPoint, ScenarioSweepResult  # noqa: E402

__all__ += ["SCENARIO_SWEEP_TOLERANCE", "ScenarioSweepPoint", "ScenarioSweepResult"]

if TYPE_CHECKING:
    from .tables import BatchTable, table, to_arrow, to_pandas


def __getattr__(name: str) -> object:
    # The tables need numpy, which `import simloop` does not load (it costs
    # ~80 ms, and the command's --no-rerun path never needs it).
    if name in ("BatchTable", "table", "to_arrow", "to_pandas"):
        from . import tables

        return getattr(tables, name)
    raise AttributeError(f"module 'simloop' has no attribute {name!r}")
