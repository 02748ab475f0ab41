"""simloop: the chapter's MuJoCo simulation loop, from Python.

    >>> import simloop
    >>> result = simloop.run(seed=0)
    >>> result.metrics["lateral_drift"]
    0.045015

The loop itself is C++ (simloop._core); this package checks arguments, gives
numpy views of the trajectory, and writes the rerun recording.
"""

from typing import TYPE_CHECKING

try:
    from . import _core  # noqa: F401  (loads libmujoco; the line below explains a failure)
except ImportError as _error:
    from ._mujoco_check import load_failure_message

    _message = load_failure_message(_error)
    if _message is None:
        raise
    raise ImportError(_message) from None

from ._api import Sim, draw_shove, load_model, run, run_batch, sweep
from .scenario import Observation, Scenario, ScenarioResult, run_scenario, run_scenario_batch
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
    "Observation",
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

# Gymnasium: simloop/Chapter-v0, simloop/PushT-v0, simloop/Scenario-v0
# (simloop/gym.py, loaded by gymnasium.make through the entry points).
# Registered once gymnasium is imported: importing it here would cost every
# `import simloop` about 0.15 s, and nothing happens when it is not installed.
_GYMNASIUM_IDS = {
    "simloop/Chapter-v0": ("simloop.gym:chapter_env", "simloop.gym:chapter_vector_env"),
    "simloop/PushT-v0": ("simloop.gym:pusht_env", "simloop.gym:pusht_vector_env"),
    "simloop/Scenario-v0": ("simloop.gym:ScenarioEnv", "simloop.gym:ScenarioVectorEnv"),
}


def _register_envs(gymnasium) -> None:  # type: ignore[no-untyped-def]
    for env_id, (entry_point, vector_entry_point) in _GYMNASIUM_IDS.items():
        if env_id not in gymnasium.registry:
            gymnasium.register(id=env_id, entry_point=entry_point, vector_entry_point=vector_entry_point)


def _register_with_gymnasium() -> None:
    import sys

    if "gymnasium" in sys.modules:
        _register_envs(sys.modules["gymnasium"])
        return
    import importlib.abc
    import importlib.util

    if importlib.util.find_spec("gymnasium") is None:
        return

    class _WhenGymnasiumLoads(importlib.abc.MetaPathFinder):
        def find_spec(self, name, path, target=None):  # type: ignore[no-untyped-def]
            if name != "gymnasium":
                return None
            sys.meta_path.remove(self)
            spec = importlib.util.find_spec(name)
            if spec is None or spec.loader is None:
                return spec
            execute = spec.loader.exec_module

            def exec_module(module):  # type: ignore[no-untyped-def]
                execute(module)
                _register_envs(module)

            spec.loader.exec_module = exec_module  # type: ignore[method-assign]
            return spec

    sys.meta_path.insert(0, _WhenGymnasiumLoads())


_register_with_gymnasium()
