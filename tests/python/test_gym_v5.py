"""Gymnasium's v5 tasks against simloop over the same XML (issue 35, "Gymnasium's v5 tasks"), as far as they go
today: a ScenarioEnv over Gymnasium's own XML (read from the installed gymnasium package), its joints recorded,
Gymnasium's frame_skip as control_every, and the task's reward and termination written over the observed columns,
steps as Gymnasium's HalfCheetah-v5, Hopper-v5 and Walker2d-v5 do, bit for bit. (Registered simloop/*-v5 ids, their
keyword arguments and Gymnasium's reset noise are not built yet.)"""

from pathlib import Path

import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium", reason="needs gymnasium (the gym extra)")
simloop_gym = pytest.importorskip("simloop.gym", reason="needs gymnasium (the gym extra)")
import simloop  # noqa: E402


def gymnasium_env(env_id: str, **kwargs):
    try:
        env = gymnasium.make(env_id, **kwargs)
    except Exception as e:  # Gymnasium's MuJoCo envs need the mujoco package and imageio
        pytest.skip(f"Gymnasium's {env_id} does not make here: {type(e).__name__}: {e}")
    import mujoco

    if simloop.MUJOCO_VERSION.split()[-1] != mujoco.__version__:  # the bits are one MuJoCo build's
        pytest.skip(f"Gymnasium steps mujoco {mujoco.__version__}, simloop {simloop.MUJOCO_VERSION}")
    return env


class Columns:
    """qpos and qvel of a task's joints (every joint: one coordinate each) from simloop's observed columns."""

    def __init__(self, names, joints):
        self.pos = [names.index(j + "_pos") for j in joints]
        self.vel = [names.index(j + "_vel") for j in joints]

    def gymnasium_obs(self, obs, clip_velocity):  # qpos[1:], then qvel (clipped to +-10 by Hopper's and Walker's)
        velocity = np.clip(obs[self.vel], -10, 10) if clip_velocity else obs[self.vel]
        return np.concatenate((obs[self.pos][1:], velocity))


def locomotion(healthy):
    """A task's reward, as v5's _get_rew computes it: (forward + healthy) - ctrl cost, with x_velocity = (x_after -
    x_before) / dt; healthy(qpos, qvel) -> bool, or None (HalfCheetah: no healthy reward)."""

    def make(columns, dt, ctrl_cost_weight):
        def reward(obs, action, next_obs):
            x_velocity = (next_obs[columns.pos[0]] - obs[columns.pos[0]]) / dt
            forward = 1.0 * x_velocity
            ctrl_cost = ctrl_cost_weight * np.sum(np.square(action))
            if healthy is None:
                return forward - ctrl_cost
            return (forward + healthy(next_obs[columns.pos], next_obs[columns.vel]) * 1.0) - ctrl_cost

        return reward

    return make


def hopper_healthy(qpos, qvel):
    state = np.concatenate((qpos, qvel))[2:]
    return (
        bool(np.all(np.logical_and(-100.0 < state, state < 100.0))) and 0.7 < qpos[1] < np.inf and -0.2 < qpos[2] < 0.2
    )


def walker_healthy(qpos, qvel):
    return 0.8 < qpos[1] < 2.0 and -1.0 < qpos[2] < 1.0


TASKS = {  # env id: (XML, frame_skip, ctrl_cost_weight, healthy, qvel clipped in the observation)
    "HalfCheetah-v5": ("half_cheetah.xml", 5, 0.1, None, False),
    "Hopper-v5": ("hopper.xml", 4, 1e-3, hopper_healthy, True),
    "Walker2d-v5": ("walker2d_v5.xml", 4, 1e-3, walker_healthy, True),
}


@pytest.mark.parametrize("env_id", list(TASKS))
def test_a_task_steps_as_gymnasiums_bit_for_bit(env_id, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # MuJoCo's default handler writes Gymnasium's load warnings to MUJOCO_LOG.TXT here
    # Both start at the XML's initial state (reset_noise_scale=0: Gymnasium's noise is 0 * uniform and 0 * normal)
    # and take the same 1,000 seeded actions (float64, inside the ctrlrange), reset together when an episode ends.
    # Gymnasium writes ctrl and calls mj_step frame_skip times; simloop takes the same steps, the first begun as the
    # observation's first half (stepper.hpp), the same bits. The observation, reward and termination are computed
    # from the same doubles with Gymnasium's arithmetic in Gymnasium's order: equal bit for bit, not within a tolerance.
    xml, frame_skip, ctrl_cost_weight, healthy, clip_velocity = TASKS[env_id]
    theirs = gymnasium_env(env_id, reset_noise_scale=0.0)
    path = Path(gymnasium.__file__).parent / "envs" / "mujoco" / "assets" / xml
    scenario = simloop.Scenario(path, steps=frame_skip * 1000, record={"joints": "all", "contacts": False})
    model = theirs.unwrapped.model
    joints = [model.joint(j).name for j in range(model.njnt)]
    names = simloop_gym.ScenarioEnv(scenario).observation_names
    columns = Columns(names, joints)
    reward = locomotion(healthy)(columns, theirs.unwrapped.dt, ctrl_cost_weight)
    terminate = None if healthy is None else lambda next_obs: not healthy(next_obs[columns.pos], next_obs[columns.vel])
    ours = simloop_gym.ScenarioEnv(scenario, control_every=frame_skip, reward=reward, terminate=terminate)
    actions = np.random.default_rng(35).uniform(-1.0, 1.0, size=(1000, model.nu))
    episodes, ended = 0, True
    for k, action in enumerate(actions):
        if ended:
            their_obs, _ = theirs.reset(seed=k)
            our_obs, _ = ours.reset(seed=k)
            assert columns.gymnasium_obs(our_obs, clip_velocity).tolist() == their_obs.tolist()
            episodes += 1
        their_obs, their_reward, their_terminated, their_truncated, _ = theirs.step(action)
        our_obs, our_reward, our_terminated, our_truncated, _ = ours.step(action)
        assert columns.gymnasium_obs(our_obs, clip_velocity).tolist() == their_obs.tolist(), k
        assert our_reward == their_reward, k
        assert (our_terminated, our_truncated) == (their_terminated, their_truncated), k
        ended = their_terminated or their_truncated
    # HalfCheetah runs its one episode to Gymnasium's TimeLimit (simloop: the scenario's length); the others fall.
    assert episodes == 1 and ended if healthy is None else episodes > 1
