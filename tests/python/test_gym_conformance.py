"""Gymnasium conformance: the checkers clean, every vectorization through
autoresets, infos in Gymnasium's vector layout (the same as SyncVectorEnv's
over single envs) in every autoreset mode, make_vec's keywords, reset
options, and each wrapper Gymnasium ships for Box spaces over both envs."""

import warnings

import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium")

import simloop  # noqa: E402,F401  (registers the ids)
from gymnasium.vector import AutoresetMode, SyncVectorEnv  # noqa: E402
from simloop.gym import PUSHT_SCENARIO, ScenarioEnv, ScenarioVectorEnv  # noqa: E402

SHORT = dict(steps=30, control_every=10)  # three decisions an episode: autoresets come quickly


def same_infos(a, b, where=""):
    """Two vector infos alike: the same keys, arrays of the same dtype and values."""
    assert set(a) == set(b), (where, sorted(a), sorted(b))
    for key in a:
        x, y = a[key], b[key]
        if isinstance(x, dict):
            same_infos(x, y, f"{where}.{key}")
            continue
        assert isinstance(x, np.ndarray) and isinstance(y, np.ndarray), (where, key)
        assert x.dtype == y.dtype and x.shape == y.shape, (where, key, x.dtype, y.dtype)
        if x.dtype == object:
            for u, v in zip(x, y):
                assert (u is None and v is None) or np.array_equal(np.asarray(u), np.asarray(v)), (where, key)
        else:
            assert np.array_equal(x, y), (where, key, x, y)


@pytest.mark.parametrize("env_id", ["simloop/Chapter-v0", "simloop/PushT-v0"])
def test_check_env_and_the_passive_checker_are_clean(env_id):
    from gymnasium.utils.env_checker import check_env

    with warnings.catch_warnings():
        warnings.simplefilter("error")  # any remark fails
        check_env(gymnasium.make(env_id, **SHORT).unwrapped)
        env = gymnasium.make(env_id, **SHORT)  # with Gymnasium's PassiveEnvChecker and OrderEnforcing
        env.reset(seed=0)
        for _ in range(7):
            _, _, terminated, truncated, _ = env.step(env.action_space.sample())
            if terminated or truncated:
                env.reset()


@pytest.mark.parametrize("env_id", ["simloop/Chapter-v0", "simloop/PushT-v0"])
def test_every_vectorization_runs_through_autoresets_and_agrees(env_id):
    """info["seed"] is a uint64 (>= 2**63 half the time): an int broke the sync and async modes' info arrays."""
    runs = {}
    for mode in ("sync", "async", "vector_entry_point"):
        envs = gymnasium.make_vec(env_id, num_envs=3, vectorization_mode=mode, **SHORT)
        try:
            obs, infos = envs.reset(seed=[2**64 - 1, 2**63, 7])
            steps = [(obs, infos)]
            actions = np.random.default_rng(1).uniform(-1, 1, size=(10,) + envs.action_space.shape)
            for action in actions:
                steps.append(envs.step(action))
        finally:
            envs.close()
        runs[mode] = steps
    assert any(step[3].any() for step in runs["vector_entry_point"][1:])  # autoresets happened
    assert runs["sync"][0][1]["seed"].dtype == np.uint64
    for mode in ("sync", "async"):
        for k, (ours, theirs) in enumerate(zip(runs["vector_entry_point"], runs[mode])):
            for x, y in zip(ours[:-1], theirs[:-1]):
                assert np.array_equal(x, y), (mode, k)
            same_infos(ours[-1], theirs[-1], f"{mode} step {k}")


@pytest.mark.parametrize("mode", list(AutoresetMode))
@pytest.mark.parametrize("threads", [1, 2])
@pytest.mark.parametrize("hooks", [True, False])  # without: episodes end by the scenario's length alone
def test_the_vector_env_is_sync_vector_env_over_single_envs_in_every_autoreset_mode(mode, threads, hooks):
    n, kwargs = 4, dict(control_every=10, steps=60, max_episode_steps=4, reward=lambda o, a, p: float(p[0] - o[0]))
    if not hooks:
        kwargs = dict(control_every=30, steps=60)
    ours = ScenarioVectorEnv(PUSHT_SCENARIO, n, autoreset_mode=mode, threads=threads, **kwargs)
    theirs = SyncVectorEnv([lambda: ScenarioEnv(PUSHT_SCENARIO, **kwargs)] * n, autoreset_mode=mode)
    assert ours.metadata["autoreset_mode"] == mode
    actions = np.random.default_rng(3).uniform(-1, 1, size=(14, n, 2))
    for env in (ours, theirs):
        env.reset(seed=11)
    ended = np.zeros(n, dtype=bool)
    for k, action in enumerate(actions):
        if mode == AutoresetMode.DISABLED and ended.any():
            a, b = (env.reset(options={"reset_mask": ended.copy()}) for env in (ours, theirs))
            assert np.array_equal(a[0], b[0]), k
            same_infos(a[1], b[1], f"reset {k}")
        a, b = ours.step(action), theirs.step(action)
        for x, y in zip(a[:-1], b[:-1]):
            assert np.array_equal(x, y), (mode, k)
        same_infos(a[-1], b[-1], f"step {k}")
        ended = a[2] | a[3]
        if ended.any() and mode == AutoresetMode.SAME_STEP:
            assert "final_obs" in a[-1] and "final_info" in a[-1]
    assert "ended_by" in a[-1] or ended.any() or mode != AutoresetMode.NEXT_STEP
    theirs.close()


def test_stepping_an_ended_env_without_autoreset_is_refused():
    venv = ScenarioVectorEnv(PUSHT_SCENARIO, 2, autoreset_mode="Disabled", max_episode_steps=1)
    venv.reset(seed=0)
    _, _, _, truncated, infos = venv.step(np.zeros((2, 2)))
    assert truncated.all() and list(infos["ended_by"]) == ["max_episode_steps"] * 2
    with pytest.raises(ValueError, match="env 0 has ended: reset it first"):
        venv.step(np.zeros((2, 2)))
    venv.reset(options={"reset_mask": np.array([True, True])})
    venv.step(np.zeros((2, 2)))


def test_a_step_limit_set_after_the_env_was_made_counts_the_steps_already_taken():
    venv = ScenarioVectorEnv(PUSHT_SCENARIO, 2)
    venv.reset(seed=0)
    for _ in range(2):
        assert not venv.step(np.zeros((2, 2)))[3].any()
    venv.max_episode_steps = 3
    _, _, _, truncated, infos = venv.step(np.zeros((2, 2)))  # the third
    assert truncated.all() and list(infos["ended_by"]) == ["max_episode_steps"] * 2


def test_a_refused_step_changes_nothing_even_with_an_autoreset_due():
    def run(refuse_first):
        venv = ScenarioVectorEnv(PUSHT_SCENARIO, 2, max_episode_steps=1)
        venv.reset(seed=3)
        venv.step(np.zeros((2, 2)))  # both end: the next step resets them
        if refuse_first:
            with pytest.raises(ValueError, match=r"^env 1: action 0 is not finite, got nan$"):
                venv.step(np.array([[0.0, 0.0], [np.nan, 0.0]]))
        return venv.step(np.full((2, 2), 0.5))

    refused, clean = run(True), run(False)
    np.testing.assert_array_equal(refused[0], clean[0])
    assert refused[4]["seed"].tolist() == clean[4]["seed"].tolist()


@pytest.mark.parametrize("n", [1, 2])
def test_a_refused_step_changes_nothing(n):
    def run(refuse):
        venv = ScenarioVectorEnv(PUSHT_SCENARIO, n)
        venv.reset(seed=3)
        venv.step(np.zeros((n, 2)))
        if refuse:
            bad = np.zeros((n, 2))
            bad[n - 1, 1] = np.inf
            with pytest.raises(ValueError, match=rf"^env {n - 1}: action 1 is not finite, got inf$"):
                venv.step(bad)
        return venv.step(np.full((n, 2), 0.5))

    refused, clean = run(True), run(False)
    for x, y in zip(refused[:-1], clean[:-1]):
        np.testing.assert_array_equal(x, y)
    same_infos(refused[-1], clean[-1])


@pytest.mark.parametrize("mode", ["NextStep", "SameStep"])
def test_rewards_handed_out_stay_as_they_were(mode):
    # A batched reward may return a view of its arguments (here the next
    # observations, which the env keeps and writes into on later steps).
    first_column = simloop.gym.batched(lambda obs, action, next_obs: next_obs[:, 0])
    venv = ScenarioVectorEnv(PUSHT_SCENARIO, 2, reward=first_column, max_episode_steps=2, autoreset_mode=mode)
    venv.reset(seed=1)
    handed_out = [venv.step(np.full((2, 2), 0.3))[1] for _ in range(5)]
    kept = [r.copy() for r in handed_out]
    venv.step(np.full((2, 2), 0.3))
    for before, now in zip(kept, handed_out):
        np.testing.assert_array_equal(now, before)


def test_make_vec_takes_the_keywords_gymnasium_passes():
    envs = gymnasium.make_vec("simloop/PushT-v0", num_envs=2, max_episode_steps=3)
    envs.reset(seed=0)
    flags = [envs.step(np.zeros((2, 2)))[3] for _ in range(3)]
    assert not flags[0].any() and not flags[1].any() and flags[2].all()
    venv = gymnasium.make_vec("simloop/PushT-v0", num_envs=2, autoreset_mode="SameStep")
    assert venv.metadata["autoreset_mode"] == AutoresetMode.SAME_STEP
    single = gymnasium.make("simloop/PushT-v0", max_episode_steps=2)  # Gymnasium's TimeLimit
    single.reset(seed=0)
    assert [single.step(np.zeros(2))[3] for _ in range(2)] == [False, True]


def test_info_says_step_time_seed_and_why_an_episode_ended():
    env = ScenarioEnv(PUSHT_SCENARIO, control_every=10, steps=25)
    _, info = env.reset(seed=2**64 - 1)
    assert info == {"step": 0, "time": 0.0, "seed": np.uint64(2**64 - 1)} and type(info["seed"]) is np.uint64
    ends = [env.step(np.zeros(2))[4] for _ in range(3)]
    assert [i["step"] for i in ends] == [10, 20, 25] and ends[1]["time"] == pytest.approx(0.04)
    assert "ended_by" not in ends[1] and ends[2]["ended_by"] == "length"
    with pytest.raises(ValueError, match="the episode has ended: reset"):
        env.step(np.zeros(2))
    diverging = ScenarioEnv(simloop.Scenario.chapter(), timestep=1.0, control_every=10)
    diverging.reset(seed=0)
    for _ in range(50):
        _, _, terminated, truncated, info = diverging.step(np.ones(1))
        if terminated or truncated:
            break
    assert terminated and info["ended_by"] == "warning" and info["warnings"]


@pytest.mark.parametrize(
    "options, error, message",
    [
        ({"qpos_jitter": 1}, ValueError, "options: unknown key 'qpos_jitter'"),
        ({"b": 1, "a": 2}, ValueError, "options: unknown keys 'a', 'b'"),
        ([("reset_mask", 1)], TypeError, "options must be a dict or None"),
    ],
)
def test_reset_options_are_never_silently_ignored(options, error, message):
    for env in (ScenarioEnv(PUSHT_SCENARIO), ScenarioVectorEnv(PUSHT_SCENARIO, 2)):
        with pytest.raises(error, match=message.replace("(", r"\(")):
            env.reset(seed=0, options=options)
        env.reset(seed=0)  # still usable


@pytest.mark.parametrize(
    "mask, message",
    [
        (np.array([True]), r"shape \(2,\)"),
        (np.array([1, 0]), "bool array"),
        ([True, False], "bool array"),
        (np.array([False, False]), "resets no env"),
    ],
)
def test_a_bad_reset_mask_is_named_and_the_env_stays_usable(mask, message):
    venv = ScenarioVectorEnv(PUSHT_SCENARIO, 2)
    with pytest.raises(ValueError, match="the first reset must reset every env"):
        venv.reset(seed=0, options={"reset_mask": np.array([True, False])})
    obs, _ = venv.reset(seed=0)
    with pytest.raises(ValueError, match=message):
        venv.reset(options={"reset_mask": mask})
    after, _, _, _, _ = venv.step(np.zeros((2, 2)))
    partial, infos = venv.reset(seed=[None, 5], options={"reset_mask": np.array([False, True])})
    fresh, _ = ScenarioEnv(PUSHT_SCENARIO).reset(seed=5)
    assert np.array_equal(partial[0], after[0]) and np.array_equal(partial[1], fresh)  # env 0 kept its episode
    assert list(infos["_seed"]) == [False, True] and infos["seed"][1] == np.uint64(5)


def _single_wrappers():
    w = gymnasium.wrappers
    return [
        (w.ClipAction, {}),
        (w.RescaleAction, dict(min_action=-0.5, max_action=0.5)),
        (w.TransformAction, dict(func=lambda a: 0.5 * a, action_space=None)),
        (w.StickyAction, dict(repeat_action_probability=0.25)),
        (w.RepeatAction, dict(num_repeats=2)),
        (w.DiscretizeAction, dict(bins=5)),
        (w.ClipReward, dict(min_reward=-1.0, max_reward=1.0)),
        (w.TransformReward, dict(func=lambda r: 2 * r)),
        (w.NormalizeReward, {}),
        (w.NormalizeObservation, {}),
        (w.DtypeObservation, dict(dtype=np.float32)),
        (w.FlattenObservation, {}),
        (w.FrameStackObservation, dict(stack_size=3)),
        (w.DelayObservation, dict(delay=2)),
        (w.MaxAndSkipObservation, dict(skip=2)),
        (w.TimeAwareObservation, {}),
        (w.ReshapeObservation, dict(shape="column")),
        (w.TransformObservation, dict(func=lambda o: o * 2.0, observation_space=None)),
        (w.TimeLimit, dict(max_episode_steps=2)),
        (w.RecordEpisodeStatistics, {}),
        (w.Autoreset, {}),
        (w.PassiveEnvChecker, {}),
        (w.OrderEnforcing, {}),
    ]


def _vector_wrappers():
    v = gymnasium.wrappers.vector
    return [
        (v.ClipAction, {}),
        (v.RescaleAction, dict(min_action=-0.5, max_action=0.5)),
        (v.TransformAction, dict(func=lambda a: 0.5 * a)),
        (v.ClipReward, dict(min_reward=-1.0, max_reward=1.0)),
        (v.TransformReward, dict(func=lambda r: 2 * r)),
        (v.NormalizeReward, {}),
        (v.NormalizeObservation, {}),
        (v.DtypeObservation, dict(dtype=np.float32)),
        (v.FlattenObservation, {}),
        (v.ReshapeObservation, dict(shape="column")),
        (v.TransformObservation, dict(func=lambda o: o * 2.0)),
        (v.RecordEpisodeStatistics, {}),
        (v.DictInfoToList, {}),
    ]


# DtypeObservation(float32) casts the float64 space's bounds, as for any
# float64 environment, and Gymnasium says so: its remark, not ours.
CAST = "ignore:.*precision lowered by casting to float32"

# Not run here: the rendering wrappers (test_render.py runs
# AddRenderObservation and RenderCollection), wrappers for Dict or image
# observations, and RescaleObservation / DiscretizeObservation,
# which need a bounded observation space (a simloop observation is any finite value).


@pytest.mark.filterwarnings(CAST)
@pytest.mark.parametrize("env_id", ["simloop/Chapter-v0", "simloop/PushT-v0"])
@pytest.mark.parametrize("wrapper, kwargs", _single_wrappers(), ids=lambda v: getattr(v, "__name__", ""))
def test_each_box_wrapper_runs_over_the_single_env(env_id, wrapper, kwargs):
    # TimeAwareObservation reads the episode's step limit from the spec.
    env = gymnasium.make(env_id, max_episode_steps=5, **SHORT)
    if kwargs.get("shape") == "column":
        kwargs = dict(shape=(env.observation_space.shape[0], 1))
    env = wrapper(env, **kwargs)
    obs, _ = env.reset(seed=0)
    assert env.observation_space.contains(obs)
    env.action_space.seed(0)
    for _ in range(8):
        obs, reward, terminated, truncated, _ = env.step(env.action_space.sample())
        assert env.observation_space.contains(np.asarray(obs, dtype=env.observation_space.dtype))
        if (terminated or truncated) and wrapper is not gymnasium.wrappers.Autoreset:
            env.reset()
    env.close()


@pytest.mark.filterwarnings(CAST)
@pytest.mark.parametrize("env_id", ["simloop/Chapter-v0", "simloop/PushT-v0"])
@pytest.mark.parametrize("wrapper, kwargs", _vector_wrappers(), ids=lambda v: getattr(v, "__name__", ""))
def test_each_box_wrapper_runs_over_the_vector_env(env_id, wrapper, kwargs):
    envs = gymnasium.make_vec(env_id, num_envs=3, **SHORT)
    if kwargs.get("shape") == "column":
        kwargs = dict(shape=(envs.single_observation_space.shape[0], 1))
    envs = wrapper(envs, **kwargs)
    obs, _ = envs.reset(seed=0)
    envs.action_space.seed(0)
    for _ in range(8):
        obs, rewards, terminated, truncated, infos = envs.step(envs.action_space.sample())
        assert np.asarray(obs).shape[0] == 3 and rewards.shape == (3,)
    envs.close()
