"""simloop's Python API: arguments checked in Python's words, then the C++ loop.

Nothing here steps physics: `run`, `run_batch` and `Sim` validate what they are
given (raising TypeError or ValueError that names the argument and the value)
and call the compiled core, which releases the GIL while it works. The
compiled classes' methods that take arguments (Model.from_file, RunResult.write,
RunResult.column, ...) are wrapped here the same way, so a wrong type gets one
line naming the argument, not pybind11's list of signatures.

The long calls (run, run_batch, Sim.step, sweep) stop within a few
milliseconds on Ctrl-C and raise KeyboardInterrupt; `progress=` takes a
callable progress(steps_done, steps_total), called from the calling thread at
most every 20 ms and once at the end (an exception it raises stops the work
and reaches the caller).
"""

from __future__ import annotations

import functools
import math
import numbers
import os
from pathlib import Path
from typing import (TYPE_CHECKING, Any, Callable, Dict, Iterable, List, Literal, Optional, Sequence, Tuple, Union, cast,
                    overload)

if TYPE_CHECKING:  # (importing numpy would cost every `import simloop` ~50 ms)
    import numpy as np
    from numpy.typing import NDArray

from . import _core
from ._core import MUJOCO_VERSION, Model, RunResult, SweepResult

if TYPE_CHECKING:
    from .tables import BatchTable

ModelLike = Union[None, Model, str, "os.PathLike[str]"]
PathLike = Union[str, bytes, "os.PathLike[str]"]
Progress = Optional[Callable[[int, int], object]]

_U64_MAX = 2**64 - 1
_I64_MAX = 2**63 - 1
# The ranges sim_loop's --steps and --record-every accept, 1 to 2**62-1
# (simloop::kMaxSteps, kMaxRecordEvery): steps + record_every fits in int64.
MAX_STEPS = _core.MAX_STEPS
MAX_RECORD_EVERY = _core.MAX_RECORD_EVERY


def _show(value: object) -> str:
    """repr(value) for an error message: one line, at most 80 characters."""
    try:
        text = repr(value)
    except Exception:  # an int past Python's digit limit, or a broken __repr__
        if isinstance(value, int):
            return f"an int of {value.bit_length()} bits"
        return f"a {type(value).__name__}"
    text = " ".join(line.strip() for line in text.splitlines())  # numpy arrays print on several lines
    return text if len(text) <= 80 else text[:77] + "..."


def _describe(value: object) -> str:
    return f"{_show(value)} ({type(value).__name__})"


def _check_int(name: str, value: object, minimum: int, maximum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(f"{name} must be an int, got {_describe(value)}")
    number = int(value)
    if not minimum <= number <= maximum:
        if maximum in _CAPS:  # a bound only huge values meet: said apart
            bound = f"at least {minimum}" if number < minimum else f"at most {maximum} (2**62-1)"
            raise ValueError(f"{name} must be {bound}, got {_show(number)}")
        raise ValueError(f"{name} must be an integer from {minimum} to {maximum}, got {_show(number)}")
    return number


_CAPS = (MAX_STEPS, MAX_RECORD_EVERY)


def _check_bool(name: str, value: object) -> bool:
    if type(value).__name__ not in ("bool", "bool_"):  # Python's bool or numpy's
        raise TypeError(f"{name} must be a bool, got {_describe(value)}")
    return bool(value)


def _check_real(name: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name} must be a number, got {_describe(value)}")
    try:
        return float(value)
    except OverflowError:  # an int beyond any float
        raise ValueError(f"{name} must be a number a float can hold, got {_show(value)}") from None


def _check_timestep(value: object, name: str = "timestep") -> float:
    timestep = _check_real(name, value)
    if not (math.isfinite(timestep) and timestep > 0.0):
        raise ValueError(f"{name} must be a positive, finite number of seconds, got {timestep!r}")
    return timestep


def _check_path(name: str, value: object, what: str) -> str:
    """A path as str (bytes decoded as os.fsdecode does: undecodable bytes
    become surrogates, which the core encodes back to the same bytes)."""
    if isinstance(value, (str, bytes, os.PathLike)):
        try:
            value = os.fsdecode(value)
        except TypeError:  # an os.PathLike whose __fspath__ returns neither
            pass
    if not isinstance(value, str):
        raise TypeError(f"{name} must be a path (str, bytes or os.PathLike), got {_describe(value)}")
    if not value:
        raise ValueError(f"{name} must name {what}, got ''")
    if "\0" in value:
        raise ValueError(f"{name} must not contain a NUL character, got {_show(value)}")
    return value


def _check_text(name: str, value: object) -> bytes:
    """str or bytes as the bytes the core reads (str as UTF-8)."""
    if isinstance(value, str):
        try:
            return value.encode("utf-8")
        except UnicodeEncodeError as e:
            raise ValueError(f"{name} must be text that UTF-8 can encode, got {value[e.start:e.end]!r} "
                             f"at index {e.start}") from None
    if isinstance(value, bytes):
        return value
    raise TypeError(f"{name} must be a str or bytes, got {_describe(value)}")


@functools.lru_cache(maxsize=1)
def _pusher_scene() -> Model:
    return Model.pusher_scene()


def load_model(model: ModelLike = None) -> Model:
    """The model to run: None for the chapter's scene, a Model, an MJCF path,
    or a mujoco.MjModel (copied; on simloop built on the same PyPI mujoco).

    A file that is missing raises OSError; one MuJoCo cannot parse raises
    simloop.MujocoError with MuJoCo's message; one without a body "box" on a
    free joint or an actuator 0 on a slide or hinge joint raises ValueError.
    """
    if model is None:
        return _pusher_scene()
    if isinstance(model, Model):
        return model
    if isinstance(model, (str, bytes, os.PathLike)):
        return Model.from_file(_check_path("model", model, "an MJCF file"))
    from ._mujoco_check import is_mujoco_model, mujoco_model_address

    if is_mujoco_model(model):
        return Model._copy_of_address(mujoco_model_address(model, MUJOCO_VERSION), "mujoco.MjModel")
    raise TypeError("model must be None, a simloop.Model, a mujoco.MjModel or a path to an MJCF file, "
                    f"got {_describe(model)}")


RNGS = ("mt19937_64", "numpy")


def _check_rng(value: object) -> str:
    if not isinstance(value, str):
        raise TypeError(f"rng must be a str, got {_describe(value)}")
    if value not in RNGS:
        raise ValueError(f"rng must be 'mt19937_64' or 'numpy', got {value!r}")
    return value


def _config(seed: object, steps: object, timestep: object, perturb: object, smoke: object,
            record_every: object, audit_energy: object = False, rng: object = "mt19937_64") -> _core.RunConfig:
    return _core.RunConfig(
        seed=_check_int("seed", seed, 0, _U64_MAX),
        steps=_check_int("steps", steps, 1, MAX_STEPS),
        timestep=_check_timestep(timestep),
        perturb=_check_bool("perturb", perturb),
        smoke=_check_bool("smoke", smoke),
        record_every=_check_int("record_every", record_every, 1, MAX_RECORD_EVERY),
        audit_energy=_check_bool("audit_energy", audit_energy),
        rng=_check_rng(rng),
    )


def _check_no_control_every(control_every: object) -> None:
    """control_every without a policy: there is nothing to decide, so a value
    other than the default would be silently ignored."""
    _check_int("control_every", control_every, 1, MAX_STEPS)
    if control_every != 1:
        raise ValueError(f"control_every={_show(control_every)} needs a policy (policy=f): without one the run "
                         "follows the scenario's controls")


def _check_progress(progress: object) -> Progress:
    if progress is not None and not callable(progress):
        raise TypeError(f"progress must be None or a callable progress(steps_done, steps_total), got {_describe(progress)}")
    return progress


@overload
def run(seed: int = 0, steps: int = 2000, timestep: float = 0.002, perturb: bool = True, smoke: bool = False,
        model: ModelLike = None, record_every: int = 1, audit_energy: bool = False,
        rng: str = "mt19937_64", *, progress: Progress = None, policy: None = None,
        control_every: int = 1) -> RunResult: ...


@overload
def run(seed: int = 0, steps: int = 2000, timestep: float = 0.002, perturb: bool = True, smoke: bool = False,
        model: ModelLike = None, record_every: int = 1, audit_energy: bool = False,
        rng: str = "mt19937_64", *, progress: Progress = None, policy: Callable[..., object],
        control_every: int = 1) -> "_core.ScenarioResult": ...


def run(seed: int = 0, steps: int = 2000, timestep: float = 0.002, perturb: bool = True, smoke: bool = False,
        model: ModelLike = None, record_every: int = 1, audit_energy: bool = False,
        rng: str = "mt19937_64", *, progress: Progress = None, policy: Optional[Callable[..., object]] = None,
        control_every: int = 1) -> "Union[RunResult, _core.ScenarioResult]":
    """Runs the chapter's loop once and returns what happened.

    seed: seeds the shove (0 to 2**64-1), and nothing else.
    steps: steps to run, 1 to 2**62-1 as sim_loop's --steps (ignored with
        smoke=True, which runs a fixed 300).
    timestep: sim seconds per mj_step, written into a copy of the model.
    perturb: False skips the shove (the baseline run).
    model: None (the chapter's scene), a simloop.Model, or an MJCF path.
    record_every: keep every K-th step in the trajectory (the final state is
        always kept), 1 to 2**62-1 as sim_loop's --record-every.
    audit_energy: account for every joule: the trajectory gains the
        ENERGY_COLUMN_NAMES columns and .energy holds the totals.
    rng: the generator that draws the shove from the seed: "mt19937_64"
        (std::mt19937_64, the default) or "numpy" (the chapter's
        np.random.default_rng(seed), PCG64, reproduced in C++ bit for bit;
        seed 0 shoves +9.82 N).
    progress: None, or progress(steps_done, steps_total), called at most
        every 20 ms and at the end; Ctrl-C raises KeyboardInterrupt promptly.

    The result has .metrics (the dict metrics.json holds), .trajectory (a
    read-only (rows, 22) float64 view, no copy) and .columns / .column(name),
    .shove, .warnings, .summary(), and .write(out) for metrics.json and
    trajectory.csv, byte-identical to `sim_loop` with the same flags.

    policy, control_every: a policy in the loop (see run_scenario): the run
    then goes through the chapter's scenario loop (Scenario.chapter(), with
    this call's seed, steps, timestep, perturb, model, record_every, rng)
    and returns a ScenarioResult (its columns named from the scene, its
    metrics the scenario's). The policy's ctrl replaces the chapter's 1.0;
    the shove acts as drawn. audit_energy is not available with a policy.
    """
    config = _config(seed, steps, timestep, perturb, smoke, record_every, audit_energy, rng)
    if policy is not None:
        return _run_chapter_with_policy(config, model, progress, policy, control_every)
    _check_no_control_every(control_every)
    return _core.run(load_model(model), config, progress=_check_progress(progress))


def _run_chapter_with_policy(config: "_core.RunConfig", model: ModelLike, progress: Progress,
                             policy: Callable[..., object], control_every: int) -> "_core.ScenarioResult":
    from .scenario import Scenario, run_scenario  # it imports this module

    if config.audit_energy:
        raise ValueError("audit_energy=True is not available with a policy (the audit is the chapter's open "
                         "loop's); leave one of them out")
    return run_scenario(Scenario.chapter(), seed=config.seed, rng=config.rng, timestep=config.timestep,
                        steps=_core.SMOKE_STEPS if config.smoke else config.steps, perturb=config.perturb,
                        record_every=config.record_every, model=load_model(model), progress=progress,
                        policy=policy, control_every=control_every)


def draw_shove(seed: int = 0, steps: int = 2000, rng: str = "mt19937_64") -> "_core.Shove":
    """The shove a run of `steps` steps draws from `seed`, without running it.

    The same Shove as run(seed=seed, steps=steps, rng=rng).shove: newtons,
    sign, force_y, start_step (steps // 2) and steps (50).
    """
    return _core.draw_shove(_check_int("seed", seed, 0, _U64_MAX), _check_int("steps", steps, 1, _I64_MAX),
                            _check_rng(rng))


def _sequence(name: str, values: object) -> List[Any]:
    if isinstance(values, (str, bytes)) or not isinstance(values, Iterable):
        raise TypeError(f"{name} must be a sequence, got {_describe(values)}")
    return list(values)


# Typed for the checker: full results unless metrics_only or an executor (then a BatchTable).
@overload
def run_batch(seeds: Iterable[int] = (0,), timesteps: Iterable[float] = (0.002,), *, steps: int = 2000,
              perturb: bool = True, smoke: bool = False, model: ModelLike = None, record_every: int = 1,
              audit_energy: bool = False, threads: Optional[int] = None, rng: str = "mt19937_64",
              progress: Progress = None, metrics_only: Literal[False] = False, executor: None = None,
              chunk_size: Optional[int] = None) -> List[RunResult]: ...


@overload
def run_batch(seeds: Iterable[int] = (0,), timesteps: Iterable[float] = (0.002,), *, steps: int = 2000,
              perturb: bool = True, smoke: bool = False, model: ModelLike = None, record_every: int = 1,
              audit_energy: bool = False, threads: Optional[int] = None, rng: str = "mt19937_64",
              progress: Progress = None, metrics_only: Literal[True], executor: object = None,
              chunk_size: Optional[int] = None) -> "BatchTable": ...


@overload
def run_batch(seeds: Iterable[int] = (0,), timesteps: Iterable[float] = (0.002,), *, steps: int = 2000,
              perturb: bool = True, smoke: bool = False, model: ModelLike = None, record_every: int = 1,
              audit_energy: bool = False, threads: Optional[int] = None, rng: str = "mt19937_64",
              progress: Progress = None, metrics_only: bool = False, executor: object = None,
              chunk_size: Optional[int] = None) -> "Union[List[RunResult], BatchTable]": ...


def run_batch(seeds: Iterable[int] = (0,), timesteps: Iterable[float] = (0.002,), *, steps: int = 2000,
              perturb: bool = True, smoke: bool = False, model: ModelLike = None, record_every: int = 1,
              audit_energy: bool = False, threads: Optional[int] = None, rng: str = "mt19937_64",
              progress: Progress = None, metrics_only: bool = False, executor: object = None,
              chunk_size: Optional[int] = None) -> "Union[List[RunResult], BatchTable]":
    """Runs every (seed, timestep) pair over one compiled model, in parallel.

    Results come in the order of itertools.product(seeds, timesteps), and each
    is bitwise identical to run() with the same arguments, whatever `threads`
    is (None: one worker per core). Each worker steps its own MuJoCo data;
    the model is shared. Every argument is checked before any run starts.
    progress: as for run(), over the steps of all the runs.
    metrics_only: keep no trajectories and return a simloop.BatchTable, one
    row per run (the parameters, the metrics unrounded, the shove, warning
    counts), whose memory does not grow with the runs' lengths:
    .to_pandas(), .to_arrow(), table["lateral_drift"].

    executor: a dask.distributed Client or a concurrent.futures.Executor
    (simloop.distributed): the runs go out in chunks of chunk_size (None: a
    default), each chunk run on a worker by the C++ batch with `threads`
    threads (None: 1), metrics only, and a BatchTable comes back (one row
    per run, in the same order, the same bits as a local metrics-only
    batch). model must then be None or an MJCF path; progress is called as
    progress(runs_done, runs_total) as chunks finish.
    """
    seed_list = [_check_int("seeds[%d]" % i, s, 0, _U64_MAX) for i, s in enumerate(_sequence("seeds", seeds))]
    timestep_list = [_check_timestep(t, "timesteps[%d]" % i) for i, t in enumerate(_sequence("timesteps", timesteps))]
    workers = 0 if threads is None else _check_int("threads", threads, 1, 4096)
    configs = [_config(s, steps, t, perturb, smoke, record_every, audit_energy, rng)
               for s in seed_list for t in timestep_list]
    metrics_only = _check_bool("metrics_only", metrics_only)
    if executor is not None:
        from .distributed import run_batch_on

        return run_batch_on(executor, configs, model, threads, chunk_size, _check_progress(progress))
    if metrics_only:
        from .tables import table
        return table(_core.run_batch(load_model(model), configs, workers, keep_rows=False,
                                     progress=_check_progress(progress)))
    return _core.run_batch(load_model(model), configs, workers, progress=_check_progress(progress))


def _finite_vector(name: str, value: object, size: int, what: str) -> "Union[Sequence[float], NDArray[np.float64]]":
    """A vector of `size` finite numbers from a sequence or a numeric numpy array;
    TypeError or ValueError naming `name`, its shape and the size wanted."""
    import numpy as np

    if isinstance(value, np.ndarray) and value.dtype == np.float64 and value.shape == (size,) \
            and np.isfinite(value).all():
        return value  # the common case, kept cheap
    if isinstance(value, np.ndarray):
        if value.dtype.kind not in "biuf":
            raise TypeError(f"{name} must hold numbers ({what}), got an array of dtype {value.dtype}")
        array = value.astype(np.float64)
    elif isinstance(value, Sequence) and not isinstance(value, (str, bytes)):
        array = np.array([_check_real("%s[%d]" % (name, i), v) for i, v in enumerate(value)], dtype=np.float64)
    else:
        raise TypeError(f"{name} must be a sequence or numpy array of {size} numbers ({what}), got {_describe(value)}")
    if array.shape != (size,):
        raise ValueError(f"{name} must have shape ({size},) ({what}), got shape {array.shape}")
    bad = np.flatnonzero(~np.isfinite(array))
    if bad.size:
        raise ValueError(f"{name}[{bad[0]}] must be finite, got {float(array[bad[0]])!r}")
    values: List[float] = array.tolist()
    return values


_JOINT_TYPES = ("free", "ball", "slide", "hinge")


class _Named:
    """One named object of a Sim's scene (base of the body, joint, actuator and sensor views)."""

    __slots__ = ("_sim", "id", "name")
    _kind = ""

    def __init__(self, sim: "Sim", id: int, name: str) -> None:
        self._sim = sim
        self.id = id
        self.name = name

    def _info(self) -> Dict[str, Any]:
        return self._sim.model.object_info(self._kind, self.id)

    def __repr__(self) -> str:
        return f"<simloop.Sim {self._kind} {self.id} {self.name!r}{self._details()}>"

    def _details(self) -> str:
        return ""


class BodyView(_Named):
    """A body: pose and velocity (world frame, as of the last step or
    Sim.forward(): MuJoCo derives them before integrating), mass, and the
    force/torque applied to it (a writable view of its xfrc_applied row)."""

    __slots__ = ()
    _kind = "body"

    @property
    def xpos(self) -> NDArray[np.float64]:
        """Position of the body's frame, world, m (a copy)."""
        xpos: NDArray[np.float64] = self._sim._views["xpos"][self.id].copy()
        return xpos

    @property
    def xquat(self) -> NDArray[np.float64]:
        """Orientation (w, x, y, z), world (a copy)."""
        xquat: NDArray[np.float64] = self._sim._views["xquat"][self.id].copy()
        return xquat

    @property
    def angular_velocity(self) -> NDArray[np.float64]:
        """rad/s, world frame (from cvel, mj_objectVelocity)."""
        return self._sim._sim.body_velocity(self.id)[:3]

    @property
    def linear_velocity(self) -> NDArray[np.float64]:
        """m/s of the body's origin, world frame (from cvel, mj_objectVelocity)."""
        return self._sim._sim.body_velocity(self.id)[3:]

    @property
    def mass(self) -> float:
        mass: float = self._info()["mass"]
        return mass

    @property
    def xfrc_applied(self) -> NDArray[np.float64]:
        """(fx, fy, fz, tx, ty, tz) applied on this body: a writable view; it persists."""
        row: NDArray[np.float64] = self._sim._views["xfrc_applied"][self.id]
        return row

    def _details(self) -> str:
        return f" mass={self.mass!r}"


class JointView(_Named):
    """A joint: its type and its slices of qpos and qvel (writable views)."""

    __slots__ = ()
    _kind = "joint"

    @property
    def type(self) -> str:
        """'free', 'ball', 'slide' or 'hinge'."""
        kind: str = self._info()["type"]
        return kind

    @property
    def qpos(self) -> NDArray[np.float64]:
        info = self._info()
        return self._sim._views["qpos"][info["qposadr"]:info["qposadr"] + info["nq"]]

    @property
    def qvel(self) -> NDArray[np.float64]:
        info = self._info()
        return self._sim._views["qvel"][info["dofadr"]:info["dofadr"] + info["nv"]]

    def _details(self) -> str:
        return f" type={self.type}"


class ActuatorView(_Named):
    """An actuator: its ctrl (a writable view of one value), the force it
    produced in the last step, and its ctrlrange."""

    __slots__ = ()
    _kind = "actuator"

    @property
    def ctrl(self) -> NDArray[np.float64]:
        return self._sim._views["ctrl"][self.id:self.id + 1]

    @property
    def force(self) -> float:
        """actuator_force: its scalar force in the last step, before the gear (a motor: ctrl)."""
        return float(self._sim._views["actuator_force"][self.id])

    @property
    def ctrlrange(self) -> Optional[Tuple[float, float]]:
        """(low, high) MuJoCo clamps ctrl to, or None if unlimited."""
        info = self._info()
        return info["ctrlrange"] if info["ctrllimited"] else None

    def _details(self) -> str:
        return f" ctrlrange={self.ctrlrange}"


class SensorView(_Named):
    """A sensor: its readings (a read-only view into sensordata)."""

    __slots__ = ()
    _kind = "sensor"

    @property
    def data(self) -> NDArray[np.float64]:
        info = self._info()
        return self._sim._views["sensordata"][info["adr"]:info["adr"] + info["dim"]]


def _view_property(name: str, doc: str, settable: bool = False) -> property:
    """A Sim property giving its view `name`; settable: assigning writes into the view (checked)."""
    def get(self: "Sim") -> NDArray[np.float64]:
        return self._views[name]

    def set(self: "Sim", value: object) -> None:
        self._set_array(name, value)

    return property(get, set if settable else None, doc=doc)


_ARRAYS = ("qpos", "qvel", "ctrl", "act", "qfrc_applied", "xfrc_applied", "sensordata", "actuator_force", "xpos",
           "xquat")


class Sim:
    """The loop's rhythm, one call at a time, on any scene: write ctrl, write forces, step, look.

        sim = simloop.Sim("tests/scenes/walker.xml")      # a Model, an MJCF path, a Scenario
        sim.ctrl[:] = 0.3                                   # or sim.step(100, ctrl=[...])
        sim.apply_force(body="torso", force=[0, 0, 20])     # persists until clear_forces()
        sim.step(100)
        sim.body("torso").xpos, sim.joint("hip").qpos, sim.sensor(0).data
        saved = sim.get_state(); ...; sim.set_state(saved)  # bit for bit

    Arrays. qpos, qvel, ctrl, act, qfrc_applied and xfrc_applied (nbody x 6)
    are numpy VIEWS into MuJoCo's mjData, writable: a write takes effect at
    the next step, and what you hold changes when the Sim steps (copy it to
    keep it). sensordata is a read-only view. A view keeps its Sim alive, and
    the mjData never moves, so a view never dangles. Derived quantities (a
    body's xpos, xquat, velocity) are copies, as of the last step: MuJoCo
    computes them before integrating; forward() brings them up to date
    without changing the run's bits.

    Threads. Each method call (step, reads, get/set_state, apply_force...)
    holds the Sim's lock, so calls from several threads take turns. The
    views do NOT take the lock: reading or writing one while another thread
    steps the Sim sees a half-written state. Share a Sim across threads
    through its methods, or give each thread its own copy (copy.copy(sim)).

    IMPORTANT: like MuJoCo's xfrc_applied, a force set with apply_force()
    PERSISTS. MuJoCo never clears it: it pushes on every following step until
    you clear it. ctrl persists the same way. Forgetting this is the
    chapter's classic bug (exercise 2).

    Sim(scenario) takes the scenario's scene and timestep only: you drive
    the loop (ctrl, forces); its controls and disturbances are not applied
    (run_scenario does that).

    The chapter's accessors (box_position, pusher_x, apply_force(force),
    clear_force, ...) need the chapter's layout (a body "box" on a free
    joint, actuator 0 on a slide or hinge joint); on another scene they
    raise ValueError saying what it lacks.

    copy.copy / copy.deepcopy give an independent Sim (its own data, the
    same read-only model); pickle carries the model, the full state and
    steps_taken (not MuJoCo's warnings).
    """

    def __init__(self, model: Union[ModelLike, "object"] = None, timestep: Optional[float] = None) -> None:
        from .scenario import Scenario  # here: scenario.py imports this module

        if isinstance(model, Scenario):
            if timestep is None:
                timestep = model.timestep
            model = model.model()
        # load_model checks what model is at runtime (TypeError naming it).
        self._sim = _core.Sim(load_model(cast(ModelLike, model)))
        self._make_views()
        if timestep is not None:
            self.timestep = timestep

    def _make_views(self) -> None:
        self._views = {name: self._sim.array(name) for name in _ARRAYS}

    @classmethod
    def _wrapping(cls, core: "_core.Sim") -> "Sim":
        sim = cls.__new__(cls)
        sim._sim = core
        sim._make_views()
        return sim

    def __copy__(self) -> "Sim":
        return Sim._wrapping(self._sim.copy())

    def __deepcopy__(self, memo: Dict[int, Any]) -> "Sim":
        return Sim._wrapping(self._sim.copy())

    def __getstate__(self) -> Dict[str, Any]:
        return {"sim": self._sim}

    def __setstate__(self, state: Dict[str, Any]) -> None:
        self._sim = state["sim"]
        self._make_views()

    @property
    def model(self) -> Model:
        """This Sim's model (its own copy when the timestep was changed)."""
        return self._sim.model

    @property
    def timestep(self) -> float:
        """Sim seconds per step (this Sim's own copy of the model)."""
        return self._sim.timestep

    @timestep.setter
    def timestep(self, value: float) -> None:
        self._sim.set_timestep(_check_timestep(value))

    # --- The arrays (views; see the class docstring).

    def _set_array(self, name: str, value: object) -> None:
        view = self._views[name]
        view[:] = _finite_vector(name, value, view.size, f"{name} has {view.size} values")

    qpos = _view_property("qpos", "Joint positions (nq), a writable view.", settable=True)
    qvel = _view_property("qvel", "Joint velocities (nv), a writable view.", settable=True)

    @property
    def ctrl(self) -> Union[float, NDArray[np.float64]]:
        """The chapter's scene: the motor command ctrl[0], a float (MuJoCo clamps it to
        [-1, 1]). Any other scene: every actuator's ctrl (nu), a writable view."""
        if self.model.has_chapter_layout:
            return self._sim.ctrl
        return self._views["ctrl"]

    @ctrl.setter
    def ctrl(self, value: object) -> None:
        if isinstance(value, numbers.Real) and not isinstance(value, bool):
            nu = self.model.nu
            if nu != 1:  # one number for several actuators would set only the first
                raise ValueError(f"ctrl must be {nu} numbers, one per actuator (a single number is for a scene "
                                 f"with one actuator, as the chapter's), got {_show(value)}")
            number = _check_real("ctrl", value)
            if not math.isfinite(number):
                raise ValueError(f"ctrl must be finite, got {number!r}")
            self._sim.set_ctrl(number)
        else:
            self._sim.set_ctrl_vector(_finite_vector("ctrl", value, self.model.nu, "one per actuator"))

    ctrl_array = _view_property("ctrl", "Every actuator's ctrl (nu), a writable view, on any scene.")
    act = _view_property("act", "Actuator activations (na), a writable view.")
    qfrc_applied = _view_property("qfrc_applied", "Generalized forces applied (nv), a writable view; it persists.")
    xfrc_applied = _view_property("xfrc_applied", "Force and torque on each body, world frame (nbody x 6), a "
                                                  "writable view; it persists.")
    sensordata = _view_property("sensordata", "Every sensor's reading (nsensordata), a read-only view, as of the "
                                              "last step.")

    # --- Named access.

    def _lookup(self, kind: str, key: object) -> "tuple[int, str]":
        if isinstance(key, str):
            name = _check_text(kind, key)  # ValueError for text UTF-8 cannot hold
            if b"\0" in name:
                raise ValueError(f"{kind} must not contain a NUL character, got {_show(key)}")
            # _check_text gives UTF-8 bytes, which pybind11's std::string takes as well as str.
            index = self._sim.id(kind, name)  # type: ignore[arg-type]
        elif isinstance(key, numbers.Integral) and not isinstance(key, bool):
            number = int(key)
            if not -2**63 <= number < 2**63:
                plural = "bodies" if kind == "body" else kind + "s"
                raise ValueError(f"{kind} index {_show(number)} is out of range: the scene has "
                                 f"{len(self.model.names(kind))} {plural}")
            index = self._sim.checked_index(kind, number)
        else:
            raise TypeError(f"{kind} must be a name (str) or an index (int), got {_describe(key)}")
        return index, self.model.names(kind)[index]

    def body(self, key: Union[str, int]) -> BodyView:
        """A body by name or index: xpos, xquat, linear/angular_velocity, mass, id."""
        return BodyView(self, *self._lookup("body", key))

    def joint(self, key: Union[str, int]) -> JointView:
        """A joint by name or index: type, qpos and qvel (writable views)."""
        return JointView(self, *self._lookup("joint", key))

    def actuator(self, key: Union[str, int]) -> ActuatorView:
        """An actuator by name or index: ctrl (a writable view), force, ctrlrange."""
        return ActuatorView(self, *self._lookup("actuator", key))

    def sensor(self, key: Union[str, int]) -> SensorView:
        """A sensor by name or index: data (a read-only view)."""
        return SensorView(self, *self._lookup("sensor", key))

    # --- Stepping.

    def step(self, n: int = 1, ctrl: Optional[object] = None, *, progress: Progress = None) -> None:
        """Advances n steps (1 to 2**62-1); with ctrl given, writes it first (it then persists).

        ctrl: a number (ctrl[0], the chapter's motor) or a vector of nu
        numbers (every actuator). Ctrl-C stops a long step promptly
        (KeyboardInterrupt; the steps taken stay taken). progress: as for run().
        """
        count = _check_int("n", n, 1, MAX_STEPS)
        if ctrl is not None:
            self.ctrl = ctrl
        if progress is None:
            self._sim.step(count)
        else:
            self._sim.step_with_progress(count, _check_progress(progress))

    def forward(self) -> None:
        """Brings xpos, xquat, velocities, sensordata and contacts up to the current
        qpos/qvel (mj_forward) without changing the next step's bits."""
        self._sim.forward()

    # --- Forces.

    def apply_force(self, force: Optional[Sequence[float]] = None, *, body: Union[str, int, None] = None,
                    torque: Optional[Sequence[float]] = None) -> None:
        """Pushes with (fx, fy, fz) newtons and/or twists with (tx, ty, tz) N m, world
        frame, at the body's origin, from now on.

        body: a name or index; None is the chapter's box (force only). A part
        not given is left as it was. It PERSISTS until clear_forces() (or
        clear_force() for the box): MuJoCo does not reset it after a step.
        """
        if body is None:
            if torque is not None:
                raise ValueError("torque needs body=...: the chapter's apply_force(force) pushes the box only")
            if force is None:
                raise TypeError("apply_force needs a force (and body=... for a body other than the chapter's box)")
            self._sim.apply_force(self._force_components("force", force))
            return
        index, _ = self._lookup("body", body)
        if force is None and torque is None:
            raise ValueError("apply_force needs force=..., torque=... or both")
        self._sim.apply_wrench(index, None if force is None else self._force_components("force", force),
                               None if torque is None else self._force_components("torque", torque))

    @staticmethod
    def _force_components(name: str, value: object) -> "list[float]":
        values = _sequence(name, value)
        if len(values) != 3:
            axes = "(fx, fy, fz)" if name == "force" else "(tx, ty, tz)"
            raise ValueError(f"{name} must have 3 components {axes}, got {len(values)}")
        checked = [_check_real("%s[%d]" % (name, i), v) for i, v in enumerate(values)]
        for i, v in enumerate(checked):
            if not math.isfinite(v):
                raise ValueError(f"{name}[{i}] must be finite, got {v!r}")
        return checked

    def clear_force(self) -> None:
        """Stops pushing the chapter's box: writes zero into its xfrc_applied force."""
        self._sim.clear_force()

    def clear_forces(self) -> None:
        """Zeros every body's xfrc_applied (forces and torques)."""
        self._sim.clear_forces()

    @property
    def applied_force(self) -> NDArray[np.float64]:
        """The force now written on the chapter's box (a copy), N."""
        return self._sim.applied_force

    # --- State.

    def get_state(self) -> NDArray[np.float64]:
        """The full physics state as a flat float64 array (a copy): time, qpos,
        qvel, act, qacc_warmstart, ctrl, qfrc_applied, xfrc_applied, mocap_pos,
        mocap_quat, userdata (see state_layout()). set_state() of it continues
        bit for bit, in this Sim or another on the same model."""
        return self._sim.get_state()

    def set_state(self, state: object) -> None:
        """Restores a state from get_state() (a float64 array of state_size values).
        steps_taken and warnings are left as they are."""
        import numpy as np

        if not isinstance(state, np.ndarray):
            raise TypeError(f"state must be a numpy float64 array (from get_state()), got {_describe(state)}")
        if state.dtype != np.float64:
            raise ValueError(f"state must have dtype float64, got {state.dtype}")
        size = sum(n for _, n in self.state_layout())
        if state.shape != (size,):
            raise ValueError(f"state must have shape ({size},) for this model, got shape {state.shape}")
        bad = np.flatnonzero(~np.isfinite(state))
        if bad.size:
            raise ValueError(f"state must be finite, got {float(state[bad[0]])!r} at index {int(bad[0])}")
        self._sim.set_state(np.ascontiguousarray(state))

    def state_layout(self) -> "list[tuple[str, int]]":
        """The state's parts in order with their sizes: [('time', 1), ('qpos', nq), ...]."""
        return [(name, int(size)) for name, size in self._sim.state_layout]

    @property
    def state_size(self) -> int:
        return sum(n for _, n in self.state_layout())

    def reset(self, keyframe: Union[str, int, None] = None) -> None:
        """Back to t = 0, or to a keyframe of the scene (a name or index): state,
        ctrl, forces, steps_taken and warnings reset (timestep kept)."""
        if keyframe is None:
            self._sim.reset()
        else:
            self._sim.reset_to_keyframe(self._lookup("keyframe", keyframe)[0])

    @property
    def time(self) -> float:
        return self._sim.time

    @property
    def steps_taken(self) -> int:
        return self._sim.steps_taken

    # --- The chapter's scene.

    @property
    def box_position(self) -> NDArray[np.float64]:
        """The box's position now (x, y, z), m: a copy."""
        return self._sim.box_position

    @property
    def box_quaternion(self) -> NDArray[np.float64]:
        """The box's orientation now, (w, x, y, z) as MuJoCo stores it: a copy."""
        return self._sim.box_quaternion

    @property
    def box_velocity(self) -> NDArray[np.float64]:
        """The box's linear velocity now, m/s, world frame: a copy."""
        return self._sim.box_velocity

    @property
    def pusher_x(self) -> float:
        """The pusher's slide-joint position, m."""
        return self._sim.pusher_x

    @property
    def pusher_velocity(self) -> float:
        return self._sim.pusher_velocity

    @property
    def contacts(self) -> List[_core.Contact]:
        """The contacts of MuJoCo's last collision pass (geom1, geom2, dist, pos)."""
        return self._sim.contacts

    @property
    def warnings(self) -> List[_core.MujocoWarning]:
        """Warnings MuJoCo raised since construction or reset."""
        return self._sim.warnings

    def __repr__(self) -> str:
        model = self.model
        scene = repr(model.name) if model.name else "(unnamed)"
        return (f"<simloop.Sim {scene} t={self.time!r} steps_taken={self.steps_taken} timestep={self.timestep!r} "
                f"nq={model.nq} nv={model.nv} nu={model.nu} nbody={model.nbody}>")


# Typed for the checker: the chapter's SweepResult, or a ScenarioSweepResult for scenario=.
@overload
def sweep(timesteps: Optional[Iterable[float]] = None, duration: Optional[float] = None,
          threads: Optional[int] = None, model: ModelLike = None, *, scenario: None = None, seed: int = 0,
          rng: str = "mt19937_64", perturb: bool = True, progress: Progress = None, executor: object = None,
          chunk_size: Optional[int] = None) -> SweepResult: ...


@overload
def sweep(timesteps: Optional[Iterable[float]] = None, duration: Optional[float] = None,
          threads: Optional[int] = None, model: ModelLike = None, *, scenario: object, seed: int = 0,
          rng: str = "mt19937_64", perturb: bool = True, progress: Progress = None, executor: object = None,
          chunk_size: Optional[int] = None) -> "_core.ScenarioSweepResult": ...


def sweep(timesteps: Optional[Iterable[float]] = None, duration: Optional[float] = None,
          threads: Optional[int] = None, model: ModelLike = None, *, scenario: Any = None, seed: int = 0,
          rng: str = "mt19937_64", perturb: bool = True, progress: Progress = None, executor: object = None,
          chunk_size: Optional[int] = None) -> "Union[SweepResult, _core.ScenarioSweepResult]":
    """The baseline (no shove) at many timesteps over the same span of sim time.

    timesteps: None for the default: 25 round timesteps (1, 2, 3, 4, 5, 6 and
        8 per decade) from 0.0005 s to 1 s, from the stable range through the
        edge to the box sinking into the floor.
    duration: sim seconds each run covers (round(duration / timestep) steps);
        None: 4 s (a scenario's: its own length).

    scenario: a simloop.Scenario or a scenario file's path sweeps that
        scenario instead (with seed, rng and perturb; model: its scene
        already compiled), and returns a ScenarioSweepResult: per timestep
        the warnings, simloop_DIVERGED, the largest speed of any recorded
        body, each one's final position and its distance from the finest
        timestep's, and whether it blew up (warned, or a body ended more than
        SCENARIO_SWEEP_TOLERANCE times the scene's size from the finest
        timestep's). The default grid drops timesteps that would leave a run
        under 4 steps. Each point is bitwise run_scenario at that timestep.

    Runs in parallel over one compiled model with the energy audit on. The
    result's .points hold, per timestep, peak box z, largest |y|, the final
    positions, warnings, the audit's figures and whether it is stable; .edge
    is the largest timestep below which all are stable; .summary() the table,
    .write(out) sweep.csv. The criterion: the box rises at most 5 mm above
    rest, ends at most 1 mm below rest, and MuJoCo raised no warning.
    progress: as for run(), over the steps of all the timesteps.
    executor: a dask.distributed Client or a concurrent.futures.Executor: the
    timesteps go out in chunks (chunk_size), each swept on a worker with
    `threads` threads (None: 1); the same SweepResult comes back. model must
    then be None or an MJCF path; progress(points_done, points_total).
    """
    if timesteps is not None:
        values = [_check_timestep(t, "timesteps[%d]" % i) for i, t in enumerate(_sequence("timesteps", timesteps))]
        if not values:
            raise ValueError("timesteps must not be empty")
    if executor is not None:
        if scenario is not None:
            raise ValueError("sweep(scenario=..., executor=...) is not supported: a scenario sweep runs locally "
                             "(use run_scenario_batch(..., timesteps=..., executor=...) for its runs on a cluster)")
        from .distributed import sweep_on

        points = _core.default_sweep_timesteps() if timesteps is None else values
        span = _check_timestep(4.0 if duration is None else duration, "duration")
        return sweep_on(executor, points, span, model, threads, chunk_size, _check_progress(progress))
    workers = 0 if threads is None else _check_int("threads", threads, 1, 4096)
    if scenario is not None:
        return _sweep_scenario(scenario, None if timesteps is None else values, duration, workers, model, seed, rng,
                               perturb, progress)
    if timesteps is None:
        values = _core.default_sweep_timesteps()
    span = _check_timestep(4.0 if duration is None else duration, "duration")
    return _core.sweep(load_model(model), values, span, workers, progress=_check_progress(progress))


def _sweep_scenario(scenario: Any, timesteps: Optional[List[float]], duration: Optional[float], workers: int,
                    model: Any, seed: int, rng: str, perturb: bool, progress: Progress) -> "_core.ScenarioSweepResult":
    """sweep(scenario=...): the arguments checked, then the C++ sweep."""
    from .scenario import _scenario_and_scene

    scenario, scene = _scenario_and_scene(scenario, model)
    if rng not in RNGS:
        raise ValueError(f"rng must be 'mt19937_64' or 'numpy', got {rng!r}")
    config = _core.ScenarioConfig(_check_int("seed", seed, 0, _U64_MAX), rng, None, None,
                                  _check_bool("perturb", perturb), 1)
    span = _core.scenario_duration(scene, scenario._core) if duration is None else _check_timestep(duration, "duration")
    values = _core.default_scenario_sweep_timesteps(span) if timesteps is None else timesteps
    if not values:
        raise ValueError(f"duration {span!r} s is too short for any of the default timesteps (each run needs 4 steps); "
                         "give duration or timesteps")
    return _core.sweep_scenario(scene, scenario._core, values, span, config, workers,
                                progress=_check_progress(progress))


# The compiled classes' methods, checked in Python's words. pybind11 answers a
# wrong argument type with its four-line list of signatures; these answer with
# one line naming the argument. Defined in Python, so a wrong argument count
# gets Python's own one-line message too.

def _install_checked_methods() -> None:
    def from_file(path: PathLike) -> Model:
        return compiled_from_file(_check_path("path", path, "an MJCF file"))

    def from_xml_string(xml: Union[str, bytes], source: str = "<string>") -> Model:
        return compiled_from_xml_string(_check_text("xml", xml), _check_text("source", source))

    def pusher_scene() -> Model:
        return compiled_pusher_scene()

    compiled_from_file = Model.from_file
    compiled_from_xml_string = Model.from_xml_string
    compiled_pusher_scene = Model.pusher_scene
    for function, doc in (
            (from_file, "Compiles an MJCF file: OSError if it cannot be read, simloop.MujocoError if MuJoCo "
                        "rejects it, ValueError if it lacks a body 'box' on a free joint or an actuator 0 on a "
                        "slide or hinge joint."),
            (from_xml_string, "Compiles MJCF text (str or UTF-8 bytes); it needs a body 'box' on a free joint "
                              "and an actuator 0 on a slide or hinge joint. source names it in errors."),
            (pusher_scene, "The chapter's scene.")):
        function.__qualname__ = f"Model.{function.__name__}"
        function.__doc__ = doc
        setattr(Model, function.__name__, staticmethod(function))

    compiled: Dict[Tuple[type, str], Callable[..., Any]] = {(cls, name): getattr(cls, name) for cls, name in (
        (Model, "with_timestep"), (RunResult, "column"), (RunResult, "write"), (RunResult, "metrics_json"),
        (RunResult, "trajectory_csv"), (RunResult, "summary"), (SweepResult, "write"), (SweepResult, "csv"),
        (SweepResult, "summary"))}

    def with_timestep(self: Model, timestep: float) -> Model:
        copy: Model = compiled[Model, "with_timestep"](self, _check_timestep(timestep))
        return copy

    def column(self: RunResult, name: str) -> NDArray[np.float64]:
        if not isinstance(name, str):
            raise TypeError(f"name must be a str (a column name), got {_describe(name)}")
        if name not in self.column_names:
            raise KeyError(f"no trajectory column named {_show(name)}; see result.column_names")
        view: NDArray[np.float64] = compiled[RunResult, "column"](self, name)
        return view

    def write_run(self: RunResult, out: PathLike) -> Tuple[Path, Path]:
        paths: Tuple[Path, Path] = compiled[RunResult, "write"](self, _check_path("out", out, "a directory"))
        return paths

    def write_sweep(self: SweepResult, out: PathLike) -> Path:
        path: Path = compiled[SweepResult, "write"](self, _check_path("out", out, "a directory"))
        return path

    def no_arguments(cls: type, name: str) -> Callable[[object], str]:
        def method(self: object) -> str:
            text: str = compiled[cls, name](self)
            return text
        return method

    methods: List[Tuple[type, str, Callable[..., Any], str]] = [
        (Model, "with_timestep", with_timestep, "A copy with opt.timestep set (a positive, finite number)."),
        (RunResult, "column", column, "One trajectory column as a read-only (strided) view (no copy); "
                                      "KeyError if the result has no such column."),
        (RunResult, "write", write_run, "Writes metrics.json and trajectory.csv into out (a directory, made if "
                                        "missing), the bytes sim_loop writes; returns their paths."),
        (SweepResult, "write", write_sweep, "Writes sweep.csv into out (atomically); returns its path."),
        (RunResult, "metrics_json", no_arguments(RunResult, "metrics_json"), "metrics.json's text."),
        (RunResult, "trajectory_csv", no_arguments(RunResult, "trajectory_csv"), "trajectory.csv's text."),
        (RunResult, "summary", no_arguments(RunResult, "summary"), "The lines sim_loop prints about the run."),
        (SweepResult, "csv", no_arguments(SweepResult, "csv"), "sweep.csv's text."),
        (SweepResult, "summary", no_arguments(SweepResult, "summary"), "The sweep's table, edge and criterion."),
    ]
    for cls, name, checked, doc in methods:
        checked.__name__ = name
        checked.__qualname__ = f"{cls.__name__}.{name}"
        checked.__doc__ = doc
        setattr(cls, name, checked)


_install_checked_methods()
