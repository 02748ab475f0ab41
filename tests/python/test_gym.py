"""Gymnasium environments over scenarios (simloop/gym.py): registration,
check_env, seeding, frame skip, truncation and termination, and the vector
environment bitwise equal to single ones at any thread count."""

import subprocess
import sys
import warnings

import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium")

import simloop  # noqa: E402
from simloop.gym import PUSHT_SCENARIO, ScenarioEnv, ScenarioVectorEnv  # noqa: E402


def same_bits(a, b):
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    return a.shape == b.shape and np.array_equal(a.view(np.uint64), b.view(np.uint64))


def test_import_simloop_leaves_gymnasium_alone_and_registers_once_it_loads():
    code = (
        "import sys, simloop; assert 'gymnasium' not in sys.modules; import gymnasium; "
        "env = gymnasium.make('simloop/Chapter-v0'); print(env.unwrapped.control_every); "
        "print(type(gymnasium.make('simloop/PushT-v0').unwrapped).__name__)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.split() == ["50", "ScenarioEnv"]
    # gymnasium first, then simloop: registered at once; simloop.gym first
    # (it imports gymnasium itself): registered too.
    # A program that asks where gymnasium is before importing it: still registered (the hook was used
    # up by the question, and the import then registered nothing).
    for code in (
        "import gymnasium, simloop; gymnasium.make('simloop/PushT-v0')",
        "import simloop.gym, gymnasium; gymnasium.make('simloop/PushT-v0')",
        "import importlib.util, simloop; importlib.util.find_spec('gymnasium'); import gymnasium; "
        "gymnasium.make('simloop/PushT-v0')",
    ):
        subprocess.run([sys.executable, "-c", code], check=True)


def test_spaces_come_from_the_scenario():
    env = gymnasium.make("simloop/PushT-v0").unwrapped
    assert env.action_space.shape == (2,)
    assert np.array_equal(env.action_space.low, [-1, -1]) and np.array_equal(env.action_space.high, [1, 1])
    result = simloop.run_scenario(PUSHT_SCENARIO, steps=2)
    assert env.observation_names == result.column_names[2:]
    assert env.observation_space.shape == (len(result.column_names) - 2,)
    # An actuator without a ctrlrange: unbounded.
    walker = ScenarioEnv("tests/scenes/walker.toml")
    limited = walker.action_space.low > -np.inf
    assert walker.action_space.shape == (simloop.Scenario.from_file("tests/scenes/walker.toml").model().nu,)
    assert np.all(np.isinf(walker.action_space.low[~limited]))


def test_scenario_v0_takes_a_scenario_object_which_copies_and_pickles():
    import copy
    import pickle

    from gymnasium.utils.env_checker import check_env

    scenario = simloop.Scenario(scene="tests/scenes/pusht.xml", steps=60, controls={"push_x": 0.5})
    assert copy.deepcopy(scenario) is scenario  # it never changes
    again = pickle.loads(pickle.dumps(scenario))
    assert again.toml == scenario.toml
    assert same_bits(simloop.run_scenario(again).trajectory, simloop.run_scenario(scenario).trajectory)
    assert pickle.loads(pickle.dumps(simloop.Scenario.from_file(PUSHT_SCENARIO))).name == "pusht"
    env = gymnasium.make("simloop/Scenario-v0", scenario=scenario, control_every=5)
    with warnings.catch_warnings(record=True):
        warnings.simplefilter("always")
        check_env(env.unwrapped)  # remakes the env from its spec (a deep copy of its arguments)


def test_scenario_v0_takes_any_scenario():
    env = gymnasium.make("simloop/Scenario-v0", scenario="tests/scenes/arm_push.toml", control_every=5)
    obs, info = env.reset(seed=0)
    assert info["step"] == 0
    obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
    assert info["step"] == 5 and reward == 0.0
    with pytest.raises(TypeError):
        gymnasium.make("simloop/Scenario-v0")


def test_reset_seeds_the_scenarios_generator():
    # PushT's bump on the T-block is drawn from the seed: the env's force
    # column shows what run_scenario(seed=s) drew.
    env = ScenarioEnv(PUSHT_SCENARIO, control_every=10)
    column = env.observation_names.index("tblock_fy")
    for seed in (0, 1, 7):
        drawn = simloop.run_scenario(PUSHT_SCENARIO, seed=seed).disturbances[0]
        obs, info = env.reset(seed=seed)
        assert info["seed"] == seed
        for _ in range(drawn["start_step"] // 10):
            obs, *_ = env.step(np.zeros(2))
        assert obs[column] == drawn["force"][1] != 0.0
    # Same seed, same episode; resets without a seed follow from it.
    episodes = []
    for _ in range(2):
        env.reset(seed=11)
        episodes.append([env.reset()[1]["seed"] for _ in range(3)])
    assert episodes[0] == episodes[1] and len(set(episodes[0])) == 3


def test_an_episode_follows_the_bits_of_a_policy_run_with_the_same_actions():
    seen, actions = [], []

    def policy(obs):
        seen.append(obs.values.copy())
        actions.append(np.array([np.cos(obs.time * 3), np.clip(0.4 - obs["tblock_y"], -1, 1)]))
        return actions[-1]

    result = simloop.run_scenario(PUSHT_SCENARIO, seed=2, steps=333, policy=policy, control_every=20)
    env = ScenarioEnv(PUSHT_SCENARIO, control_every=20, steps=333)
    obs, _ = env.reset(seed=2)
    for k, action in enumerate(actions):
        assert same_bits(obs, seen[k]), k
        obs, _, terminated, truncated, info = env.step(action)
        assert not terminated and truncated == (k == len(actions) - 1)
    assert info["step"] == 333  # the last step took 13 physics steps, not 20
    names = env.observation_names
    for i, name in enumerate(names):
        if not (
            name.endswith("_ctrl")
            or name.endswith("_fx")
            or name.endswith("_fy")
            or name.endswith("_fz")
            or name.endswith("_tx")
            or name.endswith("_ty")
            or name.endswith("_tz")
        ):
            assert same_bits(obs[i], result.trajectory[-1, i + 2]), name
    with pytest.raises(ValueError, match="has ended"):
        env.step(np.zeros(2))


def test_reward_is_the_callers():
    calls = []

    def reward(obs, action, next_obs):
        calls.append((obs.copy(), action.copy(), next_obs.copy()))
        return -float(next_obs[0])

    env = ScenarioEnv(PUSHT_SCENARIO, control_every=5, reward=reward)
    first, _ = env.reset(seed=0)
    nxt, r, *_ = env.step([0.5, -0.5])
    assert same_bits(calls[0][0], first) and same_bits(calls[0][1], [0.5, -0.5]) and same_bits(calls[0][2], nxt)
    assert r == -nxt[0]
    with pytest.raises(TypeError, match="reward must be"):
        ScenarioEnv(PUSHT_SCENARIO, reward=1.0)


def test_divergence_terminates():
    env = gymnasium.make("simloop/Chapter-v0", timestep=1.0, steps=500, control_every=10)
    env.reset(seed=0)
    for _ in range(50):
        obs, _, terminated, truncated, info = env.step(np.ones(1, dtype=np.float32))
        if terminated or truncated:
            break
    assert terminated and not truncated
    assert info["step"] < 500 and info["warnings"]


def test_bad_actions_are_refused():
    env = ScenarioEnv(PUSHT_SCENARIO)
    with pytest.raises(ValueError, match="reset"):
        env.step([0, 0])
    env.reset(seed=0)
    with pytest.raises(ValueError, match=r"shape \(2,\)"):
        env.step([0, 0, 0])
    with pytest.raises(ValueError, match=r"^action 1 is not finite, got nan$"):
        env.step([0, np.nan])
    with pytest.raises(ValueError, match="render_mode"):
        ScenarioEnv(PUSHT_SCENARIO, render_mode="human")


def single_envs_with_next_step_autoreset(n, seed, actions, **kwargs):
    """What Gymnasium's next-step autoreset does, with n ScenarioEnvs."""
    envs = [ScenarioEnv(PUSHT_SCENARIO, **kwargs) for _ in range(n)]
    for i, env in enumerate(envs):
        env.reset(seed=seed + i)
    ended = [False] * n
    out = []
    for batch in actions:
        rows, rewards, terms, truncs = [], [], [], []
        for i, env in enumerate(envs):
            if ended[i]:
                o, _ = env.reset()
                r, te, tr = 0.0, False, False
            else:
                o, r, te, tr, _ = env.step(batch[i])
            ended[i] = te or tr
            rows.append(o), rewards.append(r), terms.append(te), truncs.append(tr)
        out.append((np.array(rows), np.array(rewards), np.array(terms), np.array(truncs)))
    return out


@pytest.mark.parametrize("threads", [1, 2])
def test_the_vector_env_equals_single_envs_stepped_alike(threads):
    n, steps = 5, 15
    rng = np.random.default_rng(0)
    actions = rng.uniform(-1, 1, size=(steps, n, 2))
    reward = lambda obs, action, next_obs: float(next_obs[3] - obs[3])  # noqa: E731
    kwargs = dict(control_every=10, steps=60, reward=reward)  # 6 decisions an episode: autoresets
    expected = single_envs_with_next_step_autoreset(n, 40, actions, **kwargs)
    venv = ScenarioVectorEnv(PUSHT_SCENARIO, n, threads=threads, **kwargs)
    venv.reset(seed=40)
    truncations = 0
    for k in range(steps):
        obs, rewards, terms, truncs, infos = venv.step(actions[k])
        assert same_bits(obs, expected[k][0]), k
        assert same_bits(rewards, expected[k][1]), k
        assert np.array_equal(terms, expected[k][2]) and np.array_equal(truncs, expected[k][3])
        truncations += truncs.sum()
    assert truncations >= n  # every env ended at least once, and was reset the step after


def test_make_vec_uses_the_vector_class():
    venv = gymnasium.make_vec("simloop/PushT-v0", num_envs=3, threads=2)
    assert isinstance(venv.unwrapped, ScenarioVectorEnv)
    obs, _ = venv.reset(seed=0)
    assert obs.shape == (3, venv.unwrapped.single_observation_space.shape[0])
    obs, rewards, terms, truncs, _ = venv.step(venv.action_space.sample())
    assert obs.shape[0] == 3 and rewards.shape == (3,) and terms.dtype == np.bool_
    venv.close()


def test_the_docs_random_policy_runs():
    from pathlib import Path

    readme = (Path(__file__).resolve().parents[2] / "docs" / "training.md").read_text(encoding="utf-8")
    after = readme.split("A random policy:\n\n```python\n", 1)[1]
    code = after.split("```", 1)[0]
    assert 'gymnasium.make("simloop/' in code and "env.step(env.action_space.sample())" in code
    namespace = {}
    exec(compile(code, "docs/training.md", "exec"), namespace)
    assert namespace["total"] == 0.0  # no reward function: 0.0 every step


def test_vector_env_arguments_are_checked():
    with pytest.raises(ValueError, match="num_envs"):
        ScenarioVectorEnv(PUSHT_SCENARIO, 0)
    with pytest.raises(ValueError, match=r"^threads must be from 1 to 4096, or 0 for one per core, got -1$"):
        ScenarioVectorEnv(PUSHT_SCENARIO, 2, threads=-1)
    venv = ScenarioVectorEnv(PUSHT_SCENARIO, 2)
    with pytest.raises(ValueError, match="reset"):
        venv.step(np.zeros((2, 2)))
    with pytest.raises(ValueError, match="2 seeds"):
        venv.reset(seed=[1, 2, 3])
    venv.reset(seed=[5, None])
    with pytest.raises(ValueError, match=r"shape \(2, 2\)"):
        venv.step(np.zeros(2))
    with pytest.raises(ValueError, match="finite"):
        venv.step(np.full((2, 2), np.inf))
