"""simloop's Python API: arguments checked in Python's words, then the C++ loop.

Nothing here steps physics: `run`, `run_batch` and `Sim` validate what they are
given (raising TypeError or ValueError that names the argument and the value)
and call the compiled core, which releases the GIL while it works.
"""

from __future__ import annotations

import functools
import math
import numbers
import os
from typing import Iterable, List, Optional, Sequence, Union

from . import _core
from ._core import Model, RunResult

ModelLike = Union[None, Model, str, "os.PathLike[str]"]

_U64_MAX = 2**64 - 1
_I64_MAX = 2**63 - 1


def _describe(value: object) -> str:
    return f"{value!r} ({type(value).__name__})"


def _check_int(name: str, value: object, minimum: int, maximum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(f"{name} must be an int, got {_describe(value)}")
    number = int(value)
    if not minimum <= number <= maximum:
        if maximum == _I64_MAX:  # no upper bound worth stating
            raise ValueError(f"{name} must be at least {minimum}, got {number}")
        raise ValueError(f"{name} must be an integer from {minimum} to {maximum}, got {number}")
    return number


def _check_bool(name: str, value: object) -> bool:
    if type(value).__name__ not in ("bool", "bool_"):  # Python's bool or numpy's
        raise TypeError(f"{name} must be a bool, got {_describe(value)}")
    return bool(value)


def _check_real(name: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name} must be a number, got {_describe(value)}")
    return float(value)


def _check_timestep(value: object, name: str = "timestep") -> float:
    timestep = _check_real(name, value)
    if not (math.isfinite(timestep) and timestep > 0.0):
        raise ValueError(f"{name} must be a positive, finite number of seconds, got {timestep!r}")
    return timestep


@functools.lru_cache(maxsize=1)
def _pusher_scene() -> Model:
    return Model.pusher_scene()


def load_model(model: ModelLike = None) -> Model:
    """The model to run: None for the chapter's scene, a Model, or an MJCF path.

    A file that is missing raises OSError; one MuJoCo cannot parse raises
    simloop.MujocoError with MuJoCo's message; one without a body "box" on a
    free joint or an actuator 0 on a slide or hinge joint raises ValueError.
    """
    if model is None:
        return _pusher_scene()
    if isinstance(model, Model):
        return model
    if isinstance(model, (str, os.PathLike)):
        return Model.from_file(os.fspath(model))
    raise TypeError(f"model must be None, a simloop.Model or a path to an MJCF file, got {_describe(model)}")


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
        steps=_check_int("steps", steps, 1, _I64_MAX),
        timestep=_check_timestep(timestep),
        perturb=_check_bool("perturb", perturb),
        smoke=_check_bool("smoke", smoke),
        record_every=_check_int("record_every", record_every, 1, _I64_MAX),
        audit_energy=_check_bool("audit_energy", audit_energy),
        rng=_check_rng(rng),
    )


def run(seed: int = 0, steps: int = 2000, timestep: float = 0.002, perturb: bool = True, smoke: bool = False,
        model: ModelLike = None, record_every: int = 1, audit_energy: bool = False,
        rng: str = "mt19937_64") -> RunResult:
    """Runs the chapter's loop once and returns what happened.

    seed: seeds the shove (0 to 2**64-1), and nothing else.
    steps: steps to run (ignored with smoke=True, which runs a fixed 300).
    timestep: sim seconds per mj_step, written into a copy of the model.
    perturb: False skips the shove (the baseline run).
    model: None (the chapter's scene), a simloop.Model, or an MJCF path.
    record_every: keep every K-th step in the trajectory (the final state is
        always kept).
    audit_energy: account for every joule: the trajectory gains the
        ENERGY_COLUMN_NAMES columns and .energy holds the totals.
    rng: the generator that draws the shove from the seed: "mt19937_64"
        (std::mt19937_64, the default) or "numpy" (the chapter's
        np.random.default_rng(seed), PCG64, reproduced in C++ bit for bit;
        seed 0 shoves +9.82 N).

    The result has .metrics (the dict metrics.json holds), .trajectory (a
    read-only (rows, 22) float64 view, no copy) and .columns / .column(name),
    .shove, .warnings, .summary(), and .write(out) for metrics.json and
    trajectory.csv, byte-identical to `sim_loop` with the same flags.
    """
    config = _config(seed, steps, timestep, perturb, smoke, record_every, audit_energy, rng)
    return _core.run(load_model(model), config)


def draw_shove(seed: int = 0, steps: int = 2000, rng: str = "mt19937_64") -> "_core.Shove":
    """The shove a run of `steps` steps draws from `seed`, without running it.

    The same Shove as run(seed=seed, steps=steps, rng=rng).shove: newtons,
    sign, force_y, start_step (steps // 2) and steps (50).
    """
    return _core.draw_shove(_check_int("seed", seed, 0, _U64_MAX), _check_int("steps", steps, 1, _I64_MAX),
                            _check_rng(rng))


def _sequence(name: str, values: object) -> list:
    if isinstance(values, (str, bytes)) or not isinstance(values, Iterable):
        raise TypeError(f"{name} must be a sequence, got {_describe(values)}")
    return list(values)


def run_batch(seeds: Iterable[int] = (0,), timesteps: Iterable[float] = (0.002,), *, steps: int = 2000,
              perturb: bool = True, smoke: bool = False, model: ModelLike = None, record_every: int = 1,
              audit_energy: bool = False, threads: Optional[int] = None, rng: str = "mt19937_64") -> List[RunResult]:
    """Runs every (seed, timestep) pair over one compiled model, in parallel.

    Results come in the order of itertools.product(seeds, timesteps), and each
    is bitwise identical to run() with the same arguments, whatever `threads`
    is (None: one worker per core). Each worker steps its own MuJoCo data;
    the model is shared. Every argument is checked before any run starts.
    """
    seed_list = [_check_int("seeds[%d]" % i, s, 0, _U64_MAX) for i, s in enumerate(_sequence("seeds", seeds))]
    timestep_list = [_check_timestep(t, "timesteps[%d]" % i) for i, t in enumerate(_sequence("timesteps", timesteps))]
    workers = 0 if threads is None else _check_int("threads", threads, 1, 4096)
    configs = [_config(s, steps, t, perturb, smoke, record_every, audit_energy, rng)
               for s in seed_list for t in timestep_list]
    return _core.run_batch(load_model(model), configs, workers)


class Sim:
    """The loop's rhythm, one call at a time: write ctrl, write a force, step, look.

    Reads (box_position, contacts, ...) return copies: nothing you hold
    changes under you when the simulation steps on.

    IMPORTANT: like MuJoCo's xfrc_applied, a force set with apply_force()
    PERSISTS. MuJoCo never clears it: it pushes on every following step until
    you call clear_force(). ctrl persists the same way. Forgetting this is the
    chapter's classic bug (exercise 2).
    """

    def __init__(self, model: ModelLike = None, timestep: Optional[float] = None) -> None:
        self._sim = _core.Sim(load_model(model))
        if timestep is not None:
            self.timestep = timestep

    @property
    def timestep(self) -> float:
        """Sim seconds per step (this Sim's own copy of the model)."""
        return self._sim.timestep

    @timestep.setter
    def timestep(self, value: float) -> None:
        self._sim.set_timestep(_check_timestep(value))

    @property
    def ctrl(self) -> float:
        """The motor command, ctrl[0]; MuJoCo clamps it to the ctrlrange [-1, 1]."""
        return self._sim.ctrl

    @ctrl.setter
    def ctrl(self, value: float) -> None:
        number = _check_real("ctrl", value)
        if not math.isfinite(number):
            raise ValueError(f"ctrl must be finite, got {number!r}")
        self._sim.set_ctrl(number)

    def step(self, n: int = 1, ctrl: Optional[float] = None) -> None:
        """Advances n steps; with ctrl given, writes it first (it then persists)."""
        count = _check_int("n", n, 1, _I64_MAX)
        if ctrl is not None:
            self.ctrl = ctrl
        self._sim.step(count)

    def apply_force(self, force: Sequence[float]) -> None:
        """Pushes on the box with (fx, fy, fz) newtons, world frame, from now on.

        It PERSISTS until clear_force(): MuJoCo does not reset it after a step.
        """
        values = _sequence("force", force)
        if len(values) != 3:
            raise ValueError(f"force must have 3 components (fx, fy, fz), got {len(values)}")
        checked = [_check_real("force[%d]" % i, v) for i, v in enumerate(values)]
        for i, v in enumerate(checked):
            if not math.isfinite(v):
                raise ValueError(f"force[{i}] must be finite, got {v!r}")
        self._sim.apply_force(checked)

    def clear_force(self) -> None:
        """Stops pushing: writes zero into the box's xfrc_applied."""
        self._sim.clear_force()

    def reset(self) -> None:
        """Back to t = 0: state, ctrl, force and warnings cleared (timestep kept)."""
        self._sim.reset()

    @property
    def applied_force(self):
        """The force now written on the box (a copy), N."""
        return self._sim.applied_force

    @property
    def time(self) -> float:
        return self._sim.time

    @property
    def steps_taken(self) -> int:
        return self._sim.steps_taken

    @property
    def box_position(self):
        """The box's position now (x, y, z), m: a copy."""
        return self._sim.box_position

    @property
    def box_quaternion(self):
        """The box's orientation now, (w, x, y, z) as MuJoCo stores it: a copy."""
        return self._sim.box_quaternion

    @property
    def box_velocity(self):
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
    def contacts(self) -> list:
        """The contacts of MuJoCo's last collision pass (geom1, geom2, dist, pos)."""
        return self._sim.contacts

    @property
    def warnings(self) -> list:
        """Warnings MuJoCo raised since construction or reset."""
        return self._sim.warnings

    def __repr__(self) -> str:
        return f"<simloop.Sim t={self.time!r} steps_taken={self.steps_taken} timestep={self.timestep!r}>"


def sweep(timesteps: Optional[Iterable[float]] = None, duration: float = 4.0, threads: Optional[int] = None,
          model: ModelLike = None) -> "_core.SweepResult":
    """The baseline (no shove) at many timesteps over the same span of sim time.

    timesteps: None for the default: 25 round timesteps (1, 2, 3, 4, 5, 6 and
        8 per decade) from 0.0005 s to 1 s, from the stable range through the
        edge to the box sinking into the floor.
    duration: sim seconds each run covers (round(duration / timestep) steps).

    Runs in parallel over one compiled model with the energy audit on. The
    result's .points hold, per timestep, peak box z, largest |y|, the final
    positions, warnings, the audit's figures and whether it is stable; .edge
    is the largest timestep below which all are stable; .summary() the table,
    .write(out) sweep.csv. The criterion: the box rises at most 5 mm above
    rest, ends at most 1 mm below rest, and MuJoCo raised no warning.
    """
    if timesteps is None:
        values = _core.default_sweep_timesteps()
    else:
        values = [_check_timestep(t, "timesteps[%d]" % i) for i, t in enumerate(_sequence("timesteps", timesteps))]
        if not values:
            raise ValueError("timesteps must not be empty")
    span = _check_timestep(duration, "duration")
    workers = 0 if threads is None else _check_int("threads", threads, 1, 4096)
    return _core.sweep(load_model(model), values, span, workers)
