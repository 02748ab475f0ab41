#!/usr/bin/env python3
"""simloop's Gymnasium env step against Gymnasium's own MujocoEnv, same scene, same reward.

The PushT scene (python/simloop/scenes/pusht.xml), a decision every --every
physics steps (1 and 10 by default), random actions drawn up front, and the
same reward in both: the T-block's progress in x minus an action cost
(simloop's as a @batched function of its observation arrays; MujocoEnv's
from data.qpos). simloop.gym.ScenarioEnv against a minimal
gymnasium.envs.mujoco.MujocoEnv subclass (observation qpos and qvel, no
rendering), on the same MuJoCo: run it in the PyPI build's venv (the
MujocoEnv needs the mujoco package). Rounds alternate which goes first;
each round is --calls env.step calls (episodes long enough not to end).
Process CPU time (and wall-clock beside it) per env.step, medians, and the
median of the per-round CPU ratios. Targets (issue 18): <= 1.15 x
MujocoEnv at one physics step per action, <= 1.05 x at ten.

    .venv-pypi/bin/python bench/bench_gym_env.py [--rounds 21] [--calls 2000] [--every 1,10]
"""

import argparse
import statistics
import time
from pathlib import Path

import numpy as np
from gymnasium import spaces
from gymnasium.envs.mujoco import MujocoEnv

import simloop
from simloop.gym import PUSHT_SCENARIO, ScenarioEnv, batched

SCENE = str(Path(PUSHT_SCENARIO).with_name("pusht.xml"))
COST = 0.01  # the reward's weight on the action's size


class PushTMujocoEnv(MujocoEnv):
    """The same scene as a Gymnasium MujocoEnv: observation qpos and qvel."""

    def __init__(self, frame_skip: int) -> None:
        # MujocoEnv checks that render_fps is 1 / (timestep x frame_skip).
        fps = int(round(1.0 / (simloop.Model.from_file(SCENE).timestep * frame_skip)))
        self.metadata = {"render_modes": ["human", "rgb_array", "depth_array"], "render_fps": fps}
        observation = spaces.Box(-np.inf, np.inf, (17,), np.float64)  # PushT: nq 9 + nv 8
        super().__init__(SCENE, frame_skip, observation_space=observation)

    def step(self, action):
        x_before = self.data.qpos[0]
        self.do_simulation(action, self.frame_skip)
        reward = float(self.data.qpos[0] - x_before) - COST * float(action @ action)
        return self._get_obs(), reward, False, False, {}

    def _get_obs(self):
        return np.concatenate([self.data.qpos, self.data.qvel])

    def reset_model(self):
        self.set_state(self.init_qpos, self.init_qvel)
        return self._get_obs()


def timed(env, actions, seed):
    env.reset(seed=seed)
    wall, cpu = time.perf_counter(), time.process_time()
    for a in actions:
        env.step(a)
    return time.perf_counter() - wall, time.process_time() - cpu


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=21)
    parser.add_argument("--calls", type=int, default=2000)
    parser.add_argument("--every", default="1,10")
    args = parser.parse_args()
    print(f"{simloop.MUJOCO_VERSION}, simloop {simloop.__version__}; PushT, {args.calls} env.step calls a "
          f"round, {args.rounds} rounds; CPU time per env.step (wall beside it), medians")
    for every in (int(e) for e in args.every.split(",")):
        index = ScenarioEnv(PUSHT_SCENARIO).observation_names.index("tblock_x")
        reward = batched(lambda o, a, p: p[:, index] - o[:, index] - COST * np.einsum("ij,ij->i", a, a))
        ours = ScenarioEnv(PUSHT_SCENARIO, control_every=every, steps=every * (args.calls + 1), reward=reward)
        theirs = PushTMujocoEnv(every)
        actions = np.random.default_rng(0).uniform(-1, 1, size=(args.calls, 2))
        timed(ours, actions, 0), timed(theirs, actions, 0)  # warm up
        rounds = {"simloop": [], "MujocoEnv": []}
        for r in range(args.rounds):
            pair = (("simloop", ours), ("MujocoEnv", theirs))
            for name, env in (pair if r % 2 else pair[::-1]):
                rounds[name].append(timed(env, actions, r))
        print(f"  {every} physics step{'s' if every > 1 else ''} per action:")
        for name, times in rounds.items():
            cpu = statistics.median(t[1] for t in times) / args.calls * 1e6
            wall = statistics.median(t[0] for t in times) / args.calls * 1e6
            print(f"    {name:9s}: {cpu:7.2f} us CPU, {wall:7.2f} us wall per env.step")
        ratio = statistics.median(a[1] / b[1] for a, b in zip(rounds["simloop"], rounds["MujocoEnv"]))
        target = 1.15 if every == 1 else 1.05
        print(f"    simloop / MujocoEnv: {ratio:.3f} x the CPU time (median of per-round ratios; target <= {target})")
        theirs.close()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
