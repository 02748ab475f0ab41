"""Episodes a trainer shapes: reset(options=...) sets the start state, noise
on it and the episode's scene parameters, drawn from the episode's seed, as a
scenario's [reset] table does for a run and a batch."""

import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium")

import simloop  # noqa: E402
from simloop.gym import PUSHT_SCENARIO, ScenarioEnv, ScenarioVectorEnv  # noqa: E402

# PushT: the T-block's free joint (7 qpos, 6 qvel), then the pusher's two slides.
QPOS = [0.3, 0.1, 0.02, 1.0, 0.0, 0.0, 0.0, -0.05, 0.0]
SHAPED = {
    "qpos_noise": 0.01,
    "qvel_noise": 0.05,
    "params": [
        {"kind": "mass", "name": "tblock", "uniform": [0.1, 0.6]},
        {"kind": "friction", "value": 0.4},
        {"kind": "gravity", "uniform": [8.0, 11.0]},
    ],
}


def column(env, obs, name):
    return obs[env.observation_names.index(name)]


def test_a_given_state_is_where_the_episode_starts():
    env = ScenarioEnv(PUSHT_SCENARIO)
    obs, _ = env.reset(seed=0, options={"qpos": QPOS, "qvel": [0, 0.5, 0, 0, 0, 0, 0, 0]})
    assert column(env, obs, "tblock_x") == 0.3 and column(env, obs, "tblock_vy") == 0.5
    plain, _ = env.reset(seed=0)  # options are for that episode only
    assert column(env, plain, "tblock_x") == 0.2


def test_noise_and_params_come_from_the_episodes_seed():
    env = ScenarioEnv(PUSHT_SCENARIO)
    a, _ = env.reset(seed=5, options=SHAPED)
    b, _ = env.reset(seed=5, options=SHAPED)
    c, _ = env.reset(seed=6, options=SHAPED)
    assert np.array_equal(a, b) and not np.array_equal(a, c)
    assert abs(column(env, a, "tblock_x") - 0.2) <= 0.01
    # A seeded sequence of episodes repeats, noise and all.
    first = [env.reset(seed=1, options=SHAPED)[0]] + [env.reset(options=SHAPED)[0] for _ in range(3)]
    again = [env.reset(seed=1, options=SHAPED)[0]] + [env.reset(options=SHAPED)[0] for _ in range(3)]
    assert all(np.array_equal(x, y) for x, y in zip(first, again))


def test_an_episode_a_run_and_a_batch_start_alike():
    """options == the scenario's [reset]: the episode's steps are the run's,
    with the same actions as the run's controls."""
    shaped = simloop.Scenario(
        scene="tests/scenes/pusht.xml", steps=40, controls={"push_x": 0.8, "push_y": 0.2}, reset=SHAPED
    )
    plain = simloop.Scenario(scene="tests/scenes/pusht.xml", steps=40, controls={"push_x": 0.8, "push_y": 0.2})
    run = simloop.run_scenario(shaped, seed=9)
    env = ScenarioEnv(plain, control_every=10)
    obs, _ = env.reset(seed=9, options=SHAPED)
    rows = [obs] + [env.step([0.8, 0.2])[0] for _ in range(4)]
    names = run.column_names[2:]
    state = [i for i, n in enumerate(names) if "ctrl" not in n and "force" not in n]
    for k, row in enumerate(rows[1:], start=1):  # after each decision: the run's row at that step
        assert np.array_equal(row[state], run.trajectory[10 * k, 2:][state]), k
    # The scenario's own [reset] is what an env without options starts from.
    from_file = ScenarioEnv(shaped, control_every=10)
    assert np.array_equal(from_file.reset(seed=9)[0][state], rows[0][state])
    batch = simloop.run_scenario_batch(shaped, seeds=[9, 10], threads=2)
    assert np.array_equal(batch.results[0].trajectory, run.trajectory, equal_nan=True)


@pytest.mark.parametrize("threads", [1, 2])
def test_the_vector_env_shapes_each_env_as_a_single_one(threads):
    venv = ScenarioVectorEnv(PUSHT_SCENARIO, 3, threads=threads, control_every=5)
    obs, infos = venv.reset(seed=[3, 4, 5], options=SHAPED)
    singles = []
    for i, seed in enumerate([3, 4, 5]):
        singles.append(ScenarioEnv(PUSHT_SCENARIO, control_every=5))
        expected, _ = singles[i].reset(seed=seed, options=SHAPED)
        assert np.array_equal(obs[i], expected)
    after = venv.step(np.full((3, 2), 0.5))[0]
    for i, single in enumerate(singles):  # each with its own mass, friction and gravity
        assert np.array_equal(after[i], single.step([0.5, 0.5])[0]), i
    masked, _ = venv.reset(options={"reset_mask": np.array([False, True, False]), "qpos": QPOS})
    assert column(venv, masked[1], "tblock_x") == 0.3 and np.array_equal(masked[0], after[0])


@pytest.mark.parametrize(
    "options, error, message",
    [
        ({"qpos": [1, 2]}, ValueError, "reset.qpos must hold the scene's nq = 9 values, got 2"),
        ({"qpos_noise": -1.0}, ValueError, "reset.qpos_noise: must not be negative"),
        ({"qvel": [np.nan] * 8}, ValueError, "qvel must be finite"),
        (
            {"params": [{"kind": "mass", "name": "tblok", "value": 1.0}]},
            ValueError,
            "reset.param[0]: mass of 'tblok' = 1.0: no body named 'tblok' (did you mean 'tblock'?)",
        ),
        ({"params": [{"kind": "stiffness", "value": 1.0}]}, ValueError, "scene parameter kind must be one of"),
        ({"params": [{"kind": "friction", "uniform": [2.0, 1.0]}]}, ValueError, "low <= high"),
        ({"params": 3}, TypeError, "reset params must be a list of dicts"),
    ],
)
def test_bad_options_are_named_and_the_env_stays_usable(options, error, message):
    env = ScenarioEnv(PUSHT_SCENARIO)
    before, _ = env.reset(seed=0)
    with pytest.raises(error) as caught:
        env.reset(options=options)  # (without a seed: its generator is left as it was)
    assert message in str(caught.value) and "\n" not in str(caught.value)
    twin = ScenarioEnv(PUSHT_SCENARIO)
    twin.reset(seed=0)
    assert np.array_equal(env.np_random.integers(0, 2**62, 4), twin.np_random.integers(0, 2**62, 4))
    stepped = env.step([0.0, 0.0])[0]  # the episode it had goes on
    fresh = ScenarioEnv(PUSHT_SCENARIO)
    fresh.reset(seed=0)
    assert np.array_equal(stepped, fresh.step([0.0, 0.0])[0])


OWN = {"qpos": QPOS, "qpos_noise": 0.01, "params": [{"kind": "gravity", "value": 5.0}]}
MASS = [{"kind": "mass", "name": "tblock", "value": 0.5}]


@pytest.mark.parametrize(
    "options, same_as",
    [
        # The keys named replace the scenario's; the others stay its own.
        ({"params": MASS}, {**OWN, "params": MASS}),
        ({"qpos_noise": 0.0}, {**OWN, "qpos_noise": 0.0}),
        ({"params": []}, {"qpos": QPOS, "qpos_noise": 0.01}),
        ({"qvel_noise": 0.05}, {**OWN, "qvel_noise": 0.05}),
        ({}, OWN),
    ],
)
def test_options_override_only_the_keys_they_name(options, same_as):
    def scenario(reset):
        return simloop.Scenario(scene="tests/scenes/pusht.xml", steps=40, reset=reset)

    def episode(env, **reset):
        obs, _ = env.reset(seed=4, **reset)
        return [obs] + [env.step([0.8, 0.2])[0] for _ in range(3)]

    env = ScenarioEnv(scenario(OWN), control_every=10)
    shaped = episode(env, options=options)
    assert abs(column(env, shaped[0], "tblock_x") - 0.3) <= 0.01  # the scenario's own qpos: not named
    expected = episode(ScenarioEnv(scenario(same_as), control_every=10))
    assert all(np.array_equal(a, b) for a, b in zip(shaped, expected))
    # A key named with another value than the scenario's changes the episode.
    own = episode(env)
    assert all(np.array_equal(a, b) for a, b in zip(shaped, own)) == (options == {})
