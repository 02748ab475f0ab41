"""Starts a trainer shapes (issue 35): a keyframe by name with the other reset keys over it, and goals (a mocap
body's position) drawn per episode, the same from Scenario(reset=...), a run and an env's reset options."""

import numpy as np
import pytest
import simloop

# An arm's two hinges, a mocap target, and two keyframes.
REACH = """<mujoco>
  <worldbody>
    <body name="arm"><joint name="shoulder" axis="0 0 1"/><geom type="capsule" size="0.05" fromto="0 0 0 0.3 0 0"/>
      <body name="forearm" pos="0.3 0 0"><joint name="elbow" axis="0 0 1"/>
        <geom type="capsule" size="0.04" fromto="0 0 0 0.3 0 0"/></body></body>
    <body name="target" mocap="true" pos="0.5 0 0"><geom size="0.02" contype="0" conaffinity="0"/></body>
  </worldbody>
  <actuator><motor name="turn" joint="shoulder"/></actuator>
  <keyframe><key name="home" qpos="0.4 -0.8" qvel="0.1 0.2" mpos="0.1 0.2 0.3" mquat="1 0 0 0"/>
    <key name="up" qpos="1.5 0"/></keyframe>
</mujoco>"""
GOAL = {"body": "target", "uniform": [[0.2, -0.3, 0.0], [0.6, 0.3, 0.0]]}
RECORD = {"joints": ["shoulder", "elbow"], "bodies": ["target"], "actuators": ["turn"]}


@pytest.fixture
def scene(tmp_path):
    path = tmp_path / "reach.xml"
    path.write_text(REACH)
    return str(path)


def first_row(scene, seed=0, **reset):
    run = simloop.run_scenario(simloop.Scenario(scene=scene, steps=3, record=RECORD, reset=reset), seed=seed)
    return dict(zip(run.column_names, run.trajectory[0]))


def test_a_keyframe_is_the_start_the_other_keys_apply_over(scene):
    home = first_row(scene, keyframe="home")
    assert (home["shoulder_pos"], home["elbow_pos"], home["elbow_vel"]) == (0.4, -0.8, 0.2)
    assert home["target_y"] == 0.2  # its mocap position too
    over = first_row(scene, seed=3, keyframe="home", qvel=[0, 0], qpos_noise={"elbow": 0.01})
    assert over["shoulder_pos"] == 0.4 and over["elbow_vel"] == 0.0
    assert 0 < abs(over["elbow_pos"] + 0.8) <= 0.01  # noise about the keyframe's pose
    assert first_row(scene)["shoulder_pos"] == 0.0


def test_a_goal_is_where_the_state_says_and_the_seed_decides(scene):
    a, again, b = (first_row(scene, seed=s, goals=[GOAL]) for s in (1, 1, 2))
    assert a == again and (a["target_x"], a["target_y"]) != (b["target_x"], b["target_y"])
    assert 0.2 <= a["target_x"] < 0.6 and -0.3 <= a["target_y"] < 0.3 and a["target_z"] == 0.0
    fixed = first_row(scene, keyframe="home", goals=[{"body": "target", "pos": [1, 2, 3]}])
    assert (fixed["target_x"], fixed["target_y"], fixed["target_z"]) == (1.0, 2.0, 3.0)


def test_env_reset_options_take_them_key_by_key(scene):
    gym = pytest.importorskip("simloop.gym", reason="needs gymnasium (the gym extra)")
    scenario = simloop.Scenario(scene=scene, steps=20, record=RECORD, reset={"keyframe": "home"})
    env = gym.ScenarioEnv(scenario)
    names = env.observation_names
    obs, _ = env.reset(seed=1, options={"goals": [GOAL]})  # the scenario's keyframe stays
    row = first_row(scene, seed=1, keyframe="home", goals=[GOAL])
    assert np.array_equal(obs, [row[n] for n in names])
    obs, _ = env.reset(seed=1, options={"keyframe": "up"})
    assert obs[names.index("shoulder_pos")] == 1.5
    obs, _ = env.reset(seed=1, options={"keyframe": ""})  # the scene's own pose
    assert obs[names.index("shoulder_pos")] == 0.0
    with pytest.raises(ValueError) as caught:
        env.reset(options={"keyframe": "hoem"})
    assert str(caught.value) == (
        "reset.keyframe: no keyframe named 'hoem' (did you mean 'home'?); the scene's keyframes: home, up"
    )
    with pytest.raises(ValueError, match=r"^reset.goal\[0\].body: 'arm' is not a mocap body; the scene's mocap"):
        env.reset(options={"goals": [{"body": "arm", "pos": [0, 0, 0]}]})
