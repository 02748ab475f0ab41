"""Hooks that see the simulation: reward(obs, action, next_obs, physics) and
terminate(next_obs, physics) read the env's MuJoCo state by name, read-only,
as the state next_obs observes; plain or batched, single env or vector env
on any threads, the same bits."""

from pathlib import Path

import numpy as np
import pytest
import simloop

gym_module = pytest.importorskip("simloop.gym", reason="needs gymnasium (the gym extra)")
gymnasium = pytest.importorskip("gymnasium")

# The walker (tests/scenes/walker.xml) under random hip and knee torques: its torso's imu site, the torso's contact
# forces and its subtree's velocity, also recorded as columns to compare the hooks' reads with.
RECORD = {
    "joints": "all",
    "data": [("site_xpos", "imu"), ("cfrc_ext", "torso"), ("subtree_linvel", "torso")],
    "contacts": False,
}


def walker(steps: int = 200) -> simloop.Scenario:
    return simloop.Scenario(Path(__file__).parents[1] / "scenes" / "walker.xml", steps=steps, record=RECORD)


NAMES = gym_module.ScenarioEnv(walker()).observation_names
HEIGHT = NAMES.index("imu_site_xpos2")
FORCE_Z = NAMES.index("torso_cfrc_ext5")
SUBTREE_X = NAMES.index("torso_subtree_linvel0")


def height(obs, action, next_obs, physics):
    return float(physics.named.data.site_xpos["imu"][2])


def height_of_columns(obs, action, next_obs):
    return float(next_obs[HEIGHT])


@gym_module.batched
def heights(obs, action, next_obs, physics):
    return np.array([p.named.data.site_xpos["imu"][2] for p in physics])


def actions(steps: int, n: int) -> np.ndarray:
    return np.random.default_rng(3).uniform(-1.0, 1.0, size=(steps, n, 4))


def returns_of(env, seeds, steps=50) -> list:
    # 50 decisions of 5 steps over a 200-step episode: each env ends at decision 40 and is reset at the next step
    # (NextStep), whose reward is 0 and whose hooks see only the envs that stepped.
    env.reset(seed=seeds)
    total = np.zeros(len(seeds))
    for a in actions(steps, len(seeds)):
        total += env.step(a)[1]
    return total.tolist()


def test_a_reward_over_named_state_gives_the_same_returns_batched_per_env_and_on_any_threads():
    seeds = [0, 1, 2]
    vector = {
        (label, threads): returns_of(
            gym_module.ScenarioVectorEnv(walker(), 3, control_every=5, reward=reward, threads=threads), seeds
        )
        for label, reward in (("plain", height), ("batched", heights), ("columns", height_of_columns))
        for threads in (1, 2)
    }
    sync = gymnasium.vector.SyncVectorEnv(
        [lambda: gym_module.ScenarioEnv(walker(), control_every=5, reward=height) for _ in seeds]
    )
    expected = returns_of(sync, seeds)
    assert all(r == expected for r in vector.values()), vector
    assert min(expected) > 1.0  # some 40 heights of a torso above the floor each: read, not zeros


def test_the_hooks_read_the_state_next_obs_observes_derived_arrays_included():
    # Every step, the physics' site position, the torso's cfrc_ext (mj_rnePostConstraint) and subtree_linvel
    # (mj_subtreeVel) equal the columns recorded for the same state, bit for bit.
    seen = []

    def reward(obs, action, next_obs, physics):
        data = physics.named.data
        read = [data.site_xpos["imu"][2], data.cfrc_ext["torso"][5], data.subtree_linvel["torso"][0]]
        seen.append((read, [next_obs[HEIGHT], next_obs[FORCE_Z], next_obs[SUBTREE_X]]))
        return 0.0

    def terminate(next_obs, physics):
        return bool(physics.named.data.site_xpos["imu"][2] < 0.0)

    env = gym_module.ScenarioEnv(walker(), control_every=5, reward=reward, terminate=terminate)
    env.reset(seed=4)
    for a in actions(39, 1):
        env.step(a[0])
    assert all(read == recorded for read, recorded in seen)
    assert any(read[1] != 0.0 for read, _ in seen) and any(read[2] != 0.0 for read, _ in seen)


def test_a_terminate_hook_over_named_state_ends_as_the_condition_on_its_column_does():
    def low(next_obs, physics):
        return bool(physics.named.data.site_xpos["imu"][2] < 0.9)

    ends = []
    batched = gym_module.batched(lambda obs, physics: np.array([low(o, p) for o, p in zip(obs, physics)]))
    for terminate in (low, [("imu_site_xpos2", "<", 0.9)], batched):
        env = gym_module.ScenarioVectorEnv(walker(), 2, control_every=5, terminate=terminate, threads=2)
        env.reset(seed=[5, 6])
        ends.append([env.step(a)[2].tolist() for a in actions(30, 2)])
    assert ends[0] == ends[1] == ends[2]
    assert any(any(flags) for flags in ends[0])  # the walker falls below 0.9 m: the hook ends episodes


def test_physics_is_read_only():
    def reward(obs, action, next_obs, physics):
        physics.named.data.qpos["hip_left"] = 0.5
        return 0.0

    env = gym_module.ScenarioEnv(walker(), reward=reward)
    env.reset(seed=0)
    with pytest.raises(ValueError, match="physics is read-only in a reward or terminate hook: qpos is the env"):
        env.step(np.zeros(4))
    physics = env._setup.physics[0]
    with pytest.raises(ValueError, match="read-only"):  # numpy's own refusal, for a write through the view
        physics.named.data.xpos["torso"][0] = 1.0
    with pytest.raises(ValueError, match="physics is read-only"):
        physics.named.model.body_mass["torso"] = 2.0  # randomisable on a Sim, not from a hook


def test_a_hook_that_does_not_ask_for_the_physics_costs_nothing():
    # Only a required parameter past the plain ones asks: a default or *args keeps the plain call.
    for reward in (height_of_columns, lambda o, a, n, scale=2.0: 0.0, lambda *args: 0.0):
        env = gym_module.ScenarioEnv(walker(), reward=reward)
        assert env._setup.physics == ()
        env.reset(seed=0)
        env.step(np.zeros(4))
    assert gym_module.ScenarioEnv(walker(), reward=height)._setup.physics != ()
