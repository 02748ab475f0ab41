"""Scenarios from Python: the chapter's loop on any scene, as data.

A scenario says what to run: the scene (an MJCF file, or the chapter's), the
timestep (the scene's own unless given), the length, the controls (intent),
the disturbances (interference) and what is recorded. It comes from a TOML
file, the same files sim_loop --scenario reads, or from keyword arguments,
which are written as such a file and read by the same (C++) parser, so both
are checked alike:

    >>> import simloop
    >>> s = simloop.Scenario(scene="tests/scenes/pusht.xml", steps=500,
    ...                      controls={"push_x": 0.8, "push_y": [(0.0, 0.0), (0.5, 0.4)]},
    ...                      disturbances=[dict(body="tblock", force=[0, 1, 0], start=0.6, duration=0.1)])
    >>> result = simloop.run_scenario(s, seed=0)
    >>> result.column("tblock_x")[-1]
"""

from __future__ import annotations

import json
import math
import numbers
import os
from typing import (TYPE_CHECKING, Any, Callable, Dict, Iterable, List, Literal, Mapping, Optional, Sequence, Tuple, Union,
                    overload)

from . import _core
from ._api import (Progress, _check_bool, _check_no_control_every, _sequence, _check_int, _check_progress, _check_timestep, _describe,
                   _show, _U64_MAX, RNGS, load_model)

if TYPE_CHECKING:  # numpy and the tables load when used: `import simloop` stays quick
    import numpy as np

    from .tables import BatchTable

ScenarioResult = _core.ScenarioResult


def _toml_string(name: str, text: str) -> str:
    """A TOML basic string. JSON's escapes are not all TOML's: JSON writes a
    character beyond U+FFFF as a surrogate pair, which TOML refuses."""
    out = ['"']
    for ch in text:
        code = ord(ch)
        if 0xD800 <= code <= 0xDFFF:  # a byte that was not UTF-8 (os.fsdecode's surrogateescape)
            raise ValueError(f"{name} must be text (UTF-8; a scenario file cannot hold other bytes), got {text!r}")
        if ch in '"\\':
            out.append("\\" + ch)
        elif code < 0x20 or code == 0x7F:
            out.append(f"\\u{code:04x}")
        else:
            out.append(ch)
    return "".join(out) + '"'


def _number(name: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name} must be a number, got {_describe(value)}")
    try:
        return float(value)
    except OverflowError:
        raise ValueError(f"{name} must be a finite number, got {_describe(value)}") from None


def _control_entry(actuator: object, value: object) -> Dict[str, object]:
    """{actuator, value} for a number, {actuator, schedule} for (seconds, value)
    pairs, {actuator, csv} for a CSV file (a path object), or the file's own
    keys from a dict ({"csv": ..., "column": ...})."""
    name = f"controls[{actuator!r}]"
    if isinstance(value, numbers.Real) and not isinstance(value, bool):
        return {"actuator": actuator, "value": _number(name, value)}
    if isinstance(value, os.PathLike):
        return {"actuator": actuator, "csv": value}  # a value per step, one row each
    if isinstance(value, Mapping):
        return {"actuator": actuator, **value}
    shape = (f"{name} must be a number, a list of (seconds, value) pairs, a path object naming a CSV file, "
             f"or {{'csv': ..., 'column': ...}}, got {_describe(value)}")
    if isinstance(value, (str, bytes)) or not isinstance(value, Iterable):
        raise TypeError(shape)
    pairs = []
    for pair in value:
        try:
            if isinstance(pair, (str, bytes)):
                raise TypeError
            seconds, ctrl = pair  # a tuple, a list, a numpy row
        except (TypeError, ValueError):
            raise TypeError(shape) from None
        pairs.append([_number(name, seconds), _number(name, ctrl)])
    return {"actuator": actuator, "schedule": pairs}


def _toml_value(name: str, value: object) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if not math.isfinite(value):
            raise ValueError(f"{name} must be finite, got {value!r}")
        return repr(value)
    if isinstance(value, (str, bytes, os.PathLike)):
        return _toml_string(name, os.fsdecode(value))
    if isinstance(value, Sequence):
        return "[" + ", ".join(_toml_value(name, v) for v in value) + "]"
    if hasattr(value, "tolist"):  # numpy scalars and arrays
        return _toml_value(name, value.tolist())
    raise TypeError(f"{name} must be a number, a string or a list of them, got {_describe(value)}")


def _toml_table(header: str, items: Mapping[str, object]) -> str:
    lines = [header] if header else []
    for key, value in items.items():
        if value is None:
            continue
        if not isinstance(key, str):
            raise TypeError(f"keys must be strings, got {_describe(key)}")
        lines.append(f"{_toml_string(key, key)} = {_toml_value(key, value)}")
    return "\n".join(lines) + "\n"


class Scenario:
    """A scenario. Scenario(...) builds one from keyword arguments;
    Scenario.from_file(path) reads a TOML file; Scenario.chapter() is the
    chapter's run.

    scene: an MJCF file (None: the chapter's scene). timestep: seconds per
    step (None: the scene's own). steps or duration (seconds): the length.
    controls: {actuator: value} for a constant, {actuator: [(seconds,
    value), ...]} for a piecewise-constant schedule, or {actuator:
    Path("u.csv")} for a value per step from a CSV file's only column
    ({actuator: {"csv": ..., "column": ...}} to pick one); an actuator by
    name or index. disturbances: a list of dicts with the scenario file's keys (body,
    force, torque, newtons, direction, random_sign, start, start_step,
    start_fraction, duration, steps). record: a dict with bodies, joints,
    actuators, sensors (lists of names) and contacts (bool).
    """

    def __init__(self, scene: Union[str, "os.PathLike[str]", None] = None, *, name: str = "",
                 timestep: Optional[float] = None, steps: Optional[int] = None, duration: Optional[float] = None,
                 controls: Optional[Mapping[Union[str, int], Any]] = None,
                 disturbances: Iterable[Mapping[str, Any]] = (),
                 record: Optional[Mapping[str, Any]] = None) -> None:
        text = _toml_table("", {"name": name or None, "scene": scene, "timestep": timestep, "steps": steps,
                                "duration": duration})
        for actuator, value in (controls or {}).items():
            text += "\n" + _toml_table("[[control]]", _control_entry(actuator, value))
        for d in disturbances:
            if not isinstance(d, Mapping):
                raise TypeError(f"each disturbance must be a dict, got {_describe(d)}")
            text += "\n" + _toml_table("[[disturbance]]", d)
        if record is not None:
            text += "\n" + _toml_table("[record]", record)
        self._base = os.getcwd()  # where its relative paths resolve (sent along to workers)
        self._core = _core.Scenario.from_toml(text, "Scenario(...)", self._base)
        self.toml = text
        self._remake: Tuple[Any, ...] = (_from_toml, (text, os.getcwd()))

    @classmethod
    def from_file(cls, path: Union[str, "os.PathLike[str]"]) -> "Scenario":
        """Reads a scenario file (TOML); a relative scene resolves against its folder."""
        self = cls.__new__(cls)
        self._core = _core.Scenario.from_file(os.fspath(path))
        self._base = os.path.dirname(os.path.abspath(os.fspath(path)))
        self._remake = (Scenario.from_file, (os.path.abspath(path),))
        with open(path, encoding="utf-8") as f:
            self.toml = f.read()
        return self

    @classmethod
    def chapter(cls) -> "Scenario":
        """The chapter's run: its scene, push_motor at 1.0, the shove on the box."""
        self = cls.__new__(cls)
        self._core = _core.Scenario.chapter()
        self._base = ""
        self.toml = ""
        self._remake = (Scenario.chapter, ())
        return self

    # A Scenario does not change once made: copies are itself, and a pickle
    # makes it again the way it was made (Gymnasium deep-copies and pickles
    # an environment's arguments: env.spec.make(), AsyncVectorEnv).
    def __copy__(self) -> "Scenario":
        return self

    def __deepcopy__(self, memo: Dict[int, Any]) -> "Scenario":
        return self

    def __reduce__(self) -> Tuple[Any, ...]:
        return self._remake

    @property
    def name(self) -> str:
        return self._core.name

    @property
    def scene(self) -> str:
        """The scene's MJCF file ("" for the chapter's embedded scene)."""
        return self._core.scene

    @property
    def timestep(self) -> Optional[float]:
        return self._core.timestep

    def model(self) -> _core.Model:
        """The scene, compiled."""
        return _core.load_scene(self._core)

    def __repr__(self) -> str:
        return repr(self._core)


def _from_toml(text: str, base: str) -> Scenario:
    """A keyword Scenario made again (for pickling)."""
    self = Scenario.__new__(Scenario)
    self._core = _core.Scenario.from_toml(text, "Scenario(...)", base)
    self.toml = text
    self._remake = (_from_toml, (text, base))
    return self


def _scenario_and_scene(scenario: Union[Scenario, str, "os.PathLike[str]"],
                        model: Optional[_core.Model]) -> Tuple[Scenario, _core.Model]:
    if isinstance(scenario, (str, os.PathLike)):
        scenario = Scenario.from_file(scenario)
    if not isinstance(scenario, Scenario):
        raise TypeError(f"scenario must be a simloop.Scenario or a scenario file's path, got {_describe(scenario)}")
    scene = scenario.model() if model is None else model
    if not isinstance(scene, _core.Model):
        from ._mujoco_check import is_mujoco_model

        if not is_mujoco_model(scene):
            raise TypeError(f"model must be a simloop.Model or a mujoco.MjModel, got {_describe(scene)}")
        scene = load_model(scene)
    return scenario, scene


def _inputs_array(name: str, value: object, shapes: Tuple[int, ...], described: str) -> Optional[np.ndarray]:
    """value as a C-contiguous float64 array (the same array, not a copy,
    when it already is one), or None. Values are checked by the C++ side,
    which knows the run's steps, actuators and state size."""
    if value is None:
        return None
    import numpy as np

    if isinstance(value, (str, bytes)):
        raise TypeError(f"{name} must be an array of numbers {described}, got {_describe(value)}")
    try:
        array = np.asarray(value)
    except (TypeError, ValueError):  # ragged lists
        raise TypeError(f"{name} must be an array of numbers {described}, got {_describe(value)}") from None
    if array.dtype.kind not in "iuf":
        raise TypeError(f"{name} must be an array of numbers {described}, got an array of dtype {array.dtype}")
    if array.ndim not in shapes:
        raise ValueError(f"{name} must be {described}, got shape {array.shape}")
    return np.ascontiguousarray(array, dtype=np.float64)


class Observation:
    """What a policy sees at a decision step: the scenario's recorded
    quantities for the state entering that step.

    step: the decision step (0, K, 2K, ...). time: the sim time, s.
    values: a read-only float64 vector, one value per name in `names`, which
    are the run's trajectory columns after "step" and "time"
    (result.column_names[2:]): ctrl inputs, disturbance forces, body poses
    and velocities, joints, actuator forces, sensors, ncon. obs["tblock_x"]
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
            import difflib

            close = difflib.get_close_matches(str(name), list(self._index), n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise KeyError(f"no observed quantity named {name!r}{hint}; the observation has: "
                           + ", ".join(self._index))
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
    import numpy as np

    shape = f"{nu} ctrl values (shape ({nu},){', or a number' if nu == 1 else ''})"
    if value is None or isinstance(value, (str, bytes)) or np.asarray(value).dtype.kind not in "iuf":
        raise ValueError(f"the policy must return {shape}, got {_describe(value)} at decision step {step}")
    try:
        ctrl = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"the policy must return {shape}, got {_describe(value)} at decision step {step}") from None
    if ctrl.ndim == 0 and nu == 1:
        ctrl = ctrl.reshape(1)
    if ctrl.shape != (nu,):
        raise ValueError(f"the policy must return {shape}, got shape {ctrl.shape} at decision step {step}")
    if not np.isfinite(ctrl).all():
        raise ValueError(f"the policy returned a ctrl that is not finite at decision step {step}: {_show(value)}")
    return ctrl


def _decider(policy: object, control_every: object, scene: _core.Model, scenario: Scenario,
             config: "_core.ScenarioConfig") -> Tuple[Callable[[int, np.ndarray], np.ndarray], int]:
    """The C++ loop's decide(step, row) around the user's policy(obs), and K."""
    if not callable(policy):
        raise TypeError(f"policy must be None or a callable policy(observation) -> ctrl, got {_describe(policy)}")
    every = _check_int("control_every", control_every, 1, _core.MAX_STEPS)
    # The run's columns (and its names checked) before the first step.
    names = _core.Episodes(scene, scenario._core, config, 0).column_names[2:]
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


def run_scenario(scenario: Union[Scenario, str, "os.PathLike[str]"], *, seed: int = 0, rng: str = "mt19937_64",
                 timestep: Optional[float] = None, steps: Optional[int] = None, perturb: bool = True,
                 record_every: int = 1, model: Optional[_core.Model] = None,
                 progress: Progress = None, controls: Any = None, initial_state: Any = None,
                 policy: Optional[Policy] = None, control_every: int = 1) -> ScenarioResult:
    """Runs a scenario (a Scenario or a scenario file's path) once.

    seed draws its random disturbances and nothing else; rng is "mt19937_64"
    or "numpy" as for run(). timestep and steps override the scenario's;
    perturb=False drops its disturbances. model: the scene already compiled
    (scenario.model()), to compile it once for many runs. Returns a
    ScenarioResult: column_names, trajectory (a read-only numpy view),
    column(name), metrics (a dict), disturbances, warnings, final_row,
    final_state (the full state at the end), summary(), write(out).
    Unknown names raise ValueError listing what the scene has.

    controls: your own controls, as mujoco.rollout takes them: a (steps, nu)
    array whose row t is the whole ctrl vector (one value per actuator, in
    the scene's order) written before step t. They replace the scenario's
    controls; its disturbances still apply (perturb=False drops them). The
    rows must match the run's steps exactly (ValueError otherwise) and every
    value must be finite (NaN is refused, not read as "keep"); MuJoCo clamps
    values to ctrlrange as it applies them, and the ctrl columns record what
    it applied. A C-contiguous float64 array is read in place, not copied:
    do not write to it during the call.
    initial_state: start from this full state (time included) instead of the
    scene's reset pose: the flat layout of include/simloop/state.hpp, as
    result.final_state gives it, so a run continued from a result's
    final_state gives the bits of one longer run.

    policy: None (open loop: the scenario's controls), or a callable
    policy(obs) -> ctrl called every `control_every` steps (at steps 0, K,
    2K, ...) with an Observation, returning the ctrl of every actuator (nu
    numbers; a number when nu == 1), which MuJoCo then holds for the next K
    steps. With a policy, ctrl is the policy's on every actuator from step 0
    on: the scenario's controls are not written (its disturbances are). The
    trajectory records the ctrl applied, as always. The C++ loop takes the
    GIL only to call the policy. An exception the policy raises stops the
    run and reaches the caller with "(policy at decision step N)" added to
    its message; a ctrl of the wrong shape or not finite raises ValueError
    naming the decision step.
    """
    scenario, scene = _scenario_and_scene(scenario, model)
    if rng not in RNGS:
        raise ValueError(f"rng must be 'mt19937_64' or 'numpy', got {rng!r}")
    config = _core.ScenarioConfig(
        _check_int("seed", seed, 0, _U64_MAX), rng,
        None if timestep is None else _check_timestep(timestep),
        None if steps is None else _check_int("steps", steps, 1, _core.MAX_STEPS),
        _check_bool("perturb", perturb), _check_int("record_every", record_every, 1, _core.MAX_RECORD_EVERY))
    own = _inputs_array("controls", controls, (2,), "shaped (steps, nu)")
    start = _inputs_array("initial_state", initial_state, (1,), "shaped (state_size,)")
    if policy is not None:
        if own is not None or start is not None:
            raise ValueError("policy with controls or initial_state is not supported: the policy decides ctrl, "
                             "and its runs start from the scene's reset pose")
        decide, every = _decider(policy, control_every, scene, scenario, config)
        return _core.run_scenario(scene, scenario._core, config, decide=decide, control_every=every,
                                  progress=_check_progress(progress))
    _check_no_control_every(control_every)
    return _core.run_scenario(scene, scenario._core, config, controls=own, initial_state=start,
                              progress=_check_progress(progress))


# Typed for the checker: full results unless metrics_only or an executor (then a BatchTable).
@overload
def run_scenario_batch(scenario: Union[Scenario, str, "os.PathLike[str]"], seeds: Iterable[int] = (0,),
                       timesteps: Iterable[Optional[float]] = (None,), *, rng: str = "mt19937_64",
                       steps: Optional[int] = None, perturb: bool = True, record_every: int = 1,
                       model: Optional[_core.Model] = None, threads: Optional[int] = None,
                       progress: Progress = None, controls: Any = None, initial_state: Any = None,
                       metrics_only: Literal[False] = False, executor: None = None, chunk_size: Optional[int] = None,
                       policy: Optional[Policy] = None,
                       control_every: int = 1) -> List[ScenarioResult]: ...


@overload
def run_scenario_batch(scenario: Union[Scenario, str, "os.PathLike[str]"], seeds: Iterable[int] = (0,),
                       timesteps: Iterable[Optional[float]] = (None,), *, rng: str = "mt19937_64",
                       steps: Optional[int] = None, perturb: bool = True, record_every: int = 1,
                       model: Optional[_core.Model] = None, threads: Optional[int] = None,
                       progress: Progress = None, controls: Any = None, initial_state: Any = None,
                       metrics_only: Literal[True], executor: object = None, chunk_size: Optional[int] = None,
                       policy: Optional[Policy] = None,
                       control_every: int = 1) -> BatchTable: ...


@overload
def run_scenario_batch(scenario: Union[Scenario, str, "os.PathLike[str]"], seeds: Iterable[int] = (0,),
                       timesteps: Iterable[Optional[float]] = (None,), *, rng: str = "mt19937_64",
                       steps: Optional[int] = None, perturb: bool = True, record_every: int = 1,
                       model: Optional[_core.Model] = None, threads: Optional[int] = None,
                       progress: Progress = None, controls: Any = None, initial_state: Any = None,
                       metrics_only: bool = False, executor: object = None, chunk_size: Optional[int] = None,
                       policy: Optional[Policy] = None,
                       control_every: int = 1) -> Union[List[ScenarioResult], BatchTable]: ...


def run_scenario_batch(scenario: Union[Scenario, str, "os.PathLike[str]"], seeds: Iterable[int] = (0,),
                       timesteps: Iterable[Optional[float]] = (None,), *, rng: str = "mt19937_64",
                       steps: Optional[int] = None, perturb: bool = True, record_every: int = 1,
                       model: Optional[_core.Model] = None, threads: Optional[int] = None,
                       progress: Progress = None, controls: Any = None, initial_state: Any = None,
                       metrics_only: bool = False, executor: object = None, chunk_size: Optional[int] = None,
                       policy: Optional[Policy] = None,
                       control_every: int = 1) -> Union[List[ScenarioResult], BatchTable]:
    """Runs a scenario once per (seed, timestep) pair, in parallel over one scene.

    Results come in the order of itertools.product(seeds, timesteps), and each
    is bitwise identical to run_scenario() with the same arguments, whatever
    `threads` is (None: one worker per core). A timestep of None is the
    scenario's own (or the scene's). The scene is compiled once per distinct
    timestep and shared; each worker steps its own MuJoCo data. Every run is
    checked before any starts, and so is the memory all the kept trajectories
    take together. progress: as for run(), over the steps of all the runs.

    controls: (runs, steps, nu), run i following controls[i], or (steps, nu)
    for every run; initial_state: (runs, state_size) or (state_size,). As
    for run_scenario(), and read in place. runs is len(seeds) *
    len(timesteps), in the results' order.
    metrics_only: keep no trajectories and return a simloop.BatchTable (one
    row per run: the parameters, each recorded body's final position and
    speed, the disturbances as drawn, warning counts; unrounded), whose
    memory does not grow with the runs' lengths. .to_pandas(), .to_arrow().

    executor: a dask.distributed Client or a concurrent.futures.Executor, as
    for run_batch(): chunks on workers, metrics only, a BatchTable back (the
    scenario travels as its TOML text; model must be None; controls and
    initial_state stay local).

    policy, control_every: as for run_scenario(); one policy for every run,
    called with the GIL held from whichever worker reaches a decision (the
    others step on meanwhile). Results stay bitwise those of run_scenario()
    whatever `threads` is, as long as the policy's answer depends only on
    the observation it is given.
    """
    if executor is not None:
        if model is not None:
            raise TypeError("model must be None with executor= (the scenario's scene is compiled on each worker)")
        if controls is not None or initial_state is not None or policy is not None:
            raise ValueError("controls, initial_state and policy are not sent to an executor: run such batches "
                             "locally")
        scenario, scene = _scenario_and_scene(scenario, None)  # compiled here too: bad names fail before any work goes out
        _core.check_scenario_names(scenario._core, scene)
    else:
        scenario, scene = _scenario_and_scene(scenario, model)
    if rng not in RNGS:
        raise ValueError(f"rng must be 'mt19937_64' or 'numpy', got {rng!r}")
    seed_list = [_check_int("seeds[%d]" % i, s, 0, _U64_MAX) for i, s in enumerate(_sequence("seeds", seeds))]
    timestep_list = [None if t is None else _check_timestep(t, "timesteps[%d]" % i)
                     for i, t in enumerate(_sequence("timesteps", timesteps))]
    workers = 0 if threads is None else _check_int("threads", threads, 1, 4096)
    step_count = None if steps is None else _check_int("steps", steps, 1, _core.MAX_STEPS)
    perturb = _check_bool("perturb", perturb)
    every = _check_int("record_every", record_every, 1, _core.MAX_RECORD_EVERY)
    if executor is not None:
        from .distributed import run_scenario_batch_on

        return run_scenario_batch_on(executor, scenario, seed_list, timestep_list, rng=rng, steps=step_count,
                                     perturb=perturb, threads=threads, chunk_size=chunk_size,
                                     progress=_check_progress(progress))
    configs = [_core.ScenarioConfig(s, rng, t, step_count, perturb, every) for s in seed_list for t in timestep_list]
    metrics_only = _check_bool("metrics_only", metrics_only)
    if policy is not None:
        if controls is not None or initial_state is not None or metrics_only:
            raise ValueError("policy with controls, initial_state or metrics_only is not supported: give the "
                             "policy alone (its runs keep their trajectories and start from the reset pose)")
        if not configs:
            return []
        decide, decide_every = _decider(policy, control_every, scene, scenario, configs[0])
        return _core.run_scenario_batch(scene, scenario._core, configs, workers, decide=decide,
                                        control_every=decide_every, progress=_check_progress(progress))
    _check_no_control_every(control_every)
    own = _inputs_array("controls", controls, (2, 3), "shaped (runs, steps, nu) or (steps, nu)")
    start = _inputs_array("initial_state", initial_state, (1, 2), "shaped (runs, state_size) or (state_size,)")
    for name, array, ndim in (("controls", own, 3), ("initial_state", start, 2)):
        if array is not None and array.ndim == ndim and array.shape[0] != len(configs):
            raise ValueError(f"{name} holds {array.shape[0]} runs' inputs for {len(configs)} runs "
                             f"({len(seed_list)} seeds x {len(timestep_list)} timesteps)")
    results = _core.run_scenario_batch(scene, scenario._core, configs, workers, controls=own, initial_state=start,
                                       keep_rows=not metrics_only, progress=_check_progress(progress))
    if metrics_only:
        from .tables import table

        return table(results)
    return results


def _metrics(result: ScenarioResult) -> Dict[str, Any]:
    metrics: Dict[str, Any] = json.loads(result.metrics_json())
    return metrics


# The result's metrics as the dict metrics.json holds.
setattr(ScenarioResult, "metrics", property(_metrics, doc="The dict metrics.json holds (floats rounded to 6 decimals)."))
