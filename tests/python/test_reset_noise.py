"""Reset noise a trainer shapes (issue 35): a width per coordinate or by joint name, uniform or normal, the same from
a scenario's reset=, an env's reset options and a vector env's, drawn from the episode's seed."""

import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium")

import simloop  # noqa: E402
from simloop.gym import PUSHT_SCENARIO, ScenarioEnv, ScenarioVectorEnv  # noqa: E402

# PushT: the T-block's free joint (unnamed: 7 qpos, 6 qvel), then slide_x and slide_y.
QPOS0 = [0.2, 0.0, 0.02, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0]
# HalfCheetah's and Ant's shape on PushT's slides: qpos uniform, qvel normal.
SHAPED = {
    "qpos_noise": {"slide_x": 0.05},
    "qvel_noise": [0, 0, 0, 0, 0, 0, 0.3, 0.3],
    "qvel_noise_distribution": "normal",
}


def column(env, obs, name):
    return obs[env.observation_names.index(name)]


def test_noise_by_joint_and_coordinate_leaves_the_others_exact():
    env = ScenarioEnv(PUSHT_SCENARIO)
    a, again, other = (env.reset(seed=seed, options=SHAPED)[0] for seed in (3, 3, 4))
    assert np.array_equal(a, again) and not np.array_equal(a, other)
    assert 0 < abs(column(env, a, "slide_x_pos")) <= 0.05
    assert column(env, a, "slide_y_pos") == 0.0  # no width: exact
    assert column(env, a, "tblock_x") == 0.2 and column(env, a, "tblock_vy") == 0.0
    assert column(env, a, "slide_x_vel") != 0.0 and column(env, a, "slide_y_vel") != 0.0


def test_a_run_an_episode_and_a_vector_env_draw_alike():
    shaped = simloop.Scenario(scene="tests/scenes/pusht.xml", steps=20, record={"joints": ["slide_x"]}, reset=SHAPED)
    plain = simloop.Scenario(scene="tests/scenes/pusht.xml", steps=20, record={"joints": ["slide_x"]})
    run = simloop.run_scenario(shaped, seed=8)
    obs, _ = ScenarioEnv(plain).reset(seed=8, options=SHAPED)
    assert tuple(run.column_names[2:]) == ("slide_x_pos", "slide_x_vel", "contacts")  # after step and time
    assert np.array_equal(obs, run.trajectory[0, 2:])
    venv = ScenarioVectorEnv(plain, num_envs=2)
    many, _ = venv.reset(seed=[8, 9], options=SHAPED)
    assert np.array_equal(many[0], obs) and not np.array_equal(many[1], obs)


def test_normal_noise_has_the_given_spread():
    env = ScenarioEnv(PUSHT_SCENARIO)
    env.reset(seed=0)
    draws = np.array(
        [column(env, env.reset(options=SHAPED)[0], "slide_x_vel") for _ in range(1500)]
    )  # seeded by the first reset: the same draws every time
    assert abs(draws.mean()) < 0.03  # standard error 0.008
    assert abs(draws.std() - 0.3) < 0.03
    assert 0.27 < np.mean(np.abs(draws) > 0.3) < 0.37  # a normal's 0.317; a uniform of that spread: 0.42


@pytest.mark.parametrize(
    "options, message",
    [
        (
            {"qpos_noise": [0.1, 0.1]},
            "reset.qpos_noise must hold the scene's nq = 9 widths (one per coordinate), got 2",
        ),
        ({"qvel_noise": {"slidex": 0.1}}, "reset.qvel_noise: no joint named 'slidex' (did you mean 'slide_x'?)"),
        ({"qvel_noise_distribution": "gauss"}, 'reset.qvel_noise_distribution: must be "uniform" or "normal"'),
        ({"qpos_noise": {"slide_x": -1}}, "reset.qpos_noise.slide_x: must not be negative"),
    ],
)
def test_bad_noise_is_one_line_naming_the_key(options, message):
    env = ScenarioEnv(PUSHT_SCENARIO)
    env.reset(seed=0)
    with pytest.raises(ValueError) as caught:
        env.reset(options=options)
    assert message in str(caught.value) and "\n" not in str(caught.value)
    with pytest.raises(ValueError, match=r"reset.qvel_noise must hold the scene's nv = 8 widths"):
        simloop.run_scenario(simloop.Scenario(scene="tests/scenes/pusht.xml", steps=2, reset={"qvel_noise": [1.0]}))
