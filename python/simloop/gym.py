"""Gymnasium environments over any scenario (needs the `gym` extra: gymnasium).

    >>> import gymnasium, simloop
    >>> env = gymnasium.make("simloop/PushT-v0")
    >>> obs, info = env.reset(seed=0)
    >>> obs, reward, terminated, truncated, info = env.step(env.action_space.sample())

An episode is one run of the scenario driven by actions (the C++ loop's
Episodes, include/simloop/episode.hpp):

- reset(seed=s) seeds the scenario's generator with s: the disturbances are
  drawn from it, as run_scenario(seed=s) draws them. It also seeds the
  environment's np_random; a reset without a seed draws the episode's seed
  from np_random, so a seeded sequence of episodes repeats.
- step(action) writes the action into ctrl (every actuator, nu values) and
  takes `control_every` physics steps (the frame skip), the disturbances
  acting as scheduled; the scenario's own controls give way to the actions.
  MuJoCo clamps ctrl to each actuator's ctrlrange.
- action_space: Box(low, high, (nu,), float64) from the actuators' ctrlrange;
  an actuator without one (not ctrllimited) is -inf..inf.
- observation_space: Box(-m, m, (n,), float64), m float32's largest value,
  over the scenario's recorded quantities: the trajectory's columns after
  "step" and "time" (env.observation_names), read as the state entering the
  next step (see simloop.Observation). step and time are in info. A
  scenario without a [record] table records every body on a free joint and
  every actuator, no joint angles: list the joints a policy needs.
- reward: a scenario has none, so reward(obs, action, next_obs) -> float is
  an argument (default: 0.0 every step). A hook that takes one more
  parameter, reward(obs, action, next_obs, physics) or
  terminate(next_obs, physics), is handed the env's MuJoCo state by name,
  read-only (simloop.physics: physics.named.data.site_xpos["tip"]).
- truncated: the episode reached the scenario's length (its last step may
  take fewer than control_every physics steps), or max_episode_steps env
  steps if given. terminated: the simulation diverged (simloop_DIVERGED) or
  MuJoCo found a bad position, velocity or acceleration and reset its state
  (mjWARN_BADQPOS, BADQVEL, BADQACC); the episode stops at that physics step
  and info["warnings"] names them.
- reset(seed, options): options qpos, qvel (the scene's nq / nv values),
  qpos_noise, qvel_noise (a width, a list of one per coordinate, or
  {joint: width}; drawn from the episode's seed after its disturbances, a
  uniform noise's half-width, or with qpos_noise_distribution /
  qvel_noise_distribution "normal" its standard deviation), keyframe (a
  keyframe of the scene by name, the start the other keys apply over),
  goals ([{"body": a mocap body, "pos": [x, y, z] or "uniform": [[low
  x, y, z], [high x, y, z]]}]: its position, drawn per episode) and params (scene parameters for
  this episode: [{"kind": "friction" | "mass" | "damping" | "gravity",
  "name": ..., "value": v or "uniform": [low, high]}]): over the
  scenario's [reset] table, for this episode: each key given replaces the
  scenario's (params: the whole list, [] for none), the others stay.
  Unknown keys, wrong sizes and names are errors; the env stays usable.
- render_mode "rgb_array" or "depth_array": render() draws the episode's
  state offscreen (simloop.Renderer), width x height pixels, from `view`
  (camera, track, distance, azimuth, elevation); metadata["render_fps"] is
  the decisions per simulated second.
- on_reset(rng, physics): called at every reset (the vector env's
  autoresets too) after the scenario's [reset] and the options are applied:
  rng a numpy Generator seeded from the episode's seed (the same seed, the
  same draws), physics the start by name (simloop.physics.StartPhysics:
  qpos, qvel, act, ctrl, mocap_pos, mocap_quat writable, the rest
  read-only). The start is then derived again (quaternions made unit,
  mj_forward) and the first observation observes what the hook wrote. A
  hook that raises leaves the env as it was, its generator too.
- info: "step" (physics steps since reset) and "time" (s) always; from
  reset "seed" (the episode's, a numpy uint64) and what its start drew:
  "keyframe" (its name) if any, each scene parameter by its batch-table
  column (friction_<geom>, mass_<body>, gravity, ...) and each goal's
  goal_<body>_x, _y, _z; "ended_by" on the step that ends an episode:
  "warning", "termination", "length" or "max_episode_steps".

ScenarioVectorEnv steps N such episodes over one compiled model, one MuJoCo
data each, on C++ threads with the GIL released. Its infos are Gymnasium's
vector layout (an array per key, and a "_key" mask of the envs that have it),
the same as SyncVectorEnv over N ScenarioEnvs gives; its autoreset is any of
Gymnasium's three modes (autoreset_mode=, next-step by default), and
reset(options={"reset_mask": mask}) resets the masked envs only. Registered ids (at `import simloop`, once gymnasium is
imported): simloop/Chapter-v0 (the chapter's run, a decision every 50 steps:
10 Hz over 500 Hz physics), simloop/PushT-v0 (the PushT scenario shipped in
simloop/scenes/, a decision every 10 steps) and simloop/Scenario-v0
(scenario=... required); each also as gymnasium.make_vec(..., num_envs=N)
through the vector class.
"""

from __future__ import annotations

import os
from typing import Any, Dict, List, Optional, Tuple, cast

import gymnasium
import numpy as np

from . import _gym_registry
from ._checks import ModelLike
from ._gym_setup import (
    _TERMINAL_ENDS,
    Observe,
    OnReset,
    Rendering,
    Reward,
    Terminate,
    _check_max_episode_steps,
    _check_options,
    _ended_by,
    _episode_seed,
    _Setup,
    _start,
    batched,
)
from .gym_vector import ScenarioVectorEnv
from .render import RENDER_MODES
from .scenario import RESET_KEYS, Scenario, ScenarioLike

__all__ = [
    "PUSHT_SCENARIO",
    "ScenarioEnv",
    "ScenarioVectorEnv",
    "batched",
    "chapter_env",
    "chapter_vector_env",
    "pusht_env",
    "pusht_vector_env",
    "register_envs",
]

_CHAPTER_VIEW = {"track": "box", "distance": 1.5}
PUSHT_SCENARIO = os.path.join(os.path.dirname(os.path.abspath(__file__)), "scenes", "pusht.toml")


class ScenarioEnv(gymnasium.Env):
    """A Gymnasium environment over a scenario (a simloop.Scenario or a
    scenario file's path); see the module's documentation.

    control_every: physics steps per env.step (the frame skip). reward:
    reward(obs, action, next_obs) -> float, default 0.0 (or a @batched one).
    terminate: ends an episode (terminated, info["ended_by"] ==
    "termination") when its next observation meets it: a callable
    terminate(next_obs) -> bool (or a @batched one), or conditions on the
    observed columns, any of which ends it: [("tblock_x", ">", 0.35)] (ops
    <, <=, >, >=). Either hook may also read the env's MuJoCo state: a
    reward(obs, action, next_obs, physics) or terminate(next_obs, physics)
    gets a simloop.physics.Physics (physics.named.data.site_xpos["tip"],
    read-only, the state next_obs observes; a @batched one gets a tuple of
    them, one per row). The extra required parameter is the opt-in, seen
    once at construction: a hook without it is called as before and the
    step does no more for it; with it, each decision takes a whole forward
    pass, so every array is current (the observations' bits are the same).
    on_reset: on_reset(rng, physics), run at every reset once the
    scenario's [reset] and the options are applied, to shape the start
    (see the module's documentation). max_episode_steps: truncate after
    this many env.step calls (None: the scenario's length only). rng, timestep, steps, perturb,
    model: as for run_scenario (steps is the episode's length in physics
    steps). render_mode: None, "rgb_array" (render() gives the state as a
    (height, width, 3) uint8 picture) or "depth_array" ((height, width)
    float32 metres), drawn offscreen by simloop.Renderer from `view` (a dict:
    camera, track, distance, azimuth, elevation; None: the scene's default
    free camera); width and height in pixels. observe: None (the
    observation is the recorded row) or observe(rows) -> (n, m) array, called
    once for a batch of rows (n, width): the observation made of the rows
    (Gymnasium's tasks leave out x, clip velocities); reward and terminate
    still see the rows. Its `names` attribute, if any, gives
    observation_names. data_at_step: the [record] data columns are read
    where Gymnasium's MujocoEnv reads mjData, as the last physics step (or
    the reset) left it, cfrc_ext after mj_rnePostConstraint
    (Recorder::read_data_at_step), not for the observed state.
    """

    metadata = {"render_modes": list(RENDER_MODES)}

    def __init__(
        self,
        scenario: ScenarioLike,
        *,
        control_every: int = 1,
        reward: Optional[Reward] = None,
        terminate: Optional[Terminate] = None,
        observe: Optional[Observe] = None,
        data_at_step: bool = False,
        on_reset: Optional[OnReset] = None,
        max_episode_steps: Optional[int] = None,
        rng: str = "mt19937_64",
        timestep: Optional[float] = None,
        steps: Optional[int] = None,
        perturb: bool = True,
        model: ModelLike = None,
        render_mode: Optional[str] = None,
        width: int = 480,
        height: int = 480,
        view: Optional[Dict[str, Any]] = None,
    ) -> None:
        self._setup = _Setup(
            scenario,
            1,
            control_every,
            reward,
            terminate,
            rng,
            timestep,
            steps,
            perturb,
            model,
            Rendering(render_mode, width, height, view),
            observe,
            data_at_step,
            on_reset,
        )
        self.render_mode = render_mode
        self.metadata = {**type(self).metadata, "render_fps": self._setup.render_fps}
        self.action_space = self._setup.action_space
        self.observation_space = self._setup.observation_space
        self.observation_names = self._setup.observation_names
        self.control_every = self._setup.control_every
        self.max_episode_steps = _check_max_episode_steps(max_episode_steps)
        self._action_shape = (self._setup.nu,)
        self._obs: Optional[np.ndarray] = None  # (1, n): the episode's observation, a batch of one
        self._decisions = 0
        self._ended = True  # no episode yet

    def reset(
        self, *, seed: Optional[int] = None, options: Optional[Dict[str, Any]] = None
    ) -> Tuple[np.ndarray, Dict[str, Any]]:
        start = _start(_check_options(options, RESET_KEYS))
        # The generator as it was, restored if the reset fails (its state: a deepcopy would cost a reset's worth).
        rng, rng_seed = self._np_random, self._np_random_seed
        state = rng.bit_generator.state if rng is not None else {}
        super().reset(seed=seed)
        episode_seed = _episode_seed(self.np_random, seed)
        rows: List[np.ndarray] = []
        try:
            self._setup.reset_envs((0,), (episode_seed,), start, lambda k, row: rows.append(row))
        except BaseException:  # a start the scene refuses, or on_reset raised: the env is as it was, its generator too
            self._np_random, self._np_random_seed = rng, rng_seed
            if rng is not None:
                rng.bit_generator.state = state
            raise
        self._obs = rows[0][None]
        self._decisions, self._ended = 0, False
        return self._setup.observed(self._obs)[0], self._setup.start_info(0, episode_seed, self._obs)

    def step(self, action: object) -> Tuple[np.ndarray, float, bool, bool, Dict[str, Any]]:
        if self._ended:
            raise ValueError(
                "reset() the environment before step()"
                if self._obs is None
                else "the episode has ended: reset() it first"
            )
        setup = self._setup
        action = setup.actions(action, self._action_shape)
        obs, terminated, truncated = setup.episodes.step(action, self.control_every)
        before = cast(np.ndarray, self._obs)  # (set once an episode has started)
        self._obs = obs  # stepped: a hook that raises below leaves the env where the episode is
        self._decisions += 1
        warned, at_length = bool(terminated[0]), bool(truncated[0])
        self._ended = warned or at_length
        reward = setup.reward_of_one(before, action, obs)
        hooked = setup.terminates and not warned and bool(setup.terminations(obs)[0])
        ended_by = _ended_by(warned, at_length, self._decisions, self.max_episode_steps, hooked)
        self._ended = ended_by is not None
        terminal = ended_by in _TERMINAL_ENDS
        info = setup.step_info(setup.info(0, ended_by, warned), before, action, obs)
        return setup.observed(obs)[0], reward, terminal, self._ended and not terminal, info

    def render(self) -> Optional[np.ndarray]:
        """The episode's current state as a picture (render_mode "rgb_array"
        or "depth_array"), or None without a render_mode."""
        if self._setup.pictures is None:
            return None
        if self._obs is None:
            raise ValueError("reset() the environment before render()")
        return self._setup.pictures.picture(self._setup.episodes, 0)

    def close(self) -> None:
        if self._setup.pictures is not None:
            self._setup.pictures.close()
        super().close()


def chapter_env(**kwargs: Any) -> ScenarioEnv:
    """simloop/Chapter-v0: the chapter's run, a decision every 50 steps, its
    pictures looking at the box (which travels metres)."""
    kwargs.setdefault("control_every", 50)
    kwargs.setdefault("view", _CHAPTER_VIEW)
    return ScenarioEnv(Scenario.chapter(), **kwargs)


def chapter_vector_env(num_envs: int = 1, **kwargs: Any) -> ScenarioVectorEnv:
    kwargs.setdefault("control_every", 50)
    kwargs.setdefault("view", _CHAPTER_VIEW)
    return ScenarioVectorEnv(Scenario.chapter(), num_envs, **kwargs)


def pusht_env(**kwargs: Any) -> ScenarioEnv:
    """simloop/PushT-v0: the PushT scenario shipped with simloop, a decision every 10 steps."""
    kwargs.setdefault("control_every", 10)
    return ScenarioEnv(PUSHT_SCENARIO, **kwargs)


def pusht_vector_env(num_envs: int = 1, **kwargs: Any) -> ScenarioVectorEnv:
    kwargs.setdefault("control_every", 10)
    return ScenarioVectorEnv(PUSHT_SCENARIO, num_envs, **kwargs)


def register_envs() -> None:
    """Registers simloop/Chapter-v0, simloop/PushT-v0 and simloop/Scenario-v0
    (once; `import simloop` does it as soon as gymnasium is imported)."""
    _gym_registry.register_envs(gymnasium)
