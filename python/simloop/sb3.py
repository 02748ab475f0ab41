"""stable-baselines3 over simloop's vector env (needs the `sb3` extra:
stable-baselines3, which brings torch).

    >>> from stable_baselines3 import PPO
    >>> from simloop.sb3 import make_vec_env
    >>> envs = make_vec_env("simloop/PushT-v0", n_envs=8, seed=0, threads=2)
    >>> model = PPO("MlpPolicy", envs).learn(10_000)

make_vec_env mirrors stable_baselines3.common.env_util.make_vec_env: the same
first arguments, the envs wrapped to log their episodes (VecMonitor, where
SB3 wraps each env in a Monitor), seeded for their first reset. Its VecEnv,
SimloopVecEnv, is one ScenarioVectorEnv (its episodes stepped on C++
threads) under SB3's VecEnv interface, with SB3's conventions: done =
terminated or truncated; an ended env is reset in the same step, its last
observation in info["terminal_observation"], info["TimeLimit.truncated"]
on every step, and the new episode's reset info in reset_infos. Bitwise the
obs, rewards and dones of SB3's DummyVecEnv over as many ScenarioEnvs with
the same seeds.

Importing simloop does not import this module (nor torch): import
simloop.sb3 to use it, before the first picture is drawn (it loads triton,
torch's compiler, whose LLVM must come before Mesa's).
"""

from __future__ import annotations

import os
from typing import Any, Dict, List, Optional, Sequence, Type, Union, cast

import gymnasium
import numpy as np
from gymnasium.vector import AutoresetMode
from stable_baselines3.common.vec_env import VecEnv, VecMonitor
from stable_baselines3.common.vec_env.base_vec_env import VecEnvIndices, VecEnvObs, VecEnvStepReturn

from ._checks import _check_int, _describe

try:
    # Mesa's software renderer (simloop's pictures where there is no GPU)
    # and triton (which torch's optimisers load) each carry an LLVM: triton
    # loaded after Mesa has drawn crashes the process; loaded first, both work.
    import triton  # noqa: F401
except ImportError:
    pass
from .gym_vector import ScenarioVectorEnv
from .scenario import Scenario, ScenarioLike

# stable_baselines3's make_vec_env arguments that wrap or build each env in
# Python: simloop's envs are one vector env stepped in C++.
_PER_ENV_ARGUMENTS = (
    "start_index",
    "monitor_dir",
    "wrapper_class",
    "vec_env_cls",
    "vec_env_kwargs",
    "monitor_kwargs",
    "wrapper_kwargs",
)


def _unbatch(infos: Dict[str, Any], n: int) -> List[Dict[str, Any]]:
    """Gymnasium's vector infos (an array per key and a "_key" mask) as one dict per env."""
    per_env: List[Dict[str, Any]] = [{} for _ in range(n)]
    for key, values in infos.items():
        if key.startswith("_"):
            continue
        mask = infos.get("_" + key, np.ones(n, dtype=bool))
        if isinstance(values, dict):
            nested = _unbatch(values, n)
            for i in np.flatnonzero(mask):
                per_env[i][key] = nested[i]
        else:
            for i in np.flatnonzero(mask):
                per_env[i][key] = values[i]
    return per_env


class SimloopVecEnv(VecEnv):
    """A ScenarioVectorEnv (autoreset_mode "SameStep") as stable-baselines3's
    VecEnv. Its envs share one vector env: get_attr gives the vector env's
    attribute for each env asked for; set_attr and env_method act on all
    the envs at once (indices None or every env; env_method returns the one
    result for each env), except env_method("render"), one picture per env."""

    def __init__(self, envs: ScenarioVectorEnv) -> None:
        if not isinstance(envs, ScenarioVectorEnv):
            raise TypeError(f"envs must be a simloop.gym.ScenarioVectorEnv, got {_describe(envs)}")
        if envs.autoreset_mode != AutoresetMode.SAME_STEP:
            raise ValueError(
                "envs must reset ended episodes in the same step (autoreset_mode='SameStep'), as SB3's VecEnv does, "
                f"got {envs.autoreset_mode.value!r}"
            )
        self.envs = envs  # (VecEnv's __init__ asks get_attr for the render mode)
        super().__init__(envs.num_envs, envs.single_observation_space, envs.single_action_space)
        self._actions: Optional[np.ndarray] = None

    def reset(self) -> VecEnvObs:
        """Resets every env with the seeds seed() set and the options
        set_options() set (then forgets them, as SB3's VecEnvs do)."""
        n = self.num_envs
        seeds = list(self._seeds)
        options = [o or None for o in self._options]
        # Envs given the same options (set_options(dict) gives every env the
        # same dict) reset together; the first reset must reset every env.
        groups: List[List[int]] = []
        for i in range(n):
            for group in groups:
                if options[group[0]] is options[i]:
                    group.append(i)
                    break
            else:
                groups.append([i])
        first = self.envs.observations is None
        obs = np.empty(0)
        for number, group in enumerate(groups):
            mask = np.zeros(n, dtype=bool)
            mask[group] = True
            if first and number == 0:
                mask[:] = True
            chosen = dict(options[group[0]] or {})
            if not mask.all():
                chosen["reset_mask"] = mask
            obs, infos = self.envs.reset(seed=seeds, options=chosen or None)
            for i, info in enumerate(_unbatch(infos, n)):
                if mask[i]:
                    self.reset_infos[i] = info
        self._reset_seeds()
        self._reset_options()
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = actions

    def step_wait(self) -> VecEnvStepReturn:
        obs, rewards, terminated, truncated, infos = self.envs.step(self._actions)
        dones = terminated | truncated
        per_env = _unbatch(infos, self.num_envs)
        for ended in np.flatnonzero(dones):
            reset_info = per_env[ended]
            final_obs = reset_info.pop("final_obs")
            per_env[ended] = reset_info.pop("final_info")
            per_env[ended]["terminal_observation"] = final_obs
            self.reset_infos[ended] = reset_info
        for i, info in enumerate(per_env):
            info["TimeLimit.truncated"] = bool(truncated[i] and not terminated[i])
        return obs, rewards.astype(np.float32), dones, per_env

    def close(self) -> None:
        self.envs.close()

    def get_images(self) -> Sequence[Optional[np.ndarray]]:
        """One picture per env (render() and VecVideoRecorder use them), given a render_mode."""
        pictures = self.envs.render()
        return [None] * self.num_envs if pictures is None else list(pictures)

    def _all(self, what: str, indices: VecEnvIndices) -> None:
        if sorted(self._get_indices(indices)) != list(range(self.num_envs)):
            raise ValueError(
                f"{what} acts on every env of a simloop vector env at once (indices None), got indices {indices!r}"
            )

    def get_attr(self, attr_name: str, indices: VecEnvIndices = None) -> List[Any]:
        value = getattr(self.envs, attr_name)
        return [value for _ in self._get_indices(indices)]

    def set_attr(self, attr_name: str, value: Any, indices: VecEnvIndices = None) -> None:
        self._all(f"set_attr({attr_name!r})", indices)
        setattr(self.envs, attr_name, value)

    def env_method(
        self, method_name: str, *method_args: Any, indices: VecEnvIndices = None, **method_kwargs: Any
    ) -> List[Any]:
        wanted = list(self._get_indices(indices))
        if method_name == "render":
            pictures = self.get_images()
            return [pictures[i] for i in wanted]
        self._all(f"env_method({method_name!r})", indices)
        result = getattr(self.envs, method_name)(*method_args, **method_kwargs)
        return [result for _ in wanted]

    def env_is_wrapped(self, wrapper_class: Type[gymnasium.Wrapper], indices: VecEnvIndices = None) -> List[bool]:
        return [False for _ in self._get_indices(indices)]


def make_vec_env(
    env_id: Union[str, ScenarioLike],
    n_envs: int = 1,
    seed: Optional[int] = None,
    env_kwargs: Optional[Dict[str, Any]] = None,
    **kwargs: Any,
) -> VecEnv:
    """n_envs episodes of a simloop env as a stable-baselines3 VecEnv,
    wrapped in VecMonitor (episode returns and lengths in the infos and
    SB3's logs), seeded with seed, seed + 1, ... for the first reset (as
    stable_baselines3's make_vec_env; PPO(seed=...) seeds them again).

    env_id: a registered simloop id ("simloop/PushT-v0"), or a scenario (a
    simloop.Scenario, or the path of a .toml scenario file) for
    ScenarioVectorEnv. env_kwargs and the other keyword arguments go to the
    vector env (control_every, reward, terminate, threads, ...); it resets
    ended episodes in the same step (SB3's autoreset).
    """
    n_envs = _check_int("n_envs", n_envs, 1, 1 << 20)
    if env_kwargs is not None and not isinstance(env_kwargs, dict):
        raise TypeError(f"env_kwargs must be a dict or None, got {_describe(env_kwargs)}")
    arguments = dict(env_kwargs or {})
    for name, value in kwargs.items():
        if name in arguments:
            raise ValueError(f"make_vec_env: {name} given twice (in env_kwargs and as a keyword)")
        arguments[name] = value
    for name in _PER_ENV_ARGUMENTS:
        if name in arguments:
            raise ValueError(
                f"make_vec_env: {name} is for stable_baselines3's make_vec_env, whose envs are Python objects; "
                "simloop's step together in C++ (wrap the VecEnv it returns instead)"
            )
    if "autoreset_mode" in arguments:
        raise ValueError("make_vec_env: autoreset_mode is SB3's (the same step); do not give it")
    arguments["autoreset_mode"] = AutoresetMode.SAME_STEP
    if isinstance(env_id, str) and not env_id.endswith(".toml"):
        entry = gymnasium.spec(env_id).vector_entry_point
        if not isinstance(entry, str) or not entry.startswith("simloop."):
            raise ValueError(
                f"make_vec_env: {env_id!r} is not a simloop env (its vector entry point is {entry!r}): "
                "use stable_baselines3.common.env_util.make_vec_env"
            )
        envs = cast(
            ScenarioVectorEnv,
            gymnasium.make_vec(env_id, num_envs=n_envs, vectorization_mode="vector_entry_point", **arguments),
        )
    elif isinstance(env_id, (Scenario, str, os.PathLike)):
        envs = ScenarioVectorEnv(env_id, n_envs, **arguments)
    else:
        raise TypeError(f"env_id must be a Gymnasium id, a simloop.Scenario or a .toml path, got {_describe(env_id)}")
    vec_env = VecMonitor(SimloopVecEnv(envs))
    if seed is not None:
        vec_env.seed(seed)
    return vec_env
