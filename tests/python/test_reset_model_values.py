"""A [[reset.param]] of kind "model" (issue 35): any writable mjModel value, by object and index, drawn per run or
episode from a range; the env's own model copy holds it, the info, the run's params and a batch's table show it under
one column name, and a bad field, index or name is refused by name."""

import pickle

import numpy as np
import pytest
import simloop

gym = pytest.importorskip("simloop.gym", reason="needs gymnasium (the gym extra)")

# A box pushed by a slide's motor, as the chapter's, with a ball beside it.
SCENE = """<mujoco>
  <worldbody>
    <geom name="floor" type="plane" size="2 2 0.1"/>
    <body name="box" pos="0.4 0 0.05"><freejoint/><geom name="box_geom" type="box" size="0.05 0.05 0.05"/></body>
    <body name="pusher" pos="0 0 0.05"><joint name="slide" type="slide" axis="1 0 0" damping="4"/>
      <geom name="pusher_geom" type="box" size="0.04 0.12 0.05" mass="1"/></body>
  </worldbody>
  <actuator><motor name="push" joint="slide" gear="10" ctrllimited="true" ctrlrange="-1 1"/></actuator>
</mujoco>"""
GEAR = {"kind": "model", "field": "actuator_gear", "name": "push", "uniform": [5.0, 15.0]}
TORSION = {"kind": "model", "field": "geom_friction", "name": "box_geom", "index": 1, "value": 0.02}
ALPHA = {"kind": "model", "field": "geom_rgba", "index": 3, "uniform": [0.3, 0.9]}


def make(folder, params):
    path = folder / "push.xml"
    path.write_text(SCENE)
    return simloop.Scenario(
        scene=str(path),
        steps=60,
        controls={"push": 0.8},
        record={"bodies": ["box"], "joints": ["slide"]},
        reset={"params": params},
    )


@pytest.fixture
def scenario(tmp_path):
    return make(tmp_path, [GEAR, TORSION, ALPHA])


def test_each_episode_draws_the_values_and_its_model_holds_them(scenario, tmp_path):
    seen = {}

    def look(rng, physics):
        model = physics.named.model
        seen.update(gear=float(model.actuator_gear["push"][0]), torsion=float(model.geom_friction["box_geom"][1]))
        seen["alpha"] = np.array(model.geom_rgba)[:, 3]

    env = gym.ScenarioEnv(scenario, on_reset=look)
    _, info = env.reset(seed=7)
    assert 5.0 <= info["actuator_gear_push_0"] < 15.0 and info["geom_friction_box_geom_1"] == 0.02
    assert seen["gear"] == info["actuator_gear_push_0"] and seen["torsion"] == 0.02
    # A float array's value is drawn, then rounded to float: the info shows the value the model holds.
    assert seen["alpha"].tolist() == [info["geom_rgba_3"]] * 3 and info["geom_rgba_3"] == np.float32(
        info["geom_rgba_3"]
    )
    # The same seed, the same draws as a run; another seed, others.
    run = simloop.run_scenario(scenario, seed=7)
    assert [(p["field"], p["name"], p["index"], p["value"]) for p in run.params] == [
        ("actuator_gear", "push", 0, info["actuator_gear_push_0"]),
        ("geom_friction", "box_geom", 1, 0.02),
        ("geom_rgba", "", 3, info["geom_rgba_3"]),
    ]
    assert env.reset(seed=8)[1]["actuator_gear_push_0"] != info["actuator_gear_push_0"]
    # The gear drives the run: a stronger one pushes the pusher farther.
    fixed = [dict(GEAR, uniform=[v, v]) for v in (5.0, 15.0)]
    ends = [simloop.run_scenario(make(tmp_path, [p]), seed=0).column("slide_pos")[-1] for p in fixed]
    assert ends[0] < ends[1]


def test_batch_tables_and_options_name_a_model_value_by_one_column(scenario):
    table = simloop.run_scenario_batch(scenario, seeds=[0, 1, 2])
    gears = table["actuator_gear_push_0"]
    assert len(set(gears.tolist())) == 3 and all(5.0 <= g < 15.0 for g in gears)
    assert table["geom_friction_box_geom_1"].tolist() == [0.02] * 3
    assert simloop.run_scenario_batch(scenario, seeds=[0, 1, 2], metrics_only=True) == table
    travelled = [pickle.loads(pickle.dumps(run)) for run in table.results]
    assert [run.params for run in travelled] == [run.params for run in table.results]
    # Reset options replace the scenario's params as a whole list.
    env = gym.ScenarioEnv(scenario)
    _, info = env.reset(seed=0, options={"params": [dict(TORSION, value=0.5)]})
    assert info["geom_friction_box_geom_1"] == 0.5 and "actuator_gear_push_0" not in info
    # The vector env's infos and steps equal single envs', with the values drawn per env.
    vector = gym.ScenarioVectorEnv(scenario, 2, threads=2)
    singles = [gym.ScenarioEnv(scenario) for _ in range(2)]
    obs, infos = vector.reset(seed=[3, 4])
    for i, single in enumerate(singles):
        want_obs, want = single.reset(seed=3 + i)
        assert obs[i].tolist() == want_obs.tolist() and infos["actuator_gear_push_0"][i] == want["actuator_gear_push_0"]
    actions = np.full((2, 1), 0.5)
    for _ in range(10):
        obs = vector.step(actions)[0]
        assert obs.tolist() == [s.step(actions[0])[0].tolist() for s in singles]


@pytest.mark.parametrize(
    "param, message",
    [
        ({"field": "geom_fricton", "name": "box_geom"}, "no mjModel array named 'geom_fricton' (did you mean"),
        ({"field": "body_pos", "name": "box"}, "mjModel's body_pos is not one a run may vary; these are: body_mass"),
        ({"field": "geom_friction", "name": "box_geom", "index": 3}, "index must be 0 to 2 (geom_friction holds 3"),
        ({"field": "body_mass", "name": "bx"}, "no body named 'bx' (did you mean 'box'?)"),
        ({"field": "dof_damping", "name": "slide", "value": -1.0}, "dof_damping must be a finite number >= 0"),
        ({"name": "box"}, "reset.param[0].field: missing: a model value names an mjModel array"),
    ],
)
def test_a_bad_model_value_is_refused_by_name_and_the_env_stays_usable(scenario, param, message):
    env = gym.ScenarioEnv(scenario)
    before = env.reset(seed=1)[0]
    with pytest.raises(ValueError, match="reset.param") as error:
        env.reset(seed=1, options={"params": [{"kind": "model", "value": 1.0, **param}]})
    assert message in str(error.value)
    assert env.reset(seed=1)[0].tolist() == before.tolist()
