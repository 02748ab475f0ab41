"""What simloop's Gymnasium environments share (gym.py): the episodes, the
spaces, the checks of actions and options, the reward and terminate hooks,
why an episode ended, and the pictures."""

from __future__ import annotations

import inspect
from typing import Any, Callable, Dict, List, Mapping, NamedTuple, Optional, Sequence, Tuple, Union

import numpy as np
from gymnasium import spaces

from . import _core
from ._checks import ModelLike, _check_int, _check_keys, _check_seed, _describe
from .physics import Physics, StartPhysics
from .render import EpisodePictures
from .scenario import RESET_KEYS, ScenarioLike, _scenario_and_scene, reset_toml, scenario_config

# (reward(obs, action, next_obs) or reward(obs, action, next_obs, physics);
# terminate(next_obs) or terminate(next_obs, physics): see _takes_physics)
Reward = Callable[..., Any]
Observe = Callable[[np.ndarray], Any]
Terminate = Union[Callable[..., Any], Sequence[Tuple[str, str, float]]]
OnReset = Callable[[np.random.Generator, StartPhysics], Any]
_COMPARISONS = {"<": np.less, "<=": np.less_equal, ">": np.greater, ">=": np.greater_equal}


def batched(function: Callable[..., Any]) -> Callable[..., Any]:
    """Marks a reward or terminate function as taking a batch: arrays with a
    leading axis of episodes (obs and next_obs (n, width), actions (n, nu))
    and returning n values; one that reads the physics gets a tuple of the n
    envs' Physics last, in the rows' order. The vector env then calls it
    once a step rather than once per env (the single env calls it with n = 1)."""
    setattr(function, "simloop_batched", True)  # noqa: B010 (mypy: a Callable has no such attribute)
    return function


def _is_batched(function: object) -> bool:
    return bool(getattr(function, "simloop_batched", False))


def _takes_physics(function: Callable[..., Any], plain: int) -> bool:
    """Whether a hook asks for the env's physics: it has one required
    positional parameter more than its plain ones (`plain`: reward's obs,
    action, next_obs; terminate's next_obs). Looked at once, at
    construction: a hook that does not ask costs the step nothing, and a
    plain hook (or one with defaults, or *args) is called as before."""
    try:
        parameters = inspect.signature(function).parameters.values()
    except (TypeError, ValueError):  # (a builtin without a signature: a plain hook)
        return False
    kinds = (inspect.Parameter.POSITIONAL_ONLY, inspect.Parameter.POSITIONAL_OR_KEYWORD)
    required = [p for p in parameters if p.kind in kinds and p.default is inspect.Parameter.empty]
    return len(required) == plain + 1


# Episodes that end this way are terminated, not truncated (episode.hpp).
_TERMINATING = ("simloop_DIVERGED", "mjWARN_BADQPOS", "mjWARN_BADQVEL", "mjWARN_BADQACC")
# The ends (_ended_by) that are terminations; the others are truncations.
_TERMINAL_ENDS = ("warning", "termination")
# An observation's bounds: finite, so Gymnasium's checkers find nothing to
# remark on, and float32's, so a float32 observation (DtypeObservation, a
# torch policy's) is in its space too. No state gets near them: MuJoCo resets
# a state past 1e10 (mjWARN_BADQPOS, ...), which terminates the episode.
_FINITE = float(np.finfo(np.float32).max)


class TaskInfo(NamedTuple):
    """A task's own info keys (gym_tasks: Gymnasium's), made for a batch of rows at once: step(before, actions,
    after) and reset(rows) return {key: n values (or n rows of values)}; an env's info holds its row's."""

    step: Callable[[np.ndarray, np.ndarray, np.ndarray], Dict[str, np.ndarray]]
    reset: Callable[[np.ndarray], Dict[str, np.ndarray]]


class Rendering(NamedTuple):
    """An env's render arguments: render_mode (None, "rgb_array" or
    "depth_array"), the pictures' width and height, and the view (a dict of
    camera, track, distance, azimuth, elevation; see simloop.Renderer)."""

    mode: Optional[str]
    width: int
    height: int
    view: Optional[Mapping[str, Any]]


class _Setup:
    """What the single and the vector environment share: the episodes, the
    spaces, the checks of actions."""

    def __init__(
        self,
        scenario: ScenarioLike,
        count: int,
        control_every: int,
        reward: Optional[Reward],
        terminate: Optional[Terminate],
        rng: str,
        timestep: Optional[float],
        steps: Optional[int],
        perturb: bool,
        model: ModelLike,
        render: "Rendering",
        observe: Optional[Observe] = None,
        data_at_step: bool = False,
        on_reset: Optional[OnReset] = None,
    ) -> None:
        scenario, scene = _scenario_and_scene(scenario, model)
        if reward is not None and not callable(reward):
            raise TypeError(
                f"reward must be None or a callable reward(obs, action, next_obs) -> float, got {_describe(reward)}"
            )
        if on_reset is not None and not callable(on_reset):
            raise TypeError(f"on_reset must be None or a callable on_reset(rng, physics), got {_describe(on_reset)}")
        self.on_reset = on_reset
        # (checked here, at construction: the C++ episodes check it only as they step)
        self.control_every = _check_int("control_every", control_every, 1, _core.MAX_STEPS)
        config = scenario_config(0, rng, timestep, steps, perturb, 1)
        self.scenario = scenario
        self.reward = reward
        self.reward_reads = reward is not None and _takes_physics(reward, 3)
        terminate_reads = callable(terminate) and _takes_physics(terminate, 1)
        reads = self.reward_reads or terminate_reads
        self.episodes = _core.Episodes(scene, scenario._core, config, count, reads)
        if data_at_step:
            self.episodes.read_data_at_step(True)
        # Each env's state by name, for the hooks that ask for it (simloop.physics).
        self.physics = tuple(Physics(self.episodes, i) for i in range(count)) if reads else ()
        # (the env's fps: its decisions per simulated second, as MujocoEnv's)
        self.render_fps = 1.0 / (self.episodes.timestep * self.control_every)
        pictures = EpisodePictures(scene, render.mode, render.width, render.height, render.view)
        self.pictures = None if render.mode is None else pictures
        self.nu = self.episodes.nu
        self.names: Tuple[str, ...] = self.episodes.column_names[2:]
        low, high = self.episodes.ctrl_range
        self.action_space = spaces.Box(low, high, (self.nu,), np.float64)
        self.observe = observe
        self.observation_names = self.names if observe is None else self._observe_names(observe)
        self.observation_space = spaces.Box(-_FINITE, _FINITE, (len(self.observation_names),), np.float64)
        self.terminate: Optional[Callable[..., Any]] = None
        self.conditions: List[Tuple[int, Any, float]] = []
        self.terminate_reads = terminate_reads
        if callable(terminate):
            self.terminate = terminate
        elif terminate is not None:
            self.conditions = [self._condition(c) for c in _sequence_of("terminate", terminate)]
        self.terminates = self.terminate is not None or bool(self.conditions)  # (a hook or a condition)
        self.task_info: Optional[TaskInfo] = None  # (set by gym_tasks after construction)
        self._step_keys: Tuple[str, ...] = ()  # (the task's keys in the last step's infos)

    def _observe_names(self, observe: Observe) -> Tuple[str, ...]:
        """The names of what observe makes of a row, learnt by calling it once on a row of zeros: its `names`
        attribute if it has one, else observation0, observation1, ..."""
        if not callable(observe):
            raise TypeError(
                f"observe must be None or a callable observe(rows) -> observations, got {_describe(observe)}"
            )
        width = self.observed(np.zeros((1, len(self.names)))).shape[1]
        names = tuple(getattr(observe, "names", None) or (f"observation{i}" for i in range(width)))
        if len(names) != width:
            raise ValueError(f"observe makes {width} values of a row but names {len(names)}")
        return names

    def observed(self, rows: np.ndarray) -> np.ndarray:
        """What the env hands out for these recorded rows (n, width), a new array: the rows themselves, or
        observe's (n, m) observations of them (one call for the batch)."""
        if self.observe is None:
            return rows.copy()
        out = np.array(self.observe(rows), dtype=np.float64)  # (a copy: observe may return a view of the rows)
        if out.ndim != 2 or out.shape[0] != len(rows):
            raise ValueError(f"observe must return ({len(rows)}, m) values for {len(rows)} rows, got shape {out.shape}")
        return out

    def _condition(self, condition: object) -> Tuple[int, Any, float]:
        """(column, op, value): the episode ends when the observation's column compares so."""
        if not (
            isinstance(condition, (tuple, list))
            and len(condition) == 3
            and isinstance(condition[0], str)
            and condition[1] in _COMPARISONS
        ):
            raise TypeError(
                f"each terminate condition must be (column, op, value) with op one of "
                f"{', '.join(_COMPARISONS)}, got {_describe(condition)}"
            )
        column, op, value = condition
        if column not in self.names:
            raise ValueError(f"terminate: no observed column named {column!r}; columns: {', '.join(self.names)}")
        threshold = float(value)
        if not np.isfinite(threshold):
            raise ValueError(f"terminate: {column} {op} {value!r}: the value must be finite")
        return self.names.index(column), _COMPARISONS[op], threshold

    def _physics_of(self, envs: Optional[np.ndarray]) -> Tuple[Physics, ...]:
        """The physics of the envs whose rows a batch holds (envs: their indices; None: every env)."""
        return self.physics if envs is None else tuple(self.physics[i] for i in envs)

    def terminations(self, after: np.ndarray, envs: Optional[np.ndarray] = None) -> np.ndarray:
        """Which of these next observations end their episode by the terminate
        hook; envs: the indices of the envs they are (None: every env)."""
        hit = np.zeros(len(after), dtype=bool)
        for index, op, value in self.conditions:
            hit |= op(after[:, index], value)
        terminate = self.terminate
        if terminate is not None:
            extra = (self._physics_of(envs),) if self.terminate_reads else ()
            if _is_batched(terminate):
                flags = _batch_of("terminate", terminate(after, *extra), len(after))
                if flags.dtype != np.bool_:  # as a plain hook's: a bool, not a number that might mean one
                    raise TypeError(f"a batched terminate must return bools, got dtype {flags.dtype}")
                hit |= flags
            elif extra:
                hit |= np.array([_flag_from(terminate(o, p)) for o, p in zip(after, extra[0])], dtype=bool)
            else:
                hit |= np.array([_flag_from(terminate(o)) for o in after], dtype=bool)
        return hit

    def actions(self, action: object, shape: Tuple[int, ...]) -> np.ndarray:
        """The action as the episodes take it: float64 numbers of this shape
        (their finiteness is the episodes' check)."""
        if type(action) is np.ndarray and action.dtype == np.float64 and action.shape == shape:
            return action  # what a policy usually hands over: nothing to convert
        try:
            values = np.asarray(action, dtype=np.float64)
        except (TypeError, ValueError):
            raise TypeError(f"action must be {shape} numbers, got {_describe(action)}") from None
        if shape == (1,) and values.ndim == 0:
            values = values.reshape(1)
        if values.shape != shape:
            raise ValueError(f"action must have shape {shape}, got {values.shape}")
        return values

    def rewards(
        self, before: np.ndarray, actions: np.ndarray, after: np.ndarray, envs: Optional[np.ndarray] = None
    ) -> np.ndarray:
        """The rewards of a batch of steps: before, after (n, width), actions
        (n, nu); envs: the indices of the envs they are (None: every env)."""
        reward = self.reward
        if reward is None:
            return np.zeros(len(after))
        extra = (self._physics_of(envs),) if self.reward_reads else ()
        if _is_batched(reward):  # (a copy: the function may return a view of its arguments)
            return np.array(_batch_of("reward", reward(before, actions, after, *extra), len(after)), dtype=np.float64)
        if extra:
            rows = zip(before, actions, after, extra[0])
            return np.array([_number_from(reward(b, a, o, p)) for b, a, o, p in rows])
        return np.array([_number_from(reward(b, a, o)) for b, a, o in zip(before, actions, after)])

    def reward_of_one(self, before: np.ndarray, action: np.ndarray, after: np.ndarray) -> float:
        """One step's reward (the single env's): before and after (1, width), action (nu,)."""
        reward = self.reward
        if reward is None:
            return 0.0
        extra = (self.physics,) if self.reward_reads else ()
        if _is_batched(reward):
            return float(_batch_of("reward", reward(before, action[None], after, *extra), 1)[0])
        return _number_from(reward(before[0], action, after[0], *(p[0] for p in extra)))

    def reset_envs(
        self, envs: Sequence[int], seeds: Sequence[int], start: Optional[str], done: Callable[[int, np.ndarray], None]
    ) -> None:
        """Starts env envs[k] from episode seed seeds[k] (start: the reset options' [reset] table, or None), calling
        done(k, its first observation) as each is in place. With an on_reset hook every start is staged and shaped
        by the hook before any is put in place (Episodes.stage_reset, then commit_reset: the hook runs between
        the two calls, with no lock of the episodes held), so a hook that raises leaves every env as it was."""
        episodes, hook = self.episodes, self.on_reset
        if hook is None:
            for k, (i, seed) in enumerate(zip(envs, seeds)):
                done(k, episodes.reset(i, seed, start))
            return
        for i, seed in zip(envs, seeds):
            episodes.stage_reset(i, seed, start)
            hook(start_rng(seed), StartPhysics(episodes, i))
        for k, i in enumerate(envs):
            done(k, episodes.commit_reset(i))

    def start_info(self, i: int, seed: int, row: np.ndarray) -> Dict[str, Any]:
        """Episode i's info at its reset: step, time, its seed (a numpy uint64), what its start drew (its
        keyframe's name; each scene parameter and each goal coordinate by its batch-table column:
        friction_<geom>, mass_<body>, goal_<body>_x, ...) and a task's own keys for its first row (1, width)."""
        info = self.info(i)
        info["seed"] = np.uint64(seed)
        info.update(self.episodes.drawn(i))
        if self.task_info is not None:
            info.update({key: values[0] for key, values in self.task_info.reset(row).items()})
        return info

    def info(self, i: int, ended_by: Optional[str] = None, warned: bool = False) -> Dict[str, Any]:
        """Episode i's info; `warned`: it ended on a warning, which the info names."""
        out: Dict[str, Any] = {"step": self.episodes.steps_taken(i), "time": self.episodes.time(i)}
        if warned:
            out["warnings"] = [w.name for w in self.episodes.warnings(i) if w.name in _TERMINATING]
        if ended_by is not None:
            out["ended_by"] = ended_by
        return out

    def step_info(self, info: Dict[str, Any], before: np.ndarray, action: np.ndarray, after: np.ndarray) -> Any:
        """The single env's step info, with the task's keys for its step (before, after (1, width), action (nu,))."""
        if self.task_info is not None:
            info.update({key: values[0] for key, values in self.task_info.step(before, action[None], after).items()})
        return info

    def add_step_infos(
        self, infos: Dict[str, Any], before: np.ndarray, actions: np.ndarray, after: np.ndarray, stepped: np.ndarray
    ) -> None:
        """The task's step keys in a vector env's infos, for the envs that stepped (mask `stepped`), in Gymnasium's
        layout (zero where masked out), kept beside what a reset already put there; one call for the batch."""
        if self.task_info is None or not stepped.any():
            return
        made = self.task_info.step(before, actions, after)
        self._step_keys = tuple(made)
        everyone = bool(stepped.all())
        for key, values in made.items():
            if everyone and key not in infos:  # (every step of a vector env without an ended episode)
                infos[key], infos["_" + key] = values, stepped.copy()
                continue
            into = infos.setdefault(key, np.zeros_like(values))
            into[stepped] = values[stepped]
            infos["_" + key] = infos.get("_" + key, np.zeros(len(stepped), dtype=bool)) | stepped

    def take_step_info(self, infos: Dict[str, Any], i: int) -> Dict[str, Any]:
        """Env i's task step keys out of a vector env's infos (its final_info's, as it starts again at once)."""
        out: Dict[str, Any] = {}
        for key in self._step_keys:
            mask = infos["_" + key]
            if mask[i]:
                value = infos[key][i]
                out[key] = value.copy() if isinstance(value, np.ndarray) else value
                infos[key][i], mask[i] = 0, False
        return out


def _sequence_of(name: str, value: object) -> List[Any]:
    if isinstance(value, (str, bytes)) or not isinstance(value, Sequence):
        raise TypeError(
            f"{name} must be a callable or a list of (column, op, value) conditions, got {_describe(value)}"
        )
    return list(value)


def _number_from(value: object) -> float:
    """A reward hook's value, or a TypeError saying what it returned."""
    try:
        return float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise TypeError(f"reward must return a number, got {_describe(value)}") from None


def _flag_from(value: object) -> bool:
    """A terminate hook's value, or a TypeError saying what it returned
    (None, say: a function that forgot to return)."""
    if not isinstance(value, (bool, np.bool_)):
        raise TypeError(f"terminate must return a bool, got {_describe(value)}")
    return bool(value)


def _batch_of(name: str, values: object, n: int) -> np.ndarray:
    """A batched function's result: n values (not copied)."""
    out = np.asarray(values)
    if out.shape != (n,):
        raise ValueError(f"a batched {name} must return {n} values (one per episode), got shape {out.shape}")
    return out


def _ended_by(
    terminated: bool, truncated: bool, decisions: int, max_episode_steps: Optional[int], hooked: bool = False
) -> Optional[str]:
    """Why an episode ended on this step, or None: a warning first, then the
    terminate hook, then the scenario's length, then the caller's step limit."""
    if terminated:
        return "warning"
    if hooked:
        return "termination"
    if truncated:
        return "length"
    if max_episode_steps is not None and decisions >= max_episode_steps:
        return "max_episode_steps"
    return None


def _check_options(options: object, known: Sequence[str]) -> Dict[str, Any]:
    """reset's options: None or a dict of known keys (never silently ignored)."""
    if options is None:
        return {}
    if not isinstance(options, dict):
        raise TypeError(f"options must be a dict or None, got {_describe(options)}")
    _check_keys("options", options, known)
    return options


def _start(options: Dict[str, Any]) -> Optional[str]:
    """The episode's start from reset's options, as a [reset] table (None:
    the scenario's own). Each key it names replaces the scenario's [reset]
    key for that episode (params: the whole list, [] for none); the keys it
    leaves out stay the scenario's (the C++ reset_over)."""
    reset = {k: v for k, v in options.items() if k in RESET_KEYS}
    return reset_toml(reset) if reset else None


def start_rng(seed: int) -> np.random.Generator:
    """An on_reset hook's generator for the episode of this seed: numpy's PCG64 over the first child of
    SeedSequence(seed), a stream apart from the one the scenario's "numpy" generator draws from that seed."""
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence(seed).spawn(1)[0]))


def _check_max_episode_steps(value: object) -> Optional[int]:
    return None if value is None else _check_int("max_episode_steps", value, 1, _core.MAX_STEPS)


def _episode_seed(np_random: np.random.Generator, seed: Optional[int]) -> int:
    """The scenario's seed for an episode: reset's, else drawn from np_random."""
    if seed is not None:
        return _check_seed("seed", seed)
    return int(np_random.integers(0, 2**64, dtype=np.uint64))
