"""simloop: the chapter's MuJoCo simulation loop, from Python.

    >>> import simloop
    >>> result = simloop.run(seed=0)
    >>> result.metrics["lateral_drift"]
    0.045015

The loop itself is C++ (simloop._core); this package checks arguments, gives
numpy views of the trajectory, and writes the rerun recording.
"""

from typing import TYPE_CHECKING

from ._startup import quiet_interrupt_while_starting

quiet_interrupt_while_starting()

try:
    from . import _core  # noqa: F401  (loads libmujoco; the line below explains a failure)
except ImportError as _error:
    from ._mujoco_check import load_failure_message

    _message = load_failure_message(_error)
    if _message is None:
        raise
    raise ImportError(_message) from None

from ._checks import load_model
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
from ._gym_registry import register_when_gymnasium_loads
from .policy import Observation
from .render import MAX_PICTURE_SIZE, Renderer
from .runs import draw_shove, run, run_batch
from .scenario import Scenario, ScenarioResult
from .scenario_runs import run_scenario, run_scenario_batch
from .sim import Sim
from .sweeps import sweep

__all__ = [
    "BatchTable",
    "COLUMN_NAMES",
    "ENERGY_COLUMN_NAMES",
    "MAX_RECORD_EVERY",
    "MAX_PICTURE_SIZE",
    "MAX_STEPS",
    "MUJOCO_VERSION",
    "Contact",
    "Model",
    "MujocoError",
    "MujocoWarning",
    "Observation",
    "Renderer",
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


# Gymnasium: simloop/Chapter-v0, simloop/PushT-v0, simloop/Scenario-v0 (simloop/gym.py).
register_when_gymnasium_loads()
