"""Gymnasium's v5 tasks registered as simloop/<Task>-v5 (simloop/gym_tasks.py, issue 35 item 2): each a scenario over
Gymnasium's own XML (read from the installed gymnasium package) with Gymnasium's keyword arguments, stepping as
Gymnasium's own env does, bit for bit."""

import inspect
import os

import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium", reason="needs gymnasium (the gym extra)")
gym_tasks = pytest.importorskip("simloop.gym_tasks", reason="needs gymnasium (the gym extra)")
import simloop  # noqa: E402

# Reacher and Pusher draw their start and goal in an on_reset hook, with no reset_noise_scale: tested apart below.
GOAL_IDS = ["Reacher-v5", "Pusher-v5"]
IDS = [f"{task}-v5" for task in gym_tasks.TASKS if f"{task}-v5" not in GOAL_IDS]


def gymnasium_env(env_id: str, **kwargs):
    try:
        env = gymnasium.make(env_id, **kwargs)
    except Exception as e:  # Gymnasium's MuJoCo envs need the mujoco package and imageio
        pytest.skip(f"Gymnasium's {env_id} does not make here: {type(e).__name__}: {e}")
    import mujoco

    if simloop.MUJOCO_VERSION.split()[-1] != mujoco.__version__:  # the bits are one MuJoCo build's
        pytest.skip(f"Gymnasium steps mujoco {mujoco.__version__}, simloop {simloop.MUJOCO_VERSION}")
    return env


@pytest.fixture(autouse=True)
def _in_tmp(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # MuJoCo's default handler writes Gymnasium's load warnings to MUJOCO_LOG.TXT here


def assert_same_info(ours, theirs, k):
    """Gymnasium's info keys are in simloop's info, each the same value, bit for bit (simloop's own step, time and
    seed beside them)."""
    assert set(theirs) <= set(ours), (k, set(theirs) - set(ours))
    for key, value in theirs.items():
        assert np.asarray(ours[key]).tolist() == np.asarray(value).tolist(), (k, key)


def step_both(theirs, ours, steps=1000, noisy=False):
    """Both envs reset together (with seed k when an episode ends at step k) and take the same `steps` seeded
    actions (float64, inside the ctrlrange); noisy: Gymnasium's noisy reset state is copied into simloop's env
    (reset options qpos and qvel; a free joint's quaternion normalised first in Gymnasium's env too, as simloop
    normalises a given qpos and Gymnasium's set_state does not). Gymnasium writes ctrl and calls mj_step frame_skip
    times; simloop takes the same steps (the first begun as the observation's first half, stepper.hpp), the same
    bits. The observation, reward, termination and Gymnasium's info keys are computed from the same doubles with
    Gymnasium's arithmetic in Gymnasium's order, batched: equal bit for bit, not within a tolerance. Returns the
    episodes started."""
    nu = theirs.unwrapped.model.nu
    actions = np.random.default_rng(35).uniform(-1.0, 1.0, size=(steps, nu))
    episodes, ended = 0, True
    for k, action in enumerate(actions):
        if ended:
            their_obs, their_info = theirs.reset(seed=k)
            model, data = theirs.unwrapped.model, theirs.unwrapped.data
            if noisy and model.jnt_type[0] == 0:  # mjJNT_FREE
                import mujoco

                mujoco.mju_normalize4(data.qpos[3:7])
                mujoco.mj_forward(model, data)
                their_obs = theirs.unwrapped._get_obs()
            options = {"qpos": data.qpos.tolist(), "qvel": data.qvel.tolist()} if noisy else None
            our_obs, our_info = ours.reset(seed=k, options=options)
            assert our_obs.tolist() == their_obs.tolist()
            assert_same_info(our_info, their_info, k)
            episodes += 1
        their_obs, their_reward, their_terminated, their_truncated, their_info = theirs.step(action)
        our_obs, our_reward, our_terminated, our_truncated, our_info = ours.step(action)
        assert our_obs.tolist() == their_obs.tolist(), k
        assert our_reward == their_reward, k
        assert (our_terminated, our_truncated) == (their_terminated, their_truncated), k
        assert_same_info(our_info, their_info, k)
        ended = their_terminated or their_truncated
    return episodes


@pytest.mark.parametrize("env_id", IDS)
def test_a_task_steps_as_gymnasiums_bit_for_bit(env_id):
    # Both start at the XML's initial state (reset_noise_scale=0: Gymnasium's noise is 0 * its draws).
    theirs = gymnasium_env(env_id, reset_noise_scale=0.0)
    ours = gymnasium.make("simloop/" + env_id, reset_noise_scale=0.0)
    assert ours.observation_space.shape == theirs.observation_space.shape
    assert ours.spec.max_episode_steps == theirs.spec.max_episode_steps == 1000
    episodes = step_both(theirs, ours)
    # HalfCheetah, Swimmer and HumanoidStandup run their one episode to the TimeLimit (nothing ends them); the
    # others fall, or tip, and start again.
    assert episodes == 1 if env_id in ("HalfCheetah-v5", "Swimmer-v5", "HumanoidStandup-v5") else episodes > 1


@pytest.mark.parametrize("env_id", IDS)
def test_from_gymnasiums_noisy_reset_state_a_task_steps_as_gymnasiums(env_id):
    theirs = gymnasium_env(env_id)  # Gymnasium's own reset noise, its state copied into simloop's env
    ours = gymnasium.make("simloop/" + env_id, reset_noise_scale=0.0)
    step_both(theirs, ours, steps=300, noisy=True)


@pytest.mark.parametrize("env_id", IDS + GOAL_IDS)
def test_the_keyword_arguments_and_defaults_are_gymnasiums(env_id):
    theirs = gymnasium_env(env_id)
    signature = inspect.signature(type(theirs.unwrapped).__init__).parameters
    ours = gym_tasks.TASKS[env_id[: -len("-v5")]].defaults
    rendering = {"default_camera_config"}  # (simloop's pictures take render_mode, width, height)
    assert set(ours) == {n for n in signature if n not in ("self", "kwargs")} - rendering
    for name, value in ours.items():
        assert value == signature[name].default, name


@pytest.mark.parametrize("env_id", IDS + GOAL_IDS)
def test_each_id_passes_gymnasiums_env_checker(env_id):
    import warnings

    from gymnasium.utils.env_checker import check_env

    quiet = {} if env_id in GOAL_IDS else {"reset_noise_scale": 0.0}  # (the goal tasks: their hook's draws, seeded)
    with warnings.catch_warnings():  # InvertedPendulum's and Pusher's ctrlrange are +-3 and +-2: a remark
        warnings.filterwarnings("ignore", message=".*we recommend using a symmetric and normalized space")
        check_env(gymnasium.make("simloop/" + env_id, **quiet).unwrapped)


def test_the_keyword_arguments_change_the_task():
    # A weight changes the reward; a healthy range that nothing meets ends the first step; frame_skip is the
    # physics steps per decision; an excluded position is observed when asked for.
    def first_step(**kwargs):
        env = gymnasium.make("simloop/Hopper-v5", reset_noise_scale=0.0, **kwargs)
        env.reset(seed=0)
        obs, reward, terminated, _, info = env.step(np.full(3, 0.5))
        return obs, reward, terminated, info

    obs, reward, terminated, info = first_step()
    assert obs.shape == (11,) and not terminated and info["step"] == 4
    assert first_step(ctrl_cost_weight=1.0)[1] == pytest.approx(reward - 0.75 + 0.75e-3)
    assert first_step(healthy_z_range=(5.0, 6.0))[2]
    assert not first_step(healthy_z_range=(5.0, 6.0), terminate_when_unhealthy=False)[2]
    assert first_step(frame_skip=2)[3]["step"] == 2
    assert first_step(exclude_current_positions_from_observation=False)[0].shape == (12,)


def test_an_unknown_keyword_argument_is_a_type_error_naming_it():
    with pytest.raises(TypeError, match=r"^simloop/Hopper-v5 got unexpected keyword arguments 'healthy_zrange' \("):
        gymnasium.make("simloop/Hopper-v5", healthy_zrange=(0.5, 2.0))
    with pytest.raises(TypeError, match="'threads'"):  # the vector env's, not the single env's
        gymnasium.make("simloop/Hopper-v5", threads=2)
    with pytest.raises(TypeError, match="'reset_noise_scale'"):  # (Reacher's start is its hook's, as Gymnasium's)
        gymnasium.make("simloop/Reacher-v5", reset_noise_scale=0.1)


def test_xml_file_is_resolved_as_gymnasium_resolves_it():
    path = os.path.join(gym_tasks.assets_folder(), "hopper.xml")
    env = gymnasium.make("simloop/Hopper-v5", xml_file=path, reset_noise_scale=0.0)
    assert env.reset(seed=0)[0].shape == (11,)
    with pytest.raises(OSError, match="nothere.xml"):  # (as Gymnasium: OSError)
        gymnasium.make("simloop/Hopper-v5", xml_file="nothere.xml")


@pytest.mark.parametrize(
    ("env_id", "steps"),
    [
        ("simloop/HalfCheetah-v5", 1000),
        ("simloop/Hopper-v5", 1000),
        ("simloop/Reacher-v5", 50),
        ("simloop/Pusher-v5", 100),
    ],
)
def test_make_vec_steps_as_single_envs_on_simlooops_threads(env_id, steps):
    # gymnasium.make_vec takes the vector entry point (one ScenarioVectorEnv, 2 C++ threads): its batched
    # observations, rewards and flags are those of single envs reset with seeds 7, 8 and autoreset as it does
    # (Reacher's and Pusher's truncated at 50 and 100 steps, each new start drawn by their hook).
    quiet = {} if env_id[len("simloop/") :] in GOAL_IDS else {"reset_noise_scale": 0.0}
    envs = gymnasium.make_vec(env_id, num_envs=2, threads=2, **quiet)
    assert isinstance(envs, simloop.gym.ScenarioVectorEnv) and envs.max_episode_steps == steps
    singles = [gymnasium.make(env_id, **quiet) for _ in range(2)]
    obs, _ = envs.reset(seed=7)
    assert obs.tolist() == [env.reset(seed=7 + i)[0].tolist() for i, env in enumerate(singles)]
    np.testing.assert_array_equal(envs.observations, obs)
    actions = np.random.default_rng(1).uniform(-1.0, 1.0, size=(200, 2, envs.single_action_space.shape[0]))
    ended = [False, False]
    for k in range(200):
        obs, rewards, terminated, truncated, _ = envs.step(actions[k])
        for i, env in enumerate(singles):
            if ended[i]:  # next-step autoreset: the env is reset, its action ignored
                expected, reward, flags = env.reset()[0], 0.0, (False, False)
            else:
                expected, reward, *flags, _ = env.step(actions[k, i])
            assert (obs[i].tolist(), rewards[i], terminated[i], truncated[i]) == (expected.tolist(), reward, *flags)
            ended[i] = bool(terminated[i] or truncated[i])


def test_ants_contact_forces_are_observed_as_gymnasiums_and_not_zero():
    # Ant's observation ends with cfrc_ext of its 13 bodies (clipped to +-1), read where Gymnasium's MujocoEnv reads
    # them: after the decision's last mj_step, filled by mj_rnePostConstraint (no MuJoCo step computes them).
    theirs = gymnasium_env("Ant-v5", reset_noise_scale=0.0)
    ours = gymnasium.make("simloop/Ant-v5", reset_noise_scale=0.0)
    assert ours.unwrapped.observation_names[27] == "torso_cfrc_ext0"
    actions = np.random.default_rng(3).uniform(-1.0, 1.0, size=(50, 8))
    theirs.reset(seed=0)
    ours.reset(seed=0)
    touching = 0
    for action in actions:
        their_obs = theirs.step(action)[0]
        our_obs = ours.step(action)[0]
        assert our_obs[27:].tolist() == their_obs[27:].tolist()
        touching += np.count_nonzero(our_obs[27:]) > 0
    assert touching > 10  # its legs on the floor


@pytest.mark.parametrize(("env_id", "qvel_normal"), [("HalfCheetah-v5", True), ("Hopper-v5", False)])
def test_reset_noise_has_gymnasiums_shapes_and_scales(env_id, qvel_normal):
    # Over 300 seeded resets: qpos off the XML's by uniform draws in +-scale (standard deviation scale / sqrt(3));
    # qvel likewise, or (HalfCheetah, Ant) by scale times a standard normal draw, which passes the scale at times.
    scale = 0.1
    quiet = gymnasium.make("simloop/" + env_id, reset_noise_scale=0.0).reset(seed=0)[0]
    env = gymnasium.make("simloop/" + env_id, reset_noise_scale=scale)
    nq = len(quiet) // 2  # the positions observed: planar robots have nq == nv, x left out
    noise = np.array([env.reset(seed=s)[0] - quiet for s in range(300)])
    positions, velocities = noise[:, :nq], noise[:, nq:]
    assert np.abs(positions).max() <= scale and np.std(positions) == pytest.approx(scale / np.sqrt(3), rel=0.1)
    if qvel_normal:
        assert np.abs(velocities).max() > scale and np.std(velocities) == pytest.approx(scale, rel=0.1)
    else:
        assert np.abs(velocities).max() <= scale and np.std(velocities) == pytest.approx(scale / np.sqrt(3), rel=0.1)
    assert not np.array_equal(env.reset(seed=1)[0], env.reset(seed=2)[0])  # each seed its own draws


def assert_same_infos(ours, theirs, k):
    """Gymnasium's vector infos (an array per key and its "_key" mask; final_info a dict of them) are in simloop's,
    the same values and masks, bit for bit."""
    assert set(theirs) <= set(ours), (k, set(theirs) - set(ours))
    for key, value in theirs.items():
        if isinstance(value, dict):
            assert_same_infos(ours[key], value, k)
        elif key == "final_obs":
            assert [np.asarray(o).tolist() for o in ours[key]] == [np.asarray(o).tolist() for o in value], k
        else:
            assert ours[key].dtype == value.dtype and ours[key].tolist() == value.tolist(), (k, key)


@pytest.mark.parametrize(
    ("env_id", "mode"),
    [("Hopper-v5", "NextStep"), ("Hopper-v5", "SameStep"), ("Ant-v5", "NextStep"), ("Humanoid-v5", "NextStep")],
)
def test_make_vec_infos_are_gymnasiums_sync_vector_envs(env_id, mode):
    # Gymnasium's info keys in its vector layout, with the autoresets of a falling robot: the reset envs' keys are
    # those of their reset (NextStep), or the ended episode's are in final_info (SameStep); Humanoid's tendon
    # lengths are rows of an array. Made from the batch's arrays, the same as SyncVectorEnv over Gymnasium's envs.
    gymnasium_env(env_id)  # (skips where Gymnasium's own env does not make)
    from gymnasium.vector import AutoresetMode

    kwargs = {"num_envs": 2, "reset_noise_scale": 0.0}
    theirs = gymnasium.make_vec(
        env_id, vectorization_mode="sync", vector_kwargs={"autoreset_mode": AutoresetMode(mode)}, **kwargs
    )
    ours = gymnasium.make_vec("simloop/" + env_id, autoreset_mode=mode, threads=2, **kwargs)
    their_obs, their_infos = theirs.reset(seed=7)
    our_obs, our_infos = ours.reset(seed=7)
    assert our_obs.tolist() == their_obs.tolist()
    assert_same_infos(our_infos, their_infos, -1)
    actions = np.random.default_rng(5).uniform(-1.0, 1.0, size=(150,) + ours.action_space.shape)
    resets = 0
    for k, action in enumerate(actions):
        their_obs, their_rewards, their_terminated, their_truncated, their_infos = theirs.step(action)
        our_obs, our_rewards, our_terminated, our_truncated, our_infos = ours.step(action)
        assert our_obs.tolist() == their_obs.tolist(), k
        assert (our_rewards.tolist(), our_terminated.tolist()) == (their_rewards.tolist(), their_terminated.tolist())
        assert our_truncated.tolist() == their_truncated.tolist(), k
        assert_same_infos(our_infos, their_infos, k)
        resets += int(their_terminated.sum())
    assert resets >= 2  # (both envs fell at least once: the autoreset's infos were compared)


@pytest.mark.parametrize("env_id", ["Hopper-v5", "HalfCheetah-v5", "Ant-v5", "InvertedPendulum-v5"])
def test_the_default_view_is_gymnasiums_default_camera(env_id, monkeypatch):
    # Gymnasium's render_mode "rgb_array" picture is taken by a free camera set from its default_camera_config
    # (distance, lookat, elevation; trackbodyid does nothing to a free camera), else at the median of the geoms:
    # simloop's default view is that camera, so the pictures at the reset state are the same but for shading (the
    # two renderers' shadow maps and multisampling), and further from each other than from another view.
    theirs = gymnasium_env(env_id, render_mode="rgb_array", width=160, height=120, reset_noise_scale=0.0)
    monkeypatch.setenv("MUJOCO_GL", "egl")  # (Gymnasium's first choice, glfw, needs a screen)
    theirs.reset(seed=0)
    try:
        their_picture = theirs.render()
    except Exception as e:
        pytest.skip(f"Gymnasium cannot render here: {type(e).__name__}: {e}")
    try:
        ours = gymnasium.make(
            "simloop/" + env_id, render_mode="rgb_array", width=160, height=120, reset_noise_scale=0.0
        )
    except RuntimeError as e:
        pytest.skip(f"simloop cannot render here: {e}")
    ours.reset(seed=0)
    near = np.abs(ours.render().astype(int) - their_picture).mean()  # (levels of 255, a pixel's colour)
    elsewhere = gymnasium.make(
        "simloop/" + env_id, render_mode="rgb_array", width=160, height=120, view={"distance": 9}
    )
    elsewhere.reset(seed=0)
    far = np.abs(elsewhere.render().astype(int) - their_picture).mean()  # (another view: it can fail)
    assert near < 2.0 and far > 4 * near, (near, far)


@pytest.mark.parametrize(("env_id", "episodes"), [("Reacher-v5", 20), ("Pusher-v5", 10)])
def test_a_goal_task_steps_as_gymnasiums_bit_for_bit(env_id, episodes):
    # Gymnasium's reset_model draws the start and the goal; on_reset=None leaves simloop's start to the options, given
    # Gymnasium's qpos and qvel. Both compute the reward after the step (v5: do_simulation first), from xpos as the
    # last mj_step left it; the norms are np.linalg.norm's BLAS dot (vecdot): bit for bit, no tolerance.
    theirs = gymnasium_env(env_id)
    ours = gymnasium.make("simloop/" + env_id, on_reset=None)
    assert ours.observation_space.shape == theirs.observation_space.shape
    assert ours.spec.max_episode_steps == theirs.spec.max_episode_steps  # (50 and 100: 1,000 steps, many episodes)
    assert step_both(theirs, ours, noisy=True) == episodes


def starts(env_id, seeds, **kwargs):
    env = gymnasium.make("simloop/" + env_id, **kwargs)
    return np.array([env.reset(seed=s)[0] for s in seeds])


def test_reachers_hook_draws_its_goal_inside_gymnasiums_disc_per_seed():
    # The target (qpos[-2:], observed at 4:6) drawn uniform in +-0.2 until its norm is under 0.2: over 300 seeds all
    # inside the disc (a square's draws would leave it 21 % of the time), spread over it; the arm's angles off the
    # XML's (0) by at most 0.1, its qvel (6:8) by 0.005. The same seed, the same start, in a vector env too.
    obs = starts("Reacher-v5", range(300))
    goals = obs[:, 4:6]
    assert np.linalg.norm(goals, axis=1).max() < 0.2 and np.abs(goals).max() > 0.18
    assert np.std(goals) > 0.08 and len(np.unique(goals[:, 0])) == 300
    angles = np.arctan2(obs[:, 2:4], obs[:, 0:2])
    assert np.abs(angles).max() <= 0.1 and np.abs(obs[:, 6:8]).max() <= 0.005
    assert starts("Reacher-v5", [7, 7, 8]).tolist() == obs[[7, 7, 8]].tolist()
    envs = gymnasium.make_vec("simloop/Reacher-v5", num_envs=2, threads=2)
    assert envs.reset(seed=7)[0].tolist() == obs[[7, 8]].tolist()
    assert starts("Reacher-v5", [7], on_reset=None)[0, 4:6].tolist() == [0.1, -0.1]  # (the XML's start: its refs)


def test_pushers_hook_draws_its_object_away_from_the_goal_per_seed():
    # The object (qpos[-4:-2]: y, x off its XML's place) drawn in [-0.3, 0) x [-0.2, 0.2) until farther than 0.17
    # from the goal (at the XML's place): over 300 seeds all farther (a box's draws would be nearer 38 % of the time);
    # observed are the xpos of tips_arm (14:17), object (17:20) and goal (20:23). The arm starts at the XML's qpos.
    obs = starts("Pusher-v5", range(300))
    offset = obs[:, 17:19] - obs[:, 20:22]
    assert np.linalg.norm(offset, axis=1).min() > 0.17 and np.linalg.norm(offset, axis=1).min() < 0.18
    assert -0.3 <= offset[:, 1].min() and offset[:, 1].max() < 0 and np.abs(offset[:, 0]).max() < 0.2
    assert np.abs(obs[:, :7]).max() == 0 and 0 < np.abs(obs[:, 7:14]).max() <= 0.005
    assert starts("Pusher-v5", [3, 3]).tolist() == obs[[3, 3]].tolist()
    assert not np.array_equal(obs[3], obs[4])
