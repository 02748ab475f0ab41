"""simloop.sb3: stable-baselines3's VecEnv over ScenarioVectorEnv. Its
steps against the vector env's own (SameStep autoresets) and against SB3's
DummyVecEnv over single environments, SB3's checks, the VecEnv methods SB3
calls, and a short PPO run. Skipped where stable-baselines3 is absent (it
brings torch, gigabytes: the test extras leave it out; CI installs it for
the PyPI build's pass, scripts/setup.sh)."""

import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium")
pytest.importorskip("stable_baselines3", reason="stable-baselines3 is not installed (the sb3 extra; it brings torch)")

import simloop  # noqa: E402, F401
from simloop.gym import PUSHT_SCENARIO, ScenarioEnv, ScenarioVectorEnv  # noqa: E402
from simloop.sb3 import SimloopVecEnv, make_vec_env  # noqa: E402
from stable_baselines3 import PPO  # noqa: E402
from stable_baselines3.common.env_checker import check_env  # noqa: E402
from stable_baselines3.common.vec_env import DummyVecEnv, VecEnv, VecMonitor  # noqa: E402

# The task the PPO test trains on: switching it is this line.
TRAIN_ID = "simloop/HalfCheetah-v5"

X = ScenarioEnv(PUSHT_SCENARIO).observation_names.index("tblock_x")


def progress(obs, action, next_obs):
    return float(next_obs[X] - obs[X])


# Episodes that end at different steps: the pusher past a mark ends one
# (terminated), 40 decisions end the others (truncated).
TERMINATE = [("pusher_x", ">", 0.02)]
KWARGS = dict(control_every=10, reward=progress, terminate=TERMINATE, max_episode_steps=40)


def same_bits(a, b):
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    return a.shape == b.shape and np.array_equal(a.view(np.uint64), b.view(np.uint64))


def actions(n, steps, seed=7):
    return np.random.default_rng(seed).uniform(-1, 1, (steps, n, 2)).astype(np.float32)


def test_make_vec_env_gives_sb3_a_vecenv_over_the_cpp_vector_env():
    venv = make_vec_env("simloop/PushT-v0", n_envs=3, seed=5, threads=2)
    assert isinstance(venv, VecMonitor) and isinstance(venv, VecEnv)
    inner = venv.venv
    assert isinstance(inner, SimloopVecEnv) and isinstance(inner.envs, ScenarioVectorEnv)
    assert inner.envs._threads == 2 and inner.envs.control_every == 10
    direct = ScenarioVectorEnv(PUSHT_SCENARIO, 3, control_every=10)
    assert same_bits(venv.reset(), direct.reset(seed=5)[0])  # seeds 5, 6, 7 as SB3's make_vec_env
    assert [info["seed"] for info in inner.reset_infos] == [5, 6, 7]
    venv.close()
    direct.close()


def test_sb3_checks_pass():
    check_env(gymnasium.make("simloop/PushT-v0"), warn=False)
    venv = make_vec_env("simloop/PushT-v0", n_envs=2, seed=0)
    obs = venv.reset()
    assert obs.shape == (2,) + venv.observation_space.shape and venv.observation_space.contains(obs[0])
    venv.step_async(np.stack([venv.action_space.sample() for _ in range(2)]))
    obs, rewards, dones, infos = venv.step_wait()
    assert rewards.dtype == np.float32 and dones.dtype == np.bool_ and len(infos) == 2
    venv.close()


def test_steps_equal_the_vector_envs_own_same_step_autoresets():
    n, steps = 4, 130
    sb3 = SimloopVecEnv(ScenarioVectorEnv(PUSHT_SCENARIO, n, autoreset_mode="SameStep", **KWARGS))
    direct = ScenarioVectorEnv(PUSHT_SCENARIO, n, autoreset_mode="SameStep", **KWARGS)
    sb3.seed(11)
    assert same_bits(sb3.reset(), direct.reset(seed=11)[0])
    ended = 0
    for a in actions(n, steps):
        obs, rewards, dones, infos = sb3.step(a)
        d_obs, d_rewards, terminated, truncated, d_infos = direct.step(a)
        assert same_bits(obs, d_obs) and same_bits(rewards, d_rewards.astype(np.float32))
        assert np.array_equal(dones, terminated | truncated)
        for i in np.flatnonzero(dones):
            assert same_bits(infos[i]["terminal_observation"], d_infos["final_obs"][i])
            assert infos[i]["TimeLimit.truncated"] == bool(truncated[i])
            assert infos[i]["ended_by"] == d_infos["final_info"]["ended_by"][i]
            ended += 1
    assert ended >= n  # every env ended at least once, at different steps
    sb3.close()
    direct.close()


def test_steps_infos_and_resets_equal_dummyvecenv_over_single_envs():
    n, steps = 3, 130
    sb3 = SimloopVecEnv(ScenarioVectorEnv(PUSHT_SCENARIO, n, autoreset_mode="SameStep", threads=2, **KWARGS))
    dummy = DummyVecEnv([lambda: ScenarioEnv(PUSHT_SCENARIO, **KWARGS) for _ in range(n)])
    for venv in (sb3, dummy):
        venv.seed(3)
    assert same_bits(sb3.reset(), dummy.reset())
    ended = set()
    for a in actions(n, steps):
        obs, rewards, dones, infos = sb3.step(a)
        d_obs, d_rewards, d_dones, d_infos = dummy.step(a)
        assert same_bits(obs, d_obs) and same_bits(rewards, d_rewards) and np.array_equal(dones, d_dones)
        assert rewards.dtype == d_rewards.dtype
        for info, d_info in zip(infos, d_infos):
            assert info.keys() == d_info.keys()
            for key in info:
                assert same_bits(info[key], d_info[key]) if key == "terminal_observation" else info[key] == d_info[key]
        for i in np.flatnonzero(dones):
            ended.add(str(infos[i]["ended_by"]))
            assert sb3.reset_infos[i].keys() == dummy.reset_infos[i].keys()
            assert all(sb3.reset_infos[i][k] == dummy.reset_infos[i][k] for k in sb3.reset_infos[i])
    assert ended == {"termination", "max_episode_steps"}
    sb3.close()
    dummy.close()


def test_options_per_env_reset_as_dummyvecenv_does():
    n = 3
    sb3 = SimloopVecEnv(ScenarioVectorEnv(PUSHT_SCENARIO, n, autoreset_mode="SameStep", control_every=10))
    dummy = DummyVecEnv([lambda: ScenarioEnv(PUSHT_SCENARIO, control_every=10) for _ in range(n)])
    for venv in (sb3, dummy):
        venv.seed(1)
        venv.set_options([{"qpos_noise": 0.01}, {}, {"qpos_noise": 0.02}])  # each env its own
    first = sb3.reset()
    assert same_bits(first, dummy.reset())
    for venv in (sb3, dummy):
        venv.seed(2)
        venv.set_options({"qvel_noise": 0.5})  # one dict for every env: one reset in C++
    assert same_bits(sb3.reset(), dummy.reset())
    assert same_bits(sb3.reset(), dummy.reset())  # options and seeds used once, as SB3's VecEnvs
    assert not same_bits(first[0], first[1])
    sb3.close()
    dummy.close()


def test_attributes_and_methods_as_sb3_asks_for_them():
    venv = SimloopVecEnv(ScenarioVectorEnv(PUSHT_SCENARIO, 3, autoreset_mode="SameStep", control_every=10))
    assert venv.get_attr("render_mode") == [None] * 3 and venv.render_mode is None
    assert venv.get_attr("control_every", indices=[0, 2]) == [10, 10]
    assert venv.env_is_wrapped(gymnasium.Wrapper) == [False] * 3
    venv.set_attr("max_episode_steps", 5)
    assert venv.envs.max_episode_steps == 5
    with pytest.raises(ValueError, match=r"^set_attr\('max_episode_steps'\) acts on every env .* got indices \[1\]$"):
        venv.set_attr("max_episode_steps", 6, indices=[1])
    with pytest.raises(AttributeError, match="no_such"):
        venv.get_attr("no_such")
    venv.reset()
    for _ in range(5):
        obs, rewards, dones, infos = venv.step(np.zeros((3, 2), dtype=np.float32))
    assert dones.all() and all(info["ended_by"] == "max_episode_steps" for info in infos)
    assert all(info["TimeLimit.truncated"] for info in infos)
    assert venv.env_method("render") == [None] * 3
    with pytest.raises(ValueError, match=r"^env_method\('reset'\) acts on every env"):
        venv.env_method("reset", indices=0)
    venv.close()


def test_render_gives_each_envs_picture():
    envs = ScenarioVectorEnv(
        PUSHT_SCENARIO, 2, autoreset_mode="SameStep", control_every=10, render_mode="rgb_array", width=64, height=48
    )
    venv = make_vec_env(PUSHT_SCENARIO, n_envs=2, seed=0, render_mode="rgb_array", width=64, height=48)
    assert venv.render_mode == "rgb_array"
    venv.reset()
    envs.reset(seed=0)
    pictures = venv.env_method("render")
    assert [p.shape for p in pictures] == [(48, 64, 3)] * 2
    assert all(np.array_equal(p, q) for p, q in zip(pictures, envs.render()))
    assert venv.render().shape == (96, 64, 3)  # SB3 tiles them (two rows of one)
    venv.close()
    envs.close()


def test_make_vec_env_refuses_what_it_cannot_do():
    with pytest.raises(ValueError, match=r"^make_vec_env: wrapper_class is for stable_baselines3's make_vec_env"):
        make_vec_env("simloop/PushT-v0", wrapper_class=gymnasium.Wrapper)
    with pytest.raises(ValueError, match=r"^make_vec_env: autoreset_mode is SB3's"):
        make_vec_env("simloop/PushT-v0", autoreset_mode="NextStep")
    with pytest.raises(ValueError, match=r"^make_vec_env: control_every given twice"):
        make_vec_env("simloop/PushT-v0", env_kwargs={"control_every": 5}, control_every=5)
    with pytest.raises(ValueError, match=r"^make_vec_env: 'CartPole-v1' is not a simloop env .* use stable_baselines3"):
        make_vec_env("CartPole-v1")
    with pytest.raises(TypeError, match=r"^env_id must be a Gymnasium id, a simloop.Scenario or a .toml path, got"):
        make_vec_env(3)
    with pytest.raises(ValueError, match=r"^n_envs"):
        make_vec_env("simloop/PushT-v0", n_envs=0)
    with pytest.raises(ValueError, match="autoreset_mode='SameStep'"):
        SimloopVecEnv(ScenarioVectorEnv(PUSHT_SCENARIO, 1))
    with pytest.raises(TypeError, match=r"^envs must be a simloop.gym.ScenarioVectorEnv"):
        SimloopVecEnv(gymnasium.make_vec("simloop/PushT-v0", vectorization_mode="sync"))


def test_ppo_trains_on_it_with_no_code_between():
    # Episodes of 100 decisions (Gymnasium's are 1,000), so that some end and are logged.
    venv = make_vec_env(TRAIN_ID, n_envs=4, seed=0, threads=2, max_episode_steps=100)
    model = PPO(
        "MlpPolicy", venv, n_steps=64, batch_size=64, n_epochs=1, policy_kwargs={"net_arch": [16]}, seed=0, device="cpu"
    )
    model.learn(total_timesteps=2000)
    assert model.num_timesteps >= 2000
    assert len(model.ep_info_buffer) > 0  # episodes ended and were logged by VecMonitor
    obs = venv.reset()
    action, _ = model.predict(obs, deterministic=True)
    assert action.shape == (4,) + venv.action_space.shape
    venv.close()
