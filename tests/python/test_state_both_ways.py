"""State and scenes across the boundary with the user's own mujoco: a buffer
of mujoco.mj_getState(mjSTATE_INTEGRATION) wherever simloop takes a state,
get_state(layout="mujoco") back, Scenario(scene=) of a compiled scene;
contacts by name and id; named rows by a list of names."""

from __future__ import annotations

import pickle
from pathlib import Path

import numpy as np
import pytest
import simloop
from simloop import _build

SCENES = Path(__file__).resolve().parents[2] / "tests" / "scenes"
PYPI = _build.MUJOCO_BUILD == "pypi"
pypi_only = pytest.mark.skipif(
    not PYPI, reason=f"simloop is built on the system's {simloop.MUJOCO_VERSION}: no mujoco package objects"
)


def bits(array):
    return np.ascontiguousarray(array, dtype=np.float64).tobytes()


def mujoco_state(mujoco, model, data):
    signature = mujoco.mjtState.mjSTATE_INTEGRATION
    state = np.empty(mujoco.mj_stateSize(model, signature))
    mujoco.mj_getState(model, data, state, signature)
    return state


def mujocos_run_into_a_sim(steps):
    """PushT (the T-block on a free joint) in mujoco's own loop, pushed for
    `steps` steps, and a Sim set to its mj_getState: (mujoco, model, data, that state, the Sim)."""
    mujoco = pytest.importorskip("mujoco")
    model = mujoco.MjModel.from_xml_path(str(SCENES / "pusht.xml"))
    data = mujoco.MjData(model)
    data.ctrl[:] = np.linspace(0.3, 0.7, model.nu)
    for _ in range(steps):
        mujoco.mj_step(model, data)
    theirs = mujoco_state(mujoco, model, data)
    sim = simloop.Sim(model)
    sim.set_state(theirs)
    return mujoco, model, data, theirs, sim


@pypi_only
def test_mujocos_own_state_goes_into_a_sim_and_comes_back_and_the_runs_continue_bit_for_bit():
    mujoco, model, data, theirs, sim = mujocos_run_into_a_sim(150)
    assert model.ntree > 0 and sim.state_size == theirs.size + model.ntree  # the sleep counters: a length apart
    assert bits(sim.get_state(layout="mujoco")) == bits(theirs)
    assert bits(sim.get_state()[: theirs.size]) == bits(theirs)
    sim.step(200)
    for _ in range(200):
        mujoco.mj_step(model, data)
    assert bits(sim.qpos) == bits(data.qpos) and bits(sim.qvel) == bits(data.qvel)
    # ... and back: mujoco takes simloop's get_state(layout="mujoco") as it is.
    other = mujoco.MjData(model)
    mujoco.mj_setState(model, other, sim.get_state(layout="mujoco"), mujoco.mjtState.mjSTATE_INTEGRATION)
    sim.step(100)
    for _ in range(100):
        mujoco.mj_step(model, other)
    assert bits(sim.qpos) == bits(other.qpos) and bits(sim.qvel) == bits(other.qvel)


@pypi_only
def test_a_runs_initial_state_may_be_mujocos_own():
    _, _, _, theirs, sim = mujocos_run_into_a_sim(120)
    ours = sim.get_state()  # the same state in simloop's layout: every tree awake
    scenario = simloop.Scenario.from_file(SCENES / "pusht.toml")
    from_theirs = simloop.run_scenario(scenario, seed=3, steps=100, initial_state=theirs)
    from_ours = simloop.run_scenario(scenario, seed=3, steps=100, initial_state=ours)
    assert bits(from_theirs.trajectory) == bits(from_ours.trajectory)
    batch = simloop.run_scenario_batch(scenario, seeds=[3, 3], steps=100, initial_state=np.stack([theirs, theirs]))
    assert [bits(r.final_state) for r in batch.results] == [bits(from_ours.final_state)] * 2
    with pytest.raises(ValueError) as error:
        simloop.run_scenario(scenario, seed=0, steps=10, initial_state=theirs[:-1])
    assert str(error.value) == (
        f"initial_state must hold {ours.size} values (simloop's state, state_layout) or {theirs.size} "
        f"(MuJoCo's mj_getState(mjSTATE_INTEGRATION)) for this scene, got {theirs.size - 1}"
    )


def test_a_state_of_another_length_is_refused_naming_what_is_taken():
    sim = simloop.Sim(SCENES / "pusht.xml")
    size = sim.state_size
    before = sim.get_state()
    with pytest.raises(ValueError, match=rf"^state must have {size} values \(simloop's state, state_layout\)") as error:
        sim.set_state(np.zeros(size + 1))
    assert str(error.value).endswith(f"for this model, got {size + 1}") and "\n" not in str(error.value)
    assert bits(sim.get_state()) == bits(before)  # nothing half-written
    with pytest.raises(ValueError, match="^layout must be 'simloop' or 'mujoco', got 'dm_control'$"):
        sim.get_state(layout="dm_control")
    if not PYPI:
        with pytest.raises(ValueError, match=r"^MuJoCo's own state \(mj_getState\) needs MuJoCo 3.3 or later"):
            sim.get_state(layout="mujoco")


@pypi_only
@pytest.mark.parametrize("kind", ["MjModel", "MjSpec"])
def test_a_scenario_takes_a_mujoco_scene(kind):
    mujoco = pytest.importorskip("mujoco")
    spec = mujoco.MjSpec.from_file(str(SCENES / "pusht.xml"))
    scene = spec if kind == "MjSpec" else spec.compile()
    keywords = dict(steps=300, controls={"push_x": 0.8}, record={"bodies": ["tblock"]})
    given = simloop.Scenario(scene=scene, **keywords)
    from_file = simloop.Scenario(scene=SCENES / "pusht.xml", **keywords)
    assert given.scene == ""
    run = simloop.run_scenario(given, seed=2)
    assert bits(run.trajectory) == bits(simloop.run_scenario(from_file, seed=2).trajectory)
    again = pickle.loads(pickle.dumps(given))  # a compiled scene travels with it (gymnasium's AsyncVectorEnv)
    assert bits(simloop.run_scenario(again, seed=2).trajectory) == bits(run.trajectory)
    with pytest.raises(TypeError, match="does not travel to an executor's workers"):
        from concurrent.futures import ThreadPoolExecutor

        with ThreadPoolExecutor(1) as executor:
            simloop.run_scenario_batch(given, seeds=[0], executor=executor)


def test_a_scenario_takes_a_simloop_model_and_refuses_other_scenes_by_name():
    model = simloop.Model.from_file(SCENES / "pusht.xml")
    keywords = dict(steps=200, controls={"push_y": 0.5})
    run = simloop.run_scenario(simloop.Scenario(scene=model, **keywords), seed=1)
    from_file = simloop.run_scenario(simloop.Scenario(scene=SCENES / "pusht.xml", **keywords), seed=1)
    assert bits(run.trajectory) == bits(from_file.trajectory)
    with pytest.raises(TypeError, match=r"^model must be None, a simloop.Model, a mujoco.MjModel or MjSpec"):
        simloop.Scenario(scene=3.5)


UNNAMED = """
<mujoco>
  <worldbody>
    <geom type="plane" size="2 2 0.1"/>
    <body name="ball" pos="0 0 0.099">
      <freejoint/>
      <geom name="ball_geom" type="sphere" size="0.1"/>
    </body>
    <body pos="0.5 0 0.099">
      <freejoint/>
      <geom type="box" size="0.1 0.1 0.1"/>
    </body>
  </worldbody>
</mujoco>
"""


def test_contacts_carry_geom_and_body_ids_and_name_unnamed_ones_by_index():
    sim = simloop.Sim(simloop.Model.from_xml_string(UNNAMED))
    sim.step(5)
    contacts = {(c.geom1, c.geom2): c for c in sim.contacts}
    assert set(contacts) == {("geom0", "ball_geom"), ("geom0", "geom2")}
    ball = contacts["geom0", "ball_geom"]
    assert (ball.geom1_id, ball.geom2_id, ball.body1_id, ball.body2_id) == (0, 1, 0, 1)
    assert (ball.body1, ball.body2) == ("world", "ball")
    box = contacts["geom0", "geom2"]
    assert (box.geom2_id, box.body2_id, box.body2) == (2, 2, "body2")


def test_named_rows_take_a_list_of_names_as_dm_controls_do():
    sim = simloop.Sim(SCENES / "walker.xml")
    sim.step(20, ctrl=np.array([0.5, -0.3, 0.2, 0.0]))
    qpos = sim.named.data.qpos
    joints = [name for name in qpos.names if qpos[name].size == 1][:2]
    assert len(joints) == 2
    assert bits(qpos[joints]) == bits(np.concatenate([qpos[j] for j in joints]))
    assert bits(qpos[[joints[1], 0]]) == bits(np.concatenate([qpos[joints[1]], sim.qpos[:1]]))
    xpos = sim.named.data.xpos
    bodies = list(xpos.names)[1:3]
    assert bits(xpos[bodies]) == bits(np.stack([xpos[b] for b in bodies]))
    free = [name for name in qpos.names if qpos[name].size == 7]  # a free joint: its 7 rows, in order
    if free:
        assert bits(qpos[[free[0], joints[0]]]) == bits(np.concatenate([qpos[free[0]], qpos[joints[0]]]))
    with pytest.raises(KeyError, match="has no row named 'nosuch'"):
        qpos[[joints[0], "nosuch"]]
