#!/usr/bin/env python3
"""simloop's Gymnasium env step against Gymnasium's own MujocoEnv, same scene, same reward.

The PushT scene (python/simloop/scenes/pusht.xml), a decision every --every
physics steps (1 and 10 by default), random actions drawn up front, and the
same reward in each: the T-block's progress in x minus an action cost.
Four pairs, each timed side by side on the same MuJoCo (run it in the PyPI
build's venv: the MujocoEnv needs the mujoco package):

- single env, a vectorised reward: simloop.gym.ScenarioEnv with the reward
  as a @batched function of its (1, n) observation arrays (numpy over a
  batch of one), against a minimal gymnasium MujocoEnv subclass
  (observation qpos and qvel, no rendering) whose step computes the reward
  from data.qpos with Python floats, and against the same MujocoEnv calling
  the same numpy reward on one-row arrays of its qpos (what the vectorised
  reward costs in itself, apart from the layer);
- single env, a per-step reward: the same, simloop's reward a plain
  function of one step's arrays (Python floats, as MujocoEnv's);
- --envs episodes, a vectorised reward: ScenarioVectorEnv (one thread) with
  the @batched reward over all of them, against as many MujocoEnvs stepped
  in a Python loop; time per episode step.

Rounds alternate which goes first; each round is --calls env.step calls
(episodes long enough not to end). Process CPU time (and wall-clock beside
it) per episode step, medians, and the median of the per-round CPU ratios.
Targets (issue 18), for the vectorised reward: <= 1.15 x MujocoEnv at one
physics step per action, <= 1.05 x at ten.

--v5 HalfCheetah,Hopper,...: Gymnasium's v5 tasks instead, simloop's
registered simloop/<Task>-v5 against Gymnasium's own <Task>-v5, each as
gymnasium.make and gymnasium.make_vec make it (1 env; --envs envs:
simloop's vector entry point on one C++ thread against Gymnasium's
SyncVectorEnv), reset_noise_scale=0, an ended episode reset; target
(issue 35) <= 1.0 x at --envs envs. Where EnvPool is installed, the --envs
envs also against EnvPool's same task (make_gymnasium, one thread, its own
bundled MuJoCo and its own C++ reward: reported, no target). The load
average is printed.

    .venv-pypi/bin/python bench/bench_gym_env.py [--rounds 21] [--calls 2000] [--every 1,10] [--envs 8]
    .venv-pypi/bin/python bench/bench_gym_env.py --v5 HalfCheetah,Hopper,Walker2d,Ant,Humanoid [--envs 8]
    (all eleven: add Swimmer,Reacher,Pusher,InvertedPendulum,InvertedDoublePendulum,HumanoidStandup)
"""

import argparse
import contextlib
import os
import statistics
import time
from pathlib import Path

import numpy as np
import simloop
from gymnasium import spaces
from gymnasium.envs.mujoco import MujocoEnv
from simloop.gym import PUSHT_SCENARIO, ScenarioEnv, ScenarioVectorEnv, batched

SCENE = str(Path(PUSHT_SCENARIO).with_name("pusht.xml"))
COST = 0.01  # the reward's weight on the action's size


class PushTMujocoEnv(MujocoEnv):
    """The same scene as a Gymnasium MujocoEnv: observation qpos and qvel."""

    def __init__(self, frame_skip: int, batched_reward=None) -> None:
        self.batched_reward = batched_reward  # the same numpy reward, over one-row arrays of qpos
        # MujocoEnv checks that render_fps is 1 / (timestep x frame_skip).
        fps = int(round(1.0 / (simloop.Model.from_file(SCENE).timestep * frame_skip)))
        self.metadata = {"render_modes": ["human", "rgb_array", "depth_array"], "render_fps": fps}
        observation = spaces.Box(-np.inf, np.inf, (17,), np.float64)  # PushT: nq 9 + nv 8
        super().__init__(SCENE, frame_skip, observation_space=observation)

    def step(self, action):
        if self.batched_reward is not None:
            before = self.data.qpos[None].copy()
            self.do_simulation(action, self.frame_skip)
            reward = float(self.batched_reward(before, action[None], self.data.qpos[None])[0])
            return self._get_obs(), reward, False, False, {}
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


class MujocoEnvs:
    """n MujocoEnvs stepped one after another: the baseline for a vector env."""

    def __init__(self, n: int, frame_skip: int) -> None:
        self.envs = [PushTMujocoEnv(frame_skip) for _ in range(n)]

    def reset(self, seed):
        for i, env in enumerate(self.envs):
            env.reset(seed=seed + i)

    def step(self, actions):
        for env, a in zip(self.envs, actions):
            env.step(a)

    def close(self):
        for env in self.envs:
            env.close()


class Restarting:
    """A single env whose ended episodes start again (the v5 tasks end: they fall)."""

    def __init__(self, env) -> None:
        self.env = env

    def reset(self, seed):
        self.env.reset(seed=seed)

    def step(self, action):
        if any(self.env.step(action)[2:4]):
            self.env.reset()


class EnvPoolEnvs:
    """EnvPool's <task>-v5, n envs on one thread, stepped as a vector env (it resets ended envs itself)."""

    def __init__(self, pool) -> None:
        self.pool = pool

    def reset(self, seed):
        self.pool.reset()

    def step(self, actions):
        self.pool.step(actions)


def envpool_envs(task, n):
    """EnvPool's task where it is installed and has it, else None (said in a line)."""
    try:
        import envpool

        return EnvPoolEnvs(envpool.make_gymnasium(f"{task}-v5", num_envs=n, batch_size=n, num_threads=1, seed=0))
    except (ImportError, ValueError, KeyError) as e:  # (not installed; no such task in this EnvPool)
        print(f"    (EnvPool's {task}-v5 left out: {type(e).__name__}: {e})")
        return None


def compare(label, ours, theirs, actions, rounds, per_call, target, them="MujocoEnv"):
    """Times ours and theirs over the same actions, alternating which goes first."""
    timed(ours, actions, 0), timed(theirs, actions, 0)  # warm up
    times = {"simloop": [], them: []}
    for r in range(rounds):
        pair = (("simloop", ours), (them, theirs))
        for name, env in pair if r % 2 else pair[::-1]:
            times[name].append(timed(env, actions, r))
    steps = len(actions) * per_call
    print(f"    {label}:")
    for name, t in times.items():
        cpu = statistics.median(x[1] for x in t) / steps * 1e6
        wall = statistics.median(x[0] for x in t) / steps * 1e6
        print(f"      {name:9s}: {cpu:7.2f} us CPU, {wall:7.2f} us wall per episode step")
    ratio = statistics.median(a[1] / b[1] for a, b in zip(times["simloop"], times[them]))
    print(
        f"      simloop / {them}: {ratio:.3f} x the CPU time (median of per-round ratios"
        f"{'; target <= ' + str(target) if target else ''})"
    )


@contextlib.contextmanager
def quiet_mujoco():
    """Gymnasium's XMLs use the deprecated settotalmass: while its envs compile them, mujoco's warnings are kept
    from MuJoCo's default handler, which would append them to MUJOCO_LOG.TXT in the working folder."""
    import mujoco

    previous = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(lambda message: None)
    try:
        yield
    finally:
        mujoco.set_mju_user_warning(previous)


def noise_free(task):
    """reset_noise_scale=0 where Gymnasium's task takes it (Reacher and Pusher draw their own start: they do not)."""
    import inspect

    import gymnasium

    creator = gymnasium.envs.registration.load_env_creator(gymnasium.spec(f"{task}-v5").entry_point)
    return {"reset_noise_scale": 0.0} if "reset_noise_scale" in inspect.signature(creator).parameters else {}


def v5_tasks(tasks, args) -> None:
    """simloop/<Task>-v5 against Gymnasium's <Task>-v5: 1 env, then args.envs envs."""
    import gymnasium

    print(f"{simloop.MUJOCO_VERSION}, simloop {simloop.__version__}, gymnasium {gymnasium.__version__}; load average")
    print(
        f"  {' '.join(f'{x:.2f}' for x in os.getloadavg())}; {args.calls} env.step calls a round, {args.rounds} rounds"
    )
    rng = np.random.default_rng(0)
    for task in tasks:
        print(f"  {task}-v5:")
        kwargs = noise_free(task)
        ours = Restarting(gymnasium.make(f"simloop/{task}-v5", **kwargs))
        with quiet_mujoco():
            theirs = Restarting(gymnasium.make(f"{task}-v5", **kwargs))
        actions = rng.uniform(-0.4, 0.4, size=(args.calls, ours.env.action_space.shape[0]))
        compare("1 env (gymnasium.make)", ours, theirs, actions, args.rounds, 1, None, f"Gymnasium's {task}")
        ours = gymnasium.make_vec(f"simloop/{task}-v5", num_envs=args.envs, threads=1, **kwargs)
        with quiet_mujoco():
            theirs = gymnasium.make_vec(f"{task}-v5", num_envs=args.envs, vectorization_mode="sync", **kwargs)
        batch = rng.uniform(-0.4, 0.4, size=(max(args.calls // args.envs, 1),) + ours.action_space.shape)
        label = f"{args.envs} envs (make_vec: simloop's on 1 C++ thread, Gymnasium's SyncVectorEnv)"
        compare(label, ours, theirs, batch, args.rounds, args.envs, 1.0, f"Gymnasium's {task}")
        pool = envpool_envs(task, args.envs)
        if pool is not None:
            label = f"{args.envs} envs against EnvPool's {task}-v5 (1 thread; its own MuJoCo and C++ task: no target)"
            compare(label, ours, pool, batch, args.rounds, args.envs, None, "EnvPool")
        ours.close(), theirs.close()
    print(f"  load average after: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=21)
    parser.add_argument("--calls", type=int, default=2000)
    parser.add_argument("--every", default="1,10")
    parser.add_argument("--envs", type=int, default=8)
    parser.add_argument("--v5", default="", help="Gymnasium's v5 tasks instead, comma-separated")
    args = parser.parse_args()
    if args.v5:
        v5_tasks(args.v5.split(","), args)
        return 0
    print(
        f"{simloop.MUJOCO_VERSION}, simloop {simloop.__version__}; PushT, {args.calls} env.step calls a "
        f"round, {args.rounds} rounds; CPU time per episode step (wall beside it), medians"
    )
    index = ScenarioEnv(PUSHT_SCENARIO).observation_names.index("tblock_x")
    vectorised = batched(lambda o, a, p: p[:, index] - o[:, index] - COST * np.einsum("ij,ij->i", a, a))

    def per_step(o, a, p):
        return float(p[index] - o[index]) - COST * float(a @ a)

    rng = np.random.default_rng(0)
    for every in (int(e) for e in args.every.split(",")):
        length = every * (args.calls + 1)
        target = 1.15 if every == 1 else 1.05
        print(f"  {every} physics step{'s' if every > 1 else ''} per action:")
        actions = rng.uniform(-1, 1, size=(args.calls, 2))
        scalar, same_numpy = (
            PushTMujocoEnv(every),
            PushTMujocoEnv(every, batched(lambda o, a, p: p[:, 0] - o[:, 0] - COST * np.einsum("ij,ij->i", a, a))),
        )  # (qpos[0] is tblock_x)
        for label, reward, theirs, goal in (
            ("one env, a vectorised (@batched) reward; MujocoEnv's in Python floats", vectorised, scalar, target),
            (
                "one env, a vectorised (@batched) reward; MujocoEnv's the same numpy on one-row arrays",
                vectorised,
                same_numpy,
                target,
            ),
            ("one env, a per-step reward", per_step, scalar, None),
        ):
            ours = ScenarioEnv(PUSHT_SCENARIO, control_every=every, steps=length, reward=reward)
            compare(label, ours, theirs, actions, args.rounds, 1, goal)
        scalar.close(), same_numpy.close()
        many = MujocoEnvs(args.envs, every)
        vector = ScenarioVectorEnv(
            PUSHT_SCENARIO, args.envs, control_every=every, steps=length, reward=vectorised, threads=1
        )
        batch = rng.uniform(-1, 1, size=(max(args.calls // args.envs, 1), args.envs, 2))
        compare(f"{args.envs} envs, a vectorised reward", vector, many, batch, args.rounds, args.envs, target)
        many.close()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
