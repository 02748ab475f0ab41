"""ScenarioVectorEnv: N episodes of a scenario stepped together in C++ (gym.py
describes the episodes, and ScenarioEnv, the single environment)."""

from __future__ import annotations

from typing import Any, Dict, List, Optional, Sequence, Tuple, Union, cast

import numpy as np
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from ._checks import ModelLike, _check_int, _check_threads, _describe
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
)
from .render import RENDER_MODES
from .scenario import RESET_KEYS, ScenarioLike


def _refuse_non_finite(values: np.ndarray) -> None:
    """A ValueError naming the first env and action that is not finite, if any."""
    if not np.isfinite(values).all():
        env, index = np.argwhere(~np.isfinite(values))[0]
        raise ValueError(f"env {env}: action {index} is not finite, got {float(values[env, index])!r}")


class ScenarioVectorEnv(VectorEnv):
    """num_envs episodes of a scenario over one compiled model, one MuJoCo
    data each, stepped together on `threads` C++ threads (None: one per
    core) with the GIL released. Bitwise the same as num_envs ScenarioEnvs
    reset with the same seeds and stepped with the same actions, whatever
    the thread count, and the same infos as gymnasium.vector.SyncVectorEnv
    over them gives.

    autoreset_mode: Gymnasium's AutoresetMode (or its value, "NextStep",
    "SameStep", "Disabled"). NEXT_STEP (the default): the step after an
    episode ends resets it, ignoring its action, with reward 0 and both flags
    False. SAME_STEP: the step that ends it resets it at once; the ended
    episode's observation and info are in infos["final_obs"] and
    infos["final_info"]. DISABLED: the caller resets ended envs with
    reset(options={"reset_mask": mask}); stepping one first is an error. An
    autoreset draws the new episode's seed from that env's own np_random, as
    ScenarioEnv.reset() without a seed does, and starts as the scenario's
    own [reset] says (Gymnasium's autoreset passes no options: randomisation
    every episode needs belongs in the scenario, or in on_reset, which every
    reset runs, autoresets too). Other arguments: as for ScenarioEnv
    (observe is called once a step for the whole batch; on_reset once per
    env reset, every env's start shaped before any is put in place).
    """

    metadata = {"render_modes": list(RENDER_MODES), "autoreset_mode": AutoresetMode.NEXT_STEP}

    def __init__(
        self,
        scenario: ScenarioLike,
        num_envs: int = 1,
        *,
        control_every: int = 1,
        reward: Optional[Reward] = None,
        terminate: Optional[Terminate] = None,
        observe: Optional[Observe] = None,
        data_at_step: bool = False,
        on_reset: Optional[OnReset] = None,
        max_episode_steps: Optional[int] = None,
        autoreset_mode: Union[AutoresetMode, str] = AutoresetMode.NEXT_STEP,
        threads: Optional[int] = None,
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
        try:
            mode = AutoresetMode(autoreset_mode)
        except ValueError:
            raise ValueError(
                f"autoreset_mode must be one of {', '.join(repr(m.value) for m in AutoresetMode)}, "
                f"got {_describe(autoreset_mode)}"
            ) from None
        self.metadata = {**type(self).metadata, "autoreset_mode": mode}
        self.autoreset_mode = mode
        self.num_envs = _check_int("num_envs", num_envs, 1, 1 << 20)
        self._threads = _check_threads(threads)
        self._setup = _Setup(
            scenario,
            self.num_envs,
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
        self.metadata["render_fps"] = self._setup.render_fps
        self.single_action_space = self._setup.action_space
        self.single_observation_space = self._setup.observation_space
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.observation_names = self._setup.observation_names
        self.control_every = self._setup.control_every
        self.max_episode_steps = _check_max_episode_steps(max_episode_steps)
        self._rngs: List[Optional[np.random.Generator]] = [None] * self.num_envs
        self._obs: Optional[np.ndarray] = None  # the recorded rows (what reward and terminate see)
        self._decisions = np.zeros(self.num_envs, dtype=np.int64)
        self._ended = np.zeros(self.num_envs, dtype=bool)  # ended, not reset yet
        self._any_ended = False  # self._ended.any(), or True (then step() looks)
        self._everyone = np.ones(self.num_envs, dtype=bool)
        self._action_shape = (self.num_envs, self._setup.nu)

    def _reset_envs(
        self,
        envs: Sequence[int],
        seeds: Sequence[Optional[int]],
        obs: np.ndarray,
        infos: Dict[str, Any],
        start: Optional[str] = None,
    ) -> None:
        """Resets these envs (seeds: each one's, or None: drawn from its np_random), their first observations
        into obs; each env's np_random, count and info change as it is put in place (all together when on_reset
        is given: Setup.reset_envs)."""
        rngs: List[np.random.Generator] = []
        states: Dict[int, Any] = {}  # an env's generator state before its seed is drawn: put back if it is not reset
        for k, (i, seed) in enumerate(zip(envs, seeds)):
            rng = self._rngs[i]
            if seed is not None or rng is None:
                rng, _ = seeding.np_random(seed)  # as gymnasium.Env.reset seeds np_random
            else:
                states[k] = rng.bit_generator.state  # (a deepcopy of the generator would cost a reset's worth)
            rngs.append(rng)
        episode_seeds = [_episode_seed(rng, seed) for rng, seed in zip(rngs, seeds)]

        def done(k: int, row: np.ndarray) -> None:
            i = envs[k]
            obs[i] = row
            self._rngs[i] = rngs[k]
            states.pop(k, None)
            self._decisions[i], self._ended[i] = 0, False
            self._add_info(infos, self._setup.start_info(i, episode_seeds[k], row[None]), i)

        try:
            self._setup.reset_envs(envs, episode_seeds, start, done)
        except BaseException:
            for k, state in states.items():  # the envs not reset keep their generators as they were
                rngs[k].bit_generator.state = state
            raise

    def reset(
        self, *, seed: Union[int, Sequence[Optional[int]], None] = None, options: Optional[Dict[str, Any]] = None
    ) -> Tuple[np.ndarray, Dict[str, Any]]:
        """seed: None, an int (env i gets seed + i, as Gymnasium's vector
        environments do), or one seed (or None) per env. options: as for
        ScenarioEnv.reset (the same start for every env reset, each drawn
        from its own seed), and "reset_mask": a bool array of num_envs: reset
        only those envs (the others keep their episodes, and no info)."""
        options = _check_options(options, ("reset_mask",) + RESET_KEYS)
        start = _start(options)
        if seed is None:
            seeds: List[Optional[int]] = [None] * self.num_envs
        elif isinstance(seed, (int, np.integer)) and not isinstance(seed, bool):
            seeds = [_check_int("seed", seed, 0, 2**64 - self.num_envs) + i for i in range(self.num_envs)]
        else:
            # (a bool is not iterable here: list() raises TypeError for it, as before)
            seeds = list(cast(Sequence[Optional[int]], seed))
            if len(seeds) != self.num_envs:
                raise ValueError(f"seed must be None, an int, or {self.num_envs} seeds, got {len(seeds)}")
        mask = np.ones(self.num_envs, dtype=bool)
        if "reset_mask" in options:
            mask = options["reset_mask"]
            if not isinstance(mask, np.ndarray) or mask.dtype != np.bool_ or mask.shape != (self.num_envs,):
                raise ValueError(
                    f"options['reset_mask'] must be a numpy bool array of shape ({self.num_envs},), "
                    f"got {_describe(mask)}"
                )
            if not mask.any():
                raise ValueError("options['reset_mask'] resets no env: give at least one True")
            if self._obs is None and not mask.all():
                raise ValueError("the first reset must reset every env (no reset_mask, or all True)")
        obs = self._obs if self._obs is not None else np.zeros((self.num_envs, len(self._setup.names)))
        infos: Dict[str, Any] = {}
        envs = [int(i) for i in np.flatnonzero(mask)]
        self._reset_envs(envs, [seeds[i] for i in envs], obs, infos, start)
        self._obs = obs
        self._any_ended = bool(self._ended.any())
        return self._setup.observed(obs), infos

    @property
    def observations(self) -> Optional[np.ndarray]:
        """The envs' current observations (num_envs, n), a copy, as the last
        reset or step returned them; None before the first reset."""
        return None if self._obs is None else self._setup.observed(self._obs)

    def step(self, actions: object) -> Tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, Dict[str, Any]]:
        if self._obs is None:
            raise ValueError("reset() the environment before step()")
        setup = self._setup
        values = setup.actions(actions, self._action_shape)
        if self._any_ended:  # an autoreset due, or a refusal (Disabled)
            return self._step_ended(values)
        # Every env steps: one call into C++, which checks the actions
        # before it steps any and hands back the flags and each env's step
        # and time with the observations.
        try:
            obs, terminated, truncated, steps, times = setup.episodes.step(
                values, self.control_every, None, self._threads, True
            )
        except ValueError:
            _refuse_non_finite(values)  # (in Python's words: which env)
            raise
        before, self._obs = self._obs, obs  # stepped: a hook that raises below leaves the envs where they are
        flagged = terminated.any() or truncated.any()
        if flagged:
            self._any_ended = True
            self._ended |= terminated | truncated
        self._decisions += 1
        rewards = setup.rewards(before, values, obs)
        infos: Dict[str, Any] = {}
        setup.add_step_infos(infos, before, values, obs, self._everyone)
        if flagged or setup.terminates or self.max_episode_steps is not None:
            hooked = setup.terminations(obs) if setup.terminates else np.zeros(self.num_envs, dtype=bool)
            steps, times = self._end(obs, terminated, truncated, hooked, self._everyone, infos, steps, times)
        infos.update({"step": steps, "_step": self._everyone.copy(), "time": times, "_time": self._everyone.copy()})
        return setup.observed(obs), rewards, terminated, truncated, infos

    def _step_ended(self, values: np.ndarray) -> Tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, Dict[str, Any]]:
        """step() when some env has ended: Disabled refuses it, NextStep
        resets it (ignoring its action), and only the others step."""
        _refuse_non_finite(values)  # (before any autoreset: a refused step changes nothing)
        infos: Dict[str, Any] = {}
        if self.autoreset_mode == AutoresetMode.DISABLED and self._ended.any():
            raise ValueError(
                f"env {int(np.flatnonzero(self._ended)[0])} has ended: reset it first "
                "(reset(options={'reset_mask': mask}); autoreset_mode is Disabled)"
            )
        assert self._obs is not None
        resetting = self._ended.copy() if self.autoreset_mode == AutoresetMode.NEXT_STEP else np.zeros_like(self._ended)
        if resetting.any():
            resets = [int(i) for i in np.flatnonzero(resetting)]
            self._reset_envs(resets, [None] * len(resets), self._obs, infos)
        active = ~resetting
        mask = None if not resetting.any() else active.astype(np.uint8)
        setup = self._setup
        obs, terminated, truncated, steps, times = setup.episodes.step(
            values, self.control_every, mask, self._threads, True
        )
        obs[resetting] = self._obs[resetting]
        before, self._obs = self._obs, obs  # stepped: a hook that raises below leaves the envs where they are
        self._decisions[active] += 1
        terminated &= active
        truncated &= active
        self._ended |= terminated | truncated
        rewards = np.zeros(self.num_envs)
        hooked = np.zeros(self.num_envs, dtype=bool)
        if active.all():
            rewards = setup.rewards(before, values, obs)
            if setup.terminates:
                hooked = setup.terminations(obs)
        elif active.any():
            envs = np.flatnonzero(active)
            rewards[active] = setup.rewards(before[active], values[active], obs[active], envs)
            if setup.terminates:
                hooked[active] = setup.terminations(obs[active], envs)
        setup.add_step_infos(infos, before, values, obs, active)
        steps, times = self._end(obs, terminated, truncated, hooked, active, infos, steps, times)
        self._any_ended = bool(self._ended.any())
        # Every env stepped or was reset: each has its step and time (as
        # _add_info would lay them out, env by env).
        infos.update({"step": steps, "_step": self._everyone.copy(), "time": times, "_time": self._everyone.copy()})
        return setup.observed(obs), rewards, terminated, truncated, infos

    def _end(
        self,
        obs: np.ndarray,
        terminated: np.ndarray,
        truncated: np.ndarray,
        hooked: np.ndarray,
        active: np.ndarray,
        infos: Dict[str, Any],
        steps: np.ndarray,
        times: np.ndarray,
    ) -> Tuple[np.ndarray, np.ndarray]:
        """Ends the episodes that end on this step (each info says why; SameStep
        resets them at once); gives each env's step and time after that."""
        ending = terminated | truncated | hooked
        if self.max_episode_steps is not None:
            ending |= active & (self._decisions >= self.max_episode_steps)
        if not ending.any():
            return steps, times
        self._any_ended = True
        setup = self._setup
        for i in np.flatnonzero(ending):  # each ended episode's info says why
            ended_by = _ended_by(
                bool(terminated[i]),
                bool(truncated[i]),
                int(self._decisions[i]),
                self.max_episode_steps,
                bool(hooked[i]),
            )
            info = setup.info(int(i), ended_by, bool(terminated[i]))
            terminated[i] = ended_by in _TERMINAL_ENDS
            truncated[i] = not terminated[i]
            self._ended[i] = True
            if self.autoreset_mode == AutoresetMode.SAME_STEP:
                info.update(setup.take_step_info(infos, int(i)))  # (this step's task keys: the ended episode's)
                self._add_info(infos, {"final_obs": setup.observed(obs[i : i + 1])[0], "final_info": info}, int(i))
            else:
                self._add_info(infos, info, int(i))
        if self.autoreset_mode == AutoresetMode.SAME_STEP:  # each ended env reset at once
            envs = [int(i) for i in np.flatnonzero(ending)]
            self._reset_envs(envs, [None] * len(envs), obs, infos)
            steps, times = setup.episodes.progress()
            self._any_ended = bool(self._ended.any())
        return steps, times

    def render(self) -> Optional[Tuple[np.ndarray, ...]]:
        """Every env's current state as a picture, one per env (as
        SyncVectorEnv gives them), or None without a render_mode."""
        if self._setup.pictures is None:
            return None
        if self._obs is None:
            raise ValueError("reset() the environment before render()")
        pictures = self._setup.pictures
        return tuple(pictures.picture(self._setup.episodes, i) for i in range(self.num_envs))

    def close_extras(self, **kwargs: Any) -> None:
        if self._setup.pictures is not None:
            self._setup.pictures.close()
