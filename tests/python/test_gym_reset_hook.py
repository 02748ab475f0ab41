"""on_reset(rng, physics) (issue 35): a per-episode hook run at every reset (the vector env's autoresets and
reset_mask resets too) after the scenario's [reset] and the reset options, with a generator seeded from the
episode's seed and the start writable by name (qpos, qvel, act, ctrl, mocap_pos, mocap_quat); the first observation
observes what it wrote; a hook that raises leaves the env as it was. And what each start drew, in the info."""

import pickle

import numpy as np
import pytest
import simloop

gym = pytest.importorskip("simloop.gym", reason="needs gymnasium (the gym extra)")
gymnasium = pytest.importorskip("gymnasium")

# An arm's two hinges, a mocap target, a keyframe (as test_reset_start.py's).
REACH = """<mujoco>
  <worldbody>
    <body name="arm"><joint name="shoulder" axis="0 0 1" damping="0.1"/>
      <geom type="capsule" size="0.05" fromto="0 0 0 0.3 0 0"/>
      <body name="forearm" pos="0.3 0 0"><joint name="elbow" axis="0 0 1"/>
        <geom type="capsule" size="0.04" fromto="0 0 0 0.3 0 0"/></body></body>
    <body name="target" mocap="true" pos="0.5 0 0"><geom size="0.02" contype="0" conaffinity="0"/></body>
  </worldbody>
  <actuator><motor name="turn" joint="shoulder"/></actuator>
  <keyframe><key name="home" qpos="0.4 -0.8" qvel="0.1 0.2" mpos="0.1 0.2 0.3" mquat="1 0 0 0"/></keyframe>
</mujoco>"""
GOAL = {"body": "target", "uniform": [[0.2, -0.3, 0.0], [0.6, 0.3, 0.0]]}
RECORD = {"joints": ["shoulder", "elbow"], "bodies": ["forearm", "target"], "actuators": ["turn"]}
RESET = {"keyframe": "home", "qpos_noise": 0.01, "params": [{"kind": "damping", "name": "elbow", "uniform": [0, 1]}]}


@pytest.fixture
def scenario(tmp_path):
    path = tmp_path / "reach.xml"
    path.write_text(REACH)
    return simloop.Scenario(scene=str(path), steps=40, record=RECORD, reset=RESET)


def shape(rng, physics):
    """Bends the elbow by a drawn angle over what [reset] gave it, spins the shoulder, moves the target."""
    data = physics.named.data
    data.qpos["elbow"] = data.qpos["elbow"] + rng.uniform(-0.5, 0.5)
    data.qvel["shoulder"] = rng.uniform(-1, 1)
    data.mocap_pos["target"] = [rng.uniform(-1, 1), 0.5, 0.25]


def test_the_hook_sees_the_scenarios_start_and_the_options_and_the_first_observation_shows_its_writes(scenario):
    seen = {}

    def hook(rng, physics):
        data = physics.named.data
        seen.update(qpos=np.array(data.qpos), mocap=np.array(data.mocap_pos["target"]))
        seen["damping"] = float(physics.named.model.dof_damping["elbow"][0])
        drawn = rng.uniform(-0.5, 0.5)
        data.qpos["elbow"] = data.qpos["elbow"] + drawn
        data.mocap_pos["target"] = [0.1, -0.2, 0.7]
        seen["drawn"] = drawn

    plain, hooked = gym.ScenarioEnv(scenario), gym.ScenarioEnv(scenario, on_reset=hook)
    names = plain.observation_names
    before, plain_info = plain.reset(seed=4, options={"goals": [GOAL]})
    after, info = hooked.reset(seed=4, options={"goals": [GOAL]})
    # The hook saw the keyframe with its noise, the options' goal, the drawn damping.
    assert seen["qpos"].tolist() == [before[names.index("shoulder_pos")], before[names.index("elbow_pos")]]
    assert 0 < abs(seen["qpos"][0] - 0.4) <= 0.01
    assert seen["mocap"].tolist() == [before[names.index(f"target_{a}")] for a in "xyz"]
    assert seen["mocap"].tolist() == [info["goal_target_x"], info["goal_target_y"], info["goal_target_z"]]
    assert seen["damping"] == info["damping_elbow"] == plain_info["damping_elbow"]
    # Its writes are in the first observation, derived: the target's body and the forearm's pose moved.
    assert after[names.index("elbow_pos")] == seen["qpos"][1] + seen["drawn"] != before[names.index("elbow_pos")]
    assert [after[names.index(f"target_{a}")] for a in "xyz"] == [0.1, -0.2, 0.7]
    assert after[names.index("forearm_y")] == before[names.index("forearm_y")]  # (the elbow moves what is past it)
    assert after[names.index("forearm_x")] == before[names.index("forearm_x")]
    assert [after[names.index(n)] for n in names if n.startswith(("shoulder", "turn"))] == [
        before[names.index(n)] for n in names if n.startswith(("shoulder", "turn"))
    ]
    # The episode steps from that start: its first step differs from the plain env's.
    action = np.array([0.2])
    assert hooked.step(action)[0].tolist() != plain.step(action)[0].tolist()


def test_the_same_seed_gives_the_same_start_and_another_seed_another(scenario):
    env = gym.ScenarioEnv(scenario, on_reset=shape)
    first = [env.reset(seed=s)[0].tolist() for s in (1, 1, 2)]
    assert first[0] == first[1] != first[2]
    again = gym.ScenarioEnv(scenario, on_reset=shape)
    assert again.reset(seed=1)[0].tolist() == first[0]
    # A reset without a seed draws one from np_random: a seeded sequence repeats.
    again.reset(seed=2)
    assert [env.reset()[0].tolist() for _ in range(3)] == [again.reset()[0].tolist() for _ in range(3)]


def test_a_hook_that_writes_nothing_changes_no_bit(scenario):
    plain, hooked = gym.ScenarioEnv(scenario), gym.ScenarioEnv(scenario, on_reset=lambda rng, physics: None)
    assert plain.reset(seed=5)[0].tolist() == hooked.reset(seed=5)[0].tolist()
    for _ in range(10):
        assert plain.step(np.array([0.3]))[0].tolist() == hooked.step(np.array([0.3]))[0].tolist()


@pytest.mark.parametrize("threads", [1, 2])
@pytest.mark.parametrize("mode", ["NextStep", "SameStep"])
def test_vector_env_equals_single_envs_bit_for_bit_autoresets_included(scenario, threads, mode):
    calls = []

    def counted(rng, physics):
        calls.append(1)
        shape(rng, physics)

    # 3 envs of 40 steps, 8 a decision: each ends after 5 decisions and is reset (autoreset) with a seed drawn from
    # its own generator; a ScenarioEnv reset with that seed starts the same, bit for bit.
    vector = gym.ScenarioVectorEnv(scenario, 3, control_every=8, on_reset=counted, threads=threads, autoreset_mode=mode)
    single = gym.ScenarioEnv(scenario, control_every=8, on_reset=shape)
    obs, infos = vector.reset(seed=[7, 8, 9])
    starts = [(obs, infos)]
    for _ in range(6):
        obs, _, _, _, infos = vector.step(np.zeros((3, 1)))
        if "seed" in infos:
            starts.append((obs, infos))
    assert len(starts) == 2 and len(calls) == 6  # the first reset's 3, the autoresets' 3
    for obs, infos in starts:
        for i in range(3):
            one, info = single.reset(seed=int(infos["seed"][i]))
            assert one.tolist() == obs[i].tolist()
            assert info["damping_elbow"] == infos["damping_elbow"][i]
    masked, infos = vector.reset(seed=[None, 11, None], options={"reset_mask": np.array([False, True, False])})
    assert len(calls) == 7 and infos["_seed"].tolist() == [False, True, False]
    assert masked[1].tolist() == single.reset(seed=11)[0].tolist()


def test_a_hook_that_raises_leaves_the_env_as_it_was(scenario):
    calls = []

    def flaky(rng, physics):
        shape(rng, physics)  # written, then undone when the hook fails
        calls.append(1)
        if len(calls) == 2:
            raise RuntimeError("no start today")

    env, twin = gym.ScenarioEnv(scenario, on_reset=flaky), gym.ScenarioEnv(scenario, on_reset=shape)
    action = np.array([0.1])
    assert env.reset(seed=3)[0].tolist() == twin.reset(seed=3)[0].tolist()
    env.step(action), twin.step(action)
    with pytest.raises(RuntimeError, match="no start today"):
        env.reset()
    # The episode goes on where it was, its step count and its generator too.
    for _ in range(3):
        stepped, twin_stepped = env.step(action), twin.step(action)
        assert stepped[0].tolist() == twin_stepped[0].tolist() and stepped[4]["step"] == twin_stepped[4]["step"]
    assert env.reset()[0].tolist() == twin.reset()[0].tolist()  # (the seed drawn from np_random, as the twin's)


def test_a_vector_hook_that_raises_resets_no_env(scenario):
    calls = []

    def flaky(rng, physics):
        shape(rng, physics)
        calls.append(1)
        if len(calls) == 5:  # the second reset's second env
            raise RuntimeError("no start today")

    vector = gym.ScenarioVectorEnv(scenario, 3, control_every=8, on_reset=flaky, threads=2)
    twin = gym.ScenarioVectorEnv(scenario, 3, control_every=8, on_reset=shape, threads=2)
    assert vector.reset(seed=1)[0].tolist() == twin.reset(seed=1)[0].tolist()
    actions = np.full((3, 1), 0.2)
    assert vector.step(actions)[0].tolist() == twin.step(actions)[0].tolist()
    with pytest.raises(RuntimeError, match="no start today"):
        vector.reset()
    assert vector.observations.tolist() == twin.observations.tolist()  # every env as it was
    for _ in range(6):  # and they go on (through an autoreset) as the twin's do
        stepped, twin_stepped = vector.step(actions), twin.step(actions)
        assert stepped[0].tolist() == twin_stepped[0].tolist()
        assert stepped[4]["step"].tolist() == twin_stepped[4]["step"].tolist()


@pytest.mark.parametrize(
    "write, message",
    [
        (lambda data, model: data.xpos.__setitem__("arm", [0, 0, 1]), "xpos is read-only"),
        (lambda data, model: data.qfrc_applied.__setitem__(0, 1.0), "qfrc_applied is read-only"),
        (lambda data, model: model.body_mass.__setitem__("arm", 2.0), "body_mass is read-only"),
    ],
)
def test_writes_outside_the_start_are_refused_clearly_and_the_env_stays_usable(scenario, write, message):
    def hook(rng, physics):
        write(physics.named.data, physics.named.model)

    env = gym.ScenarioEnv(scenario, on_reset=hook)
    with pytest.raises(ValueError) as caught:
        env.reset(seed=0)
    assert str(caught.value).startswith(
        "physics in an on_reset hook may write qpos, qvel, act, ctrl, mocap_pos, mocap_quat: " + message
    )
    assert "\n" not in str(caught.value)
    env.unwrapped._setup.on_reset = None  # the same env, without the hook: it starts
    assert env.reset(seed=0)[0].tolist() == gym.ScenarioEnv(scenario).reset(seed=0)[0].tolist()


def test_derived_arrays_are_read_only_views_and_on_reset_must_be_callable(scenario):
    def hook(rng, physics):
        with pytest.raises(ValueError, match="read-only"):
            physics.named.data.xpos.array[1, 0] = 5.0

    gym.ScenarioEnv(scenario, on_reset=hook).reset(seed=0)
    with pytest.raises(TypeError, match=r"^on_reset must be None or a callable on_reset\(rng, physics\), got "):
        gym.ScenarioEnv(scenario, on_reset=3)


def test_gymnasium_make_and_make_vec_pass_on_reset_through(scenario):
    env = gymnasium.make("simloop/Scenario-v0", scenario=scenario, on_reset=shape)
    vector = gymnasium.make_vec("simloop/Scenario-v0", num_envs=2, scenario=scenario, on_reset=shape)
    single = gym.ScenarioEnv(scenario, on_reset=shape)
    obs, infos = vector.reset(seed=3)
    assert obs[1].tolist() == env.reset(seed=4)[0].tolist() == single.reset(seed=4)[0].tolist()


def test_the_info_carries_what_each_start_drew(scenario):
    env = gym.ScenarioEnv(scenario)
    _, info = env.reset(seed=2, options={"goals": [GOAL]})
    assert info["keyframe"] == "home"
    run = simloop.run_scenario(scenario, seed=2)
    assert [info["damping_elbow"]] == [p["value"] for p in run.params]
    assert 0.2 <= info["goal_target_x"] < 0.6 and info["goal_target_z"] == 0.0
    _, info = env.reset(seed=2, options={"params": [], "keyframe": ""})
    assert not any(k.startswith(("damping", "goal", "keyframe")) for k in info)
    # The vector env's infos: an array per key and its mask, autoresets too, as SyncVectorEnv gives them.
    vector = gym.ScenarioVectorEnv(scenario, 2, control_every=8, threads=1, autoreset_mode="SameStep")
    sync = gymnasium.vector.SyncVectorEnv(
        [lambda: gym.ScenarioEnv(scenario, control_every=8)] * 2,
        autoreset_mode=gymnasium.vector.AutoresetMode.SAME_STEP,
    )
    for got, want in ((vector.reset(seed=5), sync.reset(seed=5)),):
        assert got[1]["damping_elbow"].tolist() == want[1]["damping_elbow"].tolist()
        assert got[1]["keyframe"].tolist() == ["home", "home"] and got[1]["_keyframe"].all()
    for _ in range(5):
        got, want = vector.step(np.zeros((2, 1))), sync.step(np.zeros((2, 1)))
    assert got[4]["damping_elbow"].tolist() == want[4]["damping_elbow"].tolist()
    assert got[4]["_damping_elbow"].all() and "damping_elbow" not in got[4]["final_info"]


def test_batch_tables_carry_the_drawn_goals_and_only_where_there_are_goals(scenario):
    with_goal = simloop.Scenario(
        scene=scenario.scene, steps=5, record=RECORD, reset={"goals": [GOAL], "params": RESET["params"]}
    )
    table = simloop.run_scenario_batch(with_goal, seeds=[0, 1])
    names = table.column_names
    assert names.index("damping_elbow") < names.index("goal_target_x") < names.index("goal_target_z")
    for i, run in enumerate(table.results):
        first = dict(zip(run.column_names, run.trajectory[0]))
        assert [table[f"goal_target_{a}"][i] for a in "xyz"] == [first[f"target_{a}"] for a in "xyz"]
    assert table["goal_target_x"][0] != table["goal_target_x"][1]
    assert simloop.run_scenario_batch(with_goal, seeds=[0, 1], metrics_only=True) == simloop.table(table.results)
    assert simloop.table(table.results).columns.keys() == table.columns.keys()
    # A result that travels (pickled, as an executor's are) keeps what its start drew.
    travelled = [pickle.loads(pickle.dumps(run)) for run in table.results]
    assert [run.params for run in travelled] == [run.params for run in table.results]
    assert simloop.table(travelled) == simloop.table(table.results)
    plain = simloop.run_scenario_batch(scenario, seeds=[0], metrics_only=True)
    assert not any(n.startswith("goal_") for n in plain.column_names)


def test_sb3_make_vec_env_passes_on_reset_to_every_reset_autoresets_too(scenario):
    pytest.importorskip("stable_baselines3", reason="stable-baselines3 is not installed (it brings torch)")
    from simloop.sb3 import make_vec_env

    starts = []

    def counted(rng, physics):
        starts.append(float(physics.named.data.qpos["shoulder"][0]))
        shape(rng, physics)

    vec_env = make_vec_env(scenario, n_envs=2, seed=3, env_kwargs={"on_reset": counted, "control_every": 8})
    obs = vec_env.reset()
    single = gym.ScenarioEnv(scenario, control_every=8, on_reset=shape)
    assert obs[1].tolist() == single.reset(seed=4)[0].tolist() and len(starts) == 2
    for _ in range(5):  # 40 steps, 8 a decision: every env ends and SB3's autoreset starts it again
        vec_env.step(np.zeros((2, 1)))
    assert len(starts) == 4
