"""Gymnasium's v5 tasks against simloop over the same XML (issue 35, "Gymnasium's v5 tasks"), as far as they go today: a ScenarioEnv
over Gymnasium's own half_cheetah.xml (read from the installed gymnasium package), its joints recorded, a decision
every 5 physics steps and Gymnasium's reward written over the observed columns, steps as HalfCheetah-v5 does, bit for
bit. (The registered simloop/HalfCheetah-v5 and the other tasks are not built yet.)"""

from pathlib import Path

import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium", reason="needs gymnasium (the gym extra)")
simloop_gym = pytest.importorskip("simloop.gym", reason="needs gymnasium (the gym extra)")
import simloop  # noqa: E402


def gymnasium_env(env_id: str, **kwargs):
    try:
        return gymnasium.make(env_id, **kwargs)
    except Exception as e:  # Gymnasium's MuJoCo envs need the mujoco package (the PyPI build's venv has it)
        pytest.skip(f"Gymnasium's {env_id} does not make here: {type(e).__name__}: {e}")


def test_half_cheetah_steps_as_gymnasiums_bit_for_bit():
    # Both start at the XML's initial state (reset_noise_scale=0: Gymnasium's qvel is 0 + 0 * normal = 0) and take
    # the same 1,000 seeded actions (float64, inside the ctrlrange). Gymnasium writes ctrl and calls mj_step 5 times;
    # simloop takes the same 5 steps, its first begun as the observation's first half (stepper.hpp), the same bits.
    # The observation is qpos[1:] then qvel, read from the recorded joints' columns; the reward's arithmetic is
    # Gymnasium's, (x_after - x_before) / dt - 0.1 * sum(action^2), over the same doubles: equal bit for bit.
    theirs = gymnasium_env("HalfCheetah-v5", reset_noise_scale=0.0)
    xml = Path(gymnasium.__file__).parent / "envs" / "mujoco" / "assets" / "half_cheetah.xml"
    scenario = simloop.Scenario(xml, steps=5 * 1000, record={"joints": "all", "contacts": False})
    model = theirs.unwrapped.model
    joints = [model.joint(j).name for j in range(model.njnt)]
    dt = theirs.unwrapped.dt

    def reward(obs, action, next_obs):
        x = names.index("rootx_pos")
        return (next_obs[x] - obs[x]) / dt - 0.1 * np.sum(np.square(action))

    ours = simloop_gym.ScenarioEnv(scenario, control_every=5, reward=reward)
    names = ours.observation_names
    order = [names.index(j + "_pos") for j in joints[1:]] + [names.index(j + "_vel") for j in joints]
    their_obs, _ = theirs.reset(seed=0)
    our_obs, _ = ours.reset(seed=0)
    assert our_obs[order].tolist() == their_obs.tolist()
    actions = np.random.default_rng(35).uniform(-1.0, 1.0, size=(1000, model.nu))
    for k, action in enumerate(actions):
        their_obs, their_reward, their_terminated, their_truncated, _ = theirs.step(action)
        our_obs, our_reward, our_terminated, our_truncated, _ = ours.step(action)
        assert our_obs[order].tolist() == their_obs.tolist(), k
        assert our_reward == their_reward, k
        assert (our_terminated, our_truncated) == (their_terminated, their_truncated), k
    assert their_truncated  # Gymnasium's TimeLimit of 1,000 steps, simloop's scenario length of 5,000 physics steps
