"""A policy in the loop: what it sees at a decision step (Observation), and
its answers checked on their way back to the C++ loop (run_scenario's and
run_scenario_batch's policy=, run(policy=...)).
"""

from __future__ import annotations

import concurrent.futures
import importlib
import pickle
from typing import TYPE_CHECKING, Any, Callable, Mapping, Tuple, Union

from . import _core
from ._checks import _check_int, _describe, _did_you_mean, _show
from .scenario import Scenario

if TYPE_CHECKING:  # numpy loads when a policy runs: `import simloop` stays quick
    import numpy as np


class Observation:
    """What a policy sees at a decision step: the scenario's recorded
    quantities for the state entering that step.

    step: the decision step (0, K, 2K, ...). time: the sim time, s.
    values: a read-only float64 vector, one value per name in `names`, which
    are the run's trajectory columns after "step" and "time"
    (result.column_names[2:]): ctrl inputs, disturbance forces, body poses
    and velocities, joints, actuator forces, sensors, contacts. obs["tblock_x"]
    reads one by name. The ctrl columns hold the ctrl in force until now (the
    previous decision's; 0 before the first), and so do actuator forces; the
    force columns hold the disturbances acting in this step.
    """

    __slots__ = ("step", "time", "values", "_index")

    def __init__(self, step: int, time: float, values: np.ndarray, index: Mapping[str, int]) -> None:
        self.step = step
        self.time = time
        self.values = values
        self._index = index

    @property
    def names(self) -> Tuple[str, ...]:
        return tuple(self._index)

    def __getitem__(self, name: str) -> float:
        if name not in self._index:
            raise KeyError(
                f"no observed quantity named {name!r}{_did_you_mean(str(name), self._index)}; "
                f"the observation has: {', '.join(self._index)}"
            )
        return float(self.values[self._index[name]])

    def __repr__(self) -> str:
        return f"Observation(step={self.step}, time={self.time!r}, {len(self._index)} values)"


Policy = Callable[[Observation], Any]


def _with_decision_step(error: BaseException, step: int) -> None:
    """Names the decision step in the message of an exception a policy raised."""
    where = f"(policy at decision step {step})"
    if isinstance(error, KeyError) and hasattr(error, "add_note"):  # its message is the key itself: keep it
        error.add_note(where)
    elif len(error.args) == 1 and isinstance(error.args[0], str):
        error.args = (f"{error.args[0]} {where}",)
    elif not error.args:
        error.args = (where,)
    elif hasattr(error, "add_note"):  # several arguments (OSError's errno, ...): keep them
        error.add_note(where)


def _ctrl(value: object, nu: int, step: int) -> "np.ndarray":
    """The policy's answer as the float64 vector the C++ loop takes; the loop
    checks its values (nu of them, each finite) and names the step."""
    import numpy as np

    wanted = f"{nu} ctrl values (a vector{', or a number' if nu == 1 else ''})"
    if value is None or isinstance(value, (str, bytes)) or np.asarray(value).dtype.kind not in "iuf":
        raise ValueError(f"the policy must return {wanted}, got {_describe(value)} at decision step {step}")
    ctrl = np.asarray(value, dtype=np.float64)
    if ctrl.ndim == 0 and nu == 1:
        ctrl = ctrl.reshape(1)
    if ctrl.ndim != 1:
        raise ValueError(f"the policy must return {wanted}, got shape {ctrl.shape} at decision step {step}")
    return ctrl


def _decider(
    policy: object,
    control_every: object,
    scene: _core.Model,
    scenario: Union[Scenario, _core.Scenario],
    config: "_core.ScenarioConfig",
) -> Tuple[Callable[[int, np.ndarray], np.ndarray], int]:
    """The C++ loop's decide(step, row) around the user's policy(obs), and K."""
    if not callable(policy):
        raise TypeError(f"policy must be None or a callable policy(observation) -> ctrl, got {_describe(policy)}")
    every = _check_int("control_every", control_every)  # its range: the C++ loop's
    # The run's columns (and its names checked) before the first step.
    core = scenario if isinstance(scenario, _core.Scenario) else scenario._core  # a chunk's on a worker: the core's
    names = _core.scenario_columns(scene, core, config)[2:]
    index = {name: i for i, name in enumerate(names)}
    nu = scene.nu

    def decide(step: int, row: np.ndarray) -> np.ndarray:
        values = row[2:]
        values.flags.writeable = False
        try:
            out = policy(Observation(step, float(row[1]), values, index))
        except Exception as error:
            _with_decision_step(error, step)
            raise
        return _ctrl(out, nu, step)

    return decide, every


def _check_no_control_every(control_every: object) -> None:
    """control_every without a policy: there is nothing to decide, so a value
    other than the default would be silently ignored."""
    if _check_int("control_every", control_every) != 1:
        raise ValueError(
            f"control_every={_show(control_every)} needs a policy (policy=f): without one the run "
            "follows the scenario's controls"
        )


def _check_policy_travels(policy: object, executor: object, dask: bool) -> None:
    """A policy pickles as the executor will carry it (Dask: cloudpickle; a thread pool: not at all), or one
    line naming it."""
    if not callable(policy):
        raise TypeError(f"policy must be None or a callable policy(observation) -> ctrl, got {type(policy).__name__}")
    if isinstance(executor, concurrent.futures.ThreadPoolExecutor):
        return
    pickler: Any = importlib.import_module("cloudpickle") if dask else pickle
    try:
        pickler.dumps(policy)
    except Exception as error:
        why = " ".join(f"{type(error).__name__}: {error}".split())
        raise TypeError(
            f"policy {getattr(policy, '__qualname__', type(policy).__name__)!r} cannot go to the executor: it does "
            f"not pickle ({why}); define it at a module's top level, or run the batch locally"
        ) from None
