"""Ending episodes on the trainer's terms: terminate conditions on the
observed columns or a callable, and batched reward and terminate functions
that the vector env calls once a step."""

import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium")

from simloop.gym import PUSHT_SCENARIO, ScenarioEnv, ScenarioVectorEnv, batched  # noqa: E402

PUSH = np.array([1.0, 0.0])  # full throttle in x: the block is pushed past x = 0.25 m


def steps_until_end(env, limit=200):
    env.reset(seed=0)
    for k in range(1, limit + 1):
        obs, _, terminated, truncated, info = env.step(PUSH)
        if terminated or truncated:
            return k, obs, terminated, truncated, info
    raise AssertionError("the episode did not end")


def test_a_condition_on_an_observed_column_ends_the_episode():
    env = ScenarioEnv(PUSHT_SCENARIO, control_every=10, terminate=[("tblock_x", ">", 0.25)])
    k, obs, terminated, truncated, info = steps_until_end(env)
    x = obs[env.observation_names.index("tblock_x")]
    assert terminated and not truncated and info["ended_by"] == "termination" and x > 0.25
    assert k < env.unwrapped._setup.episodes.steps // 10  # before the scenario's length
    with pytest.raises(ValueError, match="the episode has ended"):
        env.step(PUSH)
    # The same end by a callable, and by a batched one.
    index = env.observation_names.index("tblock_x")
    for hook in (lambda o: o[index] > 0.25, batched(lambda o: o[:, index] > 0.25)):
        assert steps_until_end(ScenarioEnv(PUSHT_SCENARIO, control_every=10, terminate=hook))[0] == k


@pytest.mark.parametrize("threads", [1, 2])
def test_batched_reward_and_terminate_give_the_per_env_bits(threads):
    index = ScenarioEnv(PUSHT_SCENARIO).observation_names.index("tblock_x")
    # (the same arithmetic per env and per batch: a @ a and einsum may round differently, numpy version by version)
    per_env = dict(
        reward=lambda o, a, p: float(p[index] - o[index]) - 0.01 * float(a[0] * a[0] + a[1] * a[1]),
        terminate=lambda p: p[index] > 0.22,
    )
    batch = dict(
        reward=batched(lambda o, a, p: p[:, index] - o[:, index] - 0.01 * (a[:, 0] * a[:, 0] + a[:, 1] * a[:, 1])),
        terminate=batched(lambda p: p[:, index] > 0.22),
    )
    envs = [ScenarioVectorEnv(PUSHT_SCENARIO, 4, control_every=10, threads=threads, **kw) for kw in (per_env, batch)]
    actions = np.random.default_rng(2).uniform([0.6, -0.2], [1.0, 0.2], size=(60, 4, 2))  # mostly along x
    for env in envs:
        env.reset(seed=3)
    ended = 0
    for action in actions:
        a, b = (env.step(action) for env in envs)
        for x, y in zip(a[:-1], b[:-1]):
            assert np.array_equal(x, y)
        ended += int(a[2].sum())
        if a[2].any():
            assert set(a[4]["ended_by"][a[2]]) == {"termination"}
    assert ended >= 4  # every env reached the line, and was reset the step after


@pytest.mark.parametrize(
    "terminate, error, message",
    [
        ([("tblok_x", ">", 0.3)], ValueError, "terminate: no observed column named 'tblok_x'; columns: "),
        ([("tblock_x", "=>", 0.3)], TypeError, "each terminate condition must be (column, op, value)"),
        ([("tblock_x", ">", float("nan"))], ValueError, "the value must be finite"),
        ("tblock_x > 0.3", TypeError, "terminate must be a callable or a list of (column, op, value) conditions"),
    ],
)
def test_bad_terminate_hooks_are_named(terminate, error, message):
    with pytest.raises(error) as caught:
        ScenarioEnv(PUSHT_SCENARIO, terminate=terminate)
    assert message in str(caught.value)


def test_a_hook_that_raises_leaves_the_env_usable():
    calls = []

    def flaky(obs):
        calls.append(1)
        if len(calls) == 1:
            raise RuntimeError("the trainer's bug")
        return False

    env = ScenarioEnv(PUSHT_SCENARIO, control_every=10, terminate=flaky)
    env.reset(seed=0)
    with pytest.raises(RuntimeError, match="the trainer's bug"):
        env.step(PUSH)
    obs, _, terminated, truncated, info = env.step(PUSH)  # the episode goes on from where it got
    assert info["step"] == 20 and not terminated and not truncated
    wrong = ScenarioVectorEnv(PUSHT_SCENARIO, 2, reward=batched(lambda o, a, p: np.zeros(3)))
    wrong.reset(seed=0)
    with pytest.raises(ValueError, match="a batched reward must return 2 values"):
        wrong.step(np.zeros((2, 2)))
    assert wrong.reset(seed=0)[0].shape == (2, len(wrong.observation_names))


@pytest.mark.parametrize(
    "hooks, message",
    [
        ({"reward": lambda o, a, p: None}, r"reward must return a number, got None \(NoneType\)"),
        (
            {"reward": lambda o, a, p: np.zeros(2)},
            r"reward must return a number, got array\(\[0\., 0\.\]\) \(ndarray\)",
        ),
        ({"terminate": lambda p: p}, r"terminate must return a bool, got array\(.*\(ndarray\)"),
        ({"terminate": lambda p: None}, r"terminate must return a bool, got None \(NoneType\)"),
        ({"terminate": batched(lambda p: p[:, 0])}, r"a batched terminate must return bools, got dtype float64"),
        ({"terminate": batched(lambda p: [None] * len(p))}, r"a batched terminate must return bools, got dtype object"),
    ],
)
@pytest.mark.parametrize("vector", [False, True])
def test_a_hook_that_returns_the_wrong_kind_of_value_is_named(hooks, message, vector):
    env = ScenarioVectorEnv(PUSHT_SCENARIO, 2, **hooks) if vector else ScenarioEnv(PUSHT_SCENARIO, **hooks)
    env.reset(seed=0)
    with pytest.raises(TypeError, match=message):
        env.step(np.zeros((2, 2)) if vector else PUSH)
