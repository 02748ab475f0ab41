"""simloop.Sim on any scene, as an engineer used to the mujoco bindings uses it:
arrays, names, forces and torques, state, keyframes, copies."""

from __future__ import annotations

import copy
import gc
import math
from pathlib import Path

import numpy as np
import pytest
import simloop

SCENES = Path(__file__).resolve().parents[1] / "scenes"
PUSHT = SCENES / "pusht.xml"
WALKER = SCENES / "walker.xml"

KEYED = """<mujoco model="keyed">
  <worldbody>
    <geom type="plane" size="1 1 0.1"/>
    <body name="ball" pos="0 0 1"><freejoint/><geom size="0.1" mass="2"/></body>
  </worldbody>
  <keyframe>
    <key name="high" qpos="0 0 3 1 0 0 0"/>
    <key name="moving" qpos="0 0 2 1 0 0 0" qvel="1 0 0 0 0 0"/>
  </keyframe>
</mujoco>"""


def drive(sim: simloop.Sim, n: int) -> None:
    """Every actuator at a different ctrl, then n steps."""
    sim.step(n, ctrl=0.6 - 0.25 * np.arange(sim.model.nu))


def test_arrays_have_mujocos_shapes_on_any_scene():
    sim = simloop.Sim(WALKER)
    m = sim.model
    assert (m.nq, m.nv, m.nu, m.nbody) == (11, 10, 4, 6)
    assert sim.qpos.shape == (11,) and sim.qvel.shape == (10,) and sim.ctrl.shape == (4,)
    assert sim.act.shape == (0,) and sim.qfrc_applied.shape == (10,)
    assert sim.xfrc_applied.shape == (6, 6) and sim.sensordata.shape == (3,)
    assert all(a.dtype == np.float64 for a in (sim.qpos, sim.qvel, sim.ctrl, sim.sensordata))
    assert isinstance(sim.time, float)


def test_array_writes_take_effect_at_the_next_step():
    sim = simloop.Sim(PUSHT)
    x = sim.joint("slide_x")
    x.qvel[0] = 0.5  # a slice of the qvel view
    assert sim.qvel[6] == 0.5  # slide_x's dof, after the block's six
    before = float(x.qpos[0])
    sim.step(1)
    assert x.qpos[0] > before  # the velocity written moved it
    sim.ctrl[:] = [0.7, -0.2]
    assert np.array_equal(sim.actuator("push_x").ctrl, [0.7])
    sim.step(1)
    assert sim.actuator("push_x").force == 0.7  # a motor: gain 1, before its gear


def test_a_mocap_body_goes_where_mocap_pos_and_mocap_quat_put_it():
    """MuJoCo's mocap bodies (a Menagerie arm's target) move by their mocap arrays, inputs as ctrl is."""
    sim = simloop.Sim(
        simloop.Model.from_xml_string(
            '<mujoco><worldbody><body name="box"><freejoint/><geom size=".1"/></body>'
            '<body name="target" mocap="true" pos="0 0 1"><geom size=".05" contype="0" conaffinity="0"/></body>'
            "</worldbody></mujoco>"
        )
    )
    assert sim.mocap_pos.shape == (1, 3) and np.array_equal(sim.mocap_quat, [[1, 0, 0, 0]])
    sim.mocap_pos[0] = [0.5, 0.0, 0.5]
    sim.named.data.mocap_quat["target"] = [0.0, 0.0, 0.0, 1.0]  # rows by the mocap body's name
    sim.step(1)
    assert np.array_equal(sim.body("target").xpos, [0.5, 0.0, 0.5])
    assert np.array_equal(sim.body("target").xquat, [0.0, 0.0, 0.0, 1.0])
    with pytest.raises(ValueError, match=r"mocap_pos\['target'\] must be finite"):
        sim.named.data.mocap_pos["target"] = [math.nan, 0.0, 0.0]


def test_views_are_views_and_keep_their_sim_alive():
    sim = simloop.Sim(PUSHT)
    qpos = sim.qpos
    sensors = sim.sensordata
    drive(sim, 50)
    assert np.array_equal(qpos, sim.get_state()[1 : 1 + sim.model.nq])  # moved with the Sim
    with pytest.raises(ValueError, match="read-only"):
        sensors[0] = 1.0
    del sim
    gc.collect()
    assert np.isfinite(qpos).all() and qpos.base is not None  # the view still owns a live Sim
    qpos[0] += 0.0


def test_named_access_by_name_and_index():
    sim = simloop.Sim(WALKER)
    torso = sim.body("torso")
    assert torso.id == 1 and sim.body(1).name == "torso" and torso.mass == pytest.approx(4.0)
    assert sim.joint("root").type == "free" and sim.joint("hip_left").type == "hinge"
    assert sim.joint("root").qpos.shape == (7,) and sim.joint("root").qvel.shape == (6,)
    assert sim.actuator(3).name == "knee_right" and sim.actuator("hip_left").ctrlrange is not None
    assert sim.sensor("torso_acc").data.shape == (3,)
    drive(sim, 100)
    sim.forward()
    assert np.array_equal(torso.xpos, sim.qpos[:3])  # the free body's origin is its qpos
    v = sim.joint("root").qvel
    assert np.allclose(torso.linear_velocity, v[:3]) and np.allclose(
        torso.angular_velocity, sim.body(1).angular_velocity
    )
    assert "torso" in repr(torso) and "free" in repr(sim.joint("root")) and "hip_left" in repr(sim.actuator(0))


def test_unknown_names_say_what_the_scene_has():
    sim = simloop.Sim(WALKER)
    with pytest.raises(ValueError) as caught:
        sim.body("torsoo")
    assert str(caught.value) == (
        "no body named 'torsoo' (did you mean 'torso'?); the scene's bodies: world, torso, "
        "thigh_left, shin_left, thigh_right, shin_right"
    )
    with pytest.raises(ValueError, match="no joint named 'hip'; the scene's joints: root, hip_left"):
        sim.joint("hip")
    with pytest.raises(ValueError, match="actuator index 4 is out of range: the scene has 4 actuators"):
        sim.actuator(4)
    with pytest.raises(ValueError, match="sensor index -1 is out of range"):
        sim.sensor(-1)
    with pytest.raises(TypeError, match=r"body must be a name \(str\) or an index \(int\), got 1.5 \(float\)"):
        sim.body(1.5)


def test_force_and_torque_on_any_body_persist_until_cleared():
    sim = simloop.Sim(PUSHT)
    sim.apply_force(body="tblock", torque=[0.0, 0.0, 0.05])
    sim.step(200)
    assert np.array_equal(sim.body("tblock").xfrc_applied, [0, 0, 0, 0, 0, 0.05])  # still there
    assert sim.joint(0).qvel[5] > 0  # it turned the block about z
    sim.apply_force(body=1, force=[0.0, 0.3, 0.0])
    assert np.array_equal(sim.xfrc_applied[1], [0, 0.3, 0, 0, 0, 0.05])  # the torque part was left
    sim.clear_forces()
    assert not sim.xfrc_applied.any()
    with pytest.raises(ValueError, match=r"torque must be finite, got nan"):
        sim.apply_force(body="tblock", torque=[0, 0, math.nan])
    with pytest.raises(ValueError, match="torque must have 3 components"):
        sim.apply_force(body="tblock", torque=[0, 0])
    with pytest.raises(ValueError, match="needs force=..., torque=... or both"):
        sim.apply_force(body="tblock")
    with pytest.raises(ValueError, match='no body named "box"'):
        sim.apply_force([1.0, 0.0, 0.0])  # the chapter's meaning needs the chapter's box


def test_the_chapters_force_and_ctrl_still_mean_the_box_and_the_motor():
    sim = simloop.Sim()
    sim.apply_force([0.0, 2.0, 0.0])
    assert np.array_equal(sim.applied_force, [0.0, 2.0, 0.0])
    assert np.array_equal(sim.body("box").xfrc_applied[:3], [0.0, 2.0, 0.0])
    sim.step(10, ctrl=0.5)
    assert sim.ctrl == 0.5 and np.array_equal(sim.ctrl_array, [0.5])
    sim.step(1, ctrl=np.array([0.25]))
    assert sim.ctrl == 0.25


def test_step_takes_a_full_ctrl_vector_with_shape_checks():
    sim = simloop.Sim(PUSHT)
    sim.step(3, ctrl=np.array([0.5, -0.5]))
    assert np.array_equal(sim.ctrl, [0.5, -0.5])
    with pytest.raises(ValueError, match=r"ctrl must have nu = 2 values \(one per actuator\), got 3"):
        sim.step(1, ctrl=[0.1, 0.2, 0.3])
    with pytest.raises(ValueError, match=r"ctrl\[1\] must be finite, got inf"):
        sim.step(1, ctrl=[0.1, math.inf])
    with pytest.raises(ValueError, match=r"shape \(2,\).*got shape \(1, 2\)"):
        sim.step(1, ctrl=np.zeros((1, 2)))
    with pytest.raises(TypeError, match="ctrl must be a sequence or numpy array of 2 numbers"):
        sim.step(1, ctrl="0.1")
    assert sim.steps_taken == 3  # the refused calls stepped nothing


@pytest.mark.parametrize("scene", [PUSHT, WALKER], ids=["pusht", "walker"])
def test_a_saved_state_continues_bit_for_bit(scene):
    sim = simloop.Sim(scene)
    drive(sim, 137)
    saved = sim.get_state()
    drive(sim, 250)
    expected = sim.get_state()
    other = simloop.Sim(scene)  # another Sim
    other.set_state(saved)
    drive(other, 250)
    assert np.array_equal(other.get_state(), expected)
    sim.set_state(saved)  # the same Sim, after stepping on
    drive(sim, 250)
    assert np.array_equal(sim.get_state(), expected)
    assert sim.get_state().tobytes() == expected.tobytes()


def test_state_layout_and_bad_states():
    sim = simloop.Sim(WALKER)
    layout = sim.state_layout()
    names = [n for n, _ in layout]
    assert layout[:3] == [("time", 1), ("qpos", 11), ("qvel", 10)] and "userdata" in names
    assert names[-1] in (
        "userdata",
        "plastic",
        "tree_asleep",
    )  # 2.2's layout ends with userdata; 3.x's mj_getState's does not
    size = sum(n for _, n in layout)
    assert sim.get_state().shape == (size,) == (sim.state_size,)
    with pytest.raises(
        ValueError, match=rf"^state must have {size} values \(simloop's state, state_layout\).* got {size + 1}$"
    ):
        sim.set_state(np.zeros(size + 1))  # (size - 1 may be MuJoCo's own state: a scene of one tree)
    with pytest.raises(ValueError, match="state must have dtype float64, got float32"):
        sim.set_state(np.zeros(size, dtype=np.float32))
    with pytest.raises(TypeError, match="state must be a numpy float64 array"):
        sim.set_state([0.0] * size)


def test_forward_brings_poses_up_to_date_without_changing_the_run():
    a, b = simloop.Sim(WALKER), simloop.Sim(WALKER)
    drive(a, 40)
    drive(b, 40)
    b.qpos[2] += 0.0  # a no-op write
    b.forward()
    assert np.array_equal(b.body("torso").xpos, b.qpos[:3])
    drive(a, 100)
    drive(b, 100)
    assert np.array_equal(a.get_state(), b.get_state())


def test_reset_to_zero_and_to_keyframes():
    sim = simloop.Sim(simloop.Model.from_xml_string(KEYED))
    sim.step(20)
    sim.reset(keyframe="high")
    assert sim.qpos[2] == 3.0 and sim.time == 0.0 and sim.steps_taken == 0
    sim.reset(keyframe=1)
    assert sim.qvel[0] == 1.0 and sim.qpos[2] == 2.0
    sim.reset()
    assert sim.qpos[2] == 1.0 and sim.qvel[0] == 0.0
    with pytest.raises(
        ValueError, match="no keyframe named 'hihg' \\(did you mean 'high'\\?\\); the scene's keyframes: high, moving"
    ):
        sim.reset(keyframe="hihg")
    with pytest.raises(ValueError, match="keyframe index 2 is out of range: the scene has 2 keyframes"):
        sim.reset(keyframe=2)


@pytest.mark.parametrize("make_copy", [copy.copy, copy.deepcopy], ids=["copy", "deepcopy"])
def test_copies_are_independent(make_copy):
    sim = simloop.Sim(PUSHT)
    drive(sim, 60)
    twin = make_copy(sim)
    before = sim.get_state()
    assert np.array_equal(twin.get_state(), before) and twin.steps_taken == 60
    drive(twin, 30)
    assert np.array_equal(sim.get_state(), before) and sim.steps_taken == 60  # the original did not move
    twin.qpos[0] = 9.0
    assert sim.qpos[0] != 9.0  # nor do its arrays alias the copy's
    sim.step(30)
    assert not np.array_equal(twin.get_state(), sim.get_state())  # twin had qpos[0] changed


def test_a_copy_steps_as_the_original_would():
    sim = simloop.Sim(WALKER)
    drive(sim, 70)
    twin = copy.copy(sim)
    drive(sim, 90)
    drive(twin, 90)
    assert np.array_equal(sim.get_state(), twin.get_state())


def test_sim_from_a_scenario_takes_its_scene_and_timestep_and_applies_nothing():
    scenario = simloop.Scenario.from_file(SCENES / "walker.toml")
    sim = simloop.Sim(scenario)
    assert sim.model.name == "walker" and sim.timestep == simloop.Model.from_file(WALKER).timestep
    sim.step(300)  # past the scenario's torque on the torso, with its controls
    assert not sim.ctrl.any() and not sim.xfrc_applied.any()  # the user drives: nothing behind their back
    timed = simloop.Scenario(scene=str(PUSHT), timestep=0.005, steps=10)
    assert simloop.Sim(timed).timestep == 0.005


def test_reprs_say_what_they_are():
    sim = simloop.Sim(WALKER)
    assert repr(sim.model) == "<simloop.Model 'walker' nq=11 nv=10 nu=4 nbody=6 timestep=0.004>"
    assert repr(sim).startswith("<simloop.Sim 'walker' t=0.0 steps_taken=0 timestep=0.004 nq=11")
    assert repr(sim.joint("knee_left")) == "<simloop.Sim joint 2 'knee_left' type=hinge>"


def test_the_docs_sim_example_runs(monkeypatch):
    root = Path(__file__).resolve().parents[2]
    text = (root / "docs" / "python.md").read_text()
    section = text.split("## Your own loop: simloop.Sim", 1)[1]
    code = section.split("```python\n", 1)[1].split("```", 1)[0]
    monkeypatch.chdir(root)
    scope: dict = {}
    exec(compile(code, "docs/python.md", "exec"), scope)  # noqa: S102 (our own docs)
    assert scope["sim"].time == 0.0 and scope["restored"].steps_taken == 350  # set_state leaves the count
    assert np.array_equal(scope["twin"].get_state(), scope["saved"])


def test_vectors_must_hold_numbers():
    sim = simloop.Sim(PUSHT)
    with pytest.raises(TypeError, match=r"ctrl\[1\] must be a number, got '0' \(str\)"):
        sim.step(1, ctrl=[0.1, "0"])
    with pytest.raises(TypeError, match="ctrl must hold numbers .* got an array of dtype <U1"):
        sim.step(1, ctrl=np.array(["a", "b"]))
    with pytest.raises(ValueError, match=r"qpos must have shape \(9,\)"):
        sim.qpos = [0.0]
    sim.qvel = np.arange(8.0)
    assert np.array_equal(sim.qvel, np.arange(8.0)) and sim.steps_taken == 0


def test_names_that_cannot_be_a_scenes_are_refused_in_one_line():
    sim = simloop.Sim(PUSHT)
    with pytest.raises(ValueError, match="body must be text that UTF-8 can encode"):
        sim.body("\udcfe")
    with pytest.raises(ValueError, match="joint must not contain a NUL character"):
        sim.joint("slide_x\0")
    with pytest.raises(ValueError, match=r"body index 2\*\*70|body index 1180591620717411303424 is out of range"):
        sim.body(2**70)
