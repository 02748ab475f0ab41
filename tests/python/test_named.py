"""Sim.named: every mjModel and mjData array with rows by name (views, not
copies), the parameters a trainer randomises written into the Sim's own
model, contact forces, and every kind of object's names."""

import copy
import pickle
from pathlib import Path

import numpy as np
import pytest
import simloop


def test_rows_are_named_by_the_objects_they_are():
    sim = simloop.Sim()
    named = sim.named
    assert named.data.xpos["box"].tolist() == [0.4, 0.0, 0.05]
    assert named.model.geom_friction["floor"].tolist() == [1.0, 0.005, 0.0001]
    assert named.model.actuator_gear["push_motor"][0] == 10.0
    assert named.data.qpos["pusher_slide"].tolist() == [0.0]  # a joint's slice of qpos...
    assert named.data.qvel["pusher_slide"].shape == (1,)  # ...and of qvel
    assert named.data.xpos[["box", "pusher"]].shape == (2, 3)
    assert named.data.xpos["box", 2] == 0.05
    assert named.model.body_mass.names == ("world", "box", "pusher")
    assert np.asarray(named.model.body_mass).tolist() == [0.0, 0.5, 1.0]
    # sensordata by sensor: each sensor's slice of its values, as dm_control's named has it.
    pusht = simloop.Sim(model=Path(simloop.__file__).parent / "scenes" / "pusht.xml")
    pusht.step(5)
    sensors = pusht.named.data.sensordata
    assert sensors.names == ("tblock_pos", "tip_x")
    np.testing.assert_array_equal(sensors["tblock_pos"], pusht.sensor("tblock_pos").data)
    assert sensors["tip_x"].shape == (1,) and sensors["tblock_pos"].shape == (3,)


def test_views_are_mujocos_own_memory():
    sim = simloop.Sim()
    xpos = sim.named.data.xpos
    sim.step(300, ctrl=1.0)
    assert xpos["box"][0] > 0.4  # the same view, moved on with the Sim
    sim.named.data.qpos["pusher_slide"] = [0.25]  # the state is writable
    assert sim.qpos[7] == 0.25
    with pytest.raises(ValueError, match="xpos is read-only here"):
        sim.named.data.xpos["box"] = [0, 0, 0]
    assert not sim.named.data.cfrc_ext.array.flags.writeable


def test_a_written_parameter_is_the_sims_own_and_changes_its_run():
    shared = simloop.Model.pusher_scene()
    slippery, rough = simloop.Sim(shared), simloop.Sim(shared)
    slippery.named.model.geom_friction["floor"] = [0.0, 0.005, 0.0001]
    slippery.named.model.geom_friction["box_geom"] = [0.0, 0.005, 0.0001]  # MuJoCo takes the larger of the two
    for sim in (slippery, rough):
        sim.qvel[0] = 1.0  # the box slides along x at 1 m/s
        sim.step(100)
    assert slippery.qvel[0] > 0.99 and rough.qvel[0] < 0.1
    assert rough.named.model.geom_friction["floor"][0] == 1.0  # the shared model is untouched
    assert simloop.Sim(shared).named.model.geom_friction["floor"][0] == 1.0
    # A copy and a pickle carry the written model; the copy's writes are its own.
    twin = copy.copy(slippery)
    assert twin.named.model.geom_friction["floor"][0] == 0.0
    twin.named.model.geom_friction["floor"] = [0.7, 0.005, 0.0001]
    assert slippery.named.model.geom_friction["floor"][0] == 0.0
    assert pickle.loads(pickle.dumps(slippery)).named.model.geom_friction["floor"][0] == 0.0


def test_what_cannot_be_written_or_found_says_so():
    sim = simloop.Sim()
    with pytest.raises(ValueError, match=r"^geom_size is read-only here"):
        sim.named.model.geom_size["floor"] = [1, 1, 1]
    with pytest.raises(ValueError, match=r"must be finite"):
        sim.named.model.body_mass["box"] = float("nan")
    # Values with no physical meaning below 0, as a scene parameter refuses them (a negative mass
    # turned the next steps' state to NaN); 0 is a value, and a gear may be negative.
    with pytest.raises(ValueError, match=r"^body_mass\['box'\] must be >= 0, got -1.0 \(float\)$"):
        sim.named.model.body_mass["box"] = -1.0
    with pytest.raises(ValueError, match=r"must be >= 0"):
        sim.named.model.geom_friction["floor"] = [1.0, -0.005, 0.0001]
    assert set(simloop._core.NONNEGATIVE_MODEL_FIELDS) < set(simloop._core.WRITABLE_MODEL_FIELDS)
    assert "body_mass" in simloop._core.NONNEGATIVE_MODEL_FIELDS
    zero = simloop.Sim()
    zero.named.model.dof_damping["pusher_slide"] = 0.0
    zero.named.model.actuator_gear["push_motor"] = [-1.0, 0, 0, 0, 0, 0]
    assert zero.named.model.actuator_gear["push_motor"][0] == -1.0
    with pytest.raises(KeyError, match=r"no row named 'boxx' \(did you mean 'box'\?\); its rows: world, box, pusher"):
        sim.named.data.xpos["boxx"]
    with pytest.raises(
        AttributeError,
        match=r"^mjModel has no array named 'geom_fricton' \(did you mean "
        r"'geom_friction'\?\)$",
    ):
        sim.named.model.geom_fricton
    with pytest.raises(KeyError, match="rows have no names: index them by number"):
        sim.named.data.efc_force["box"]
    assert sim.named.model.body_mass["box"] == 0.5  # nothing was written


def test_contacts_carry_their_forces():
    sim = simloop.Sim()
    sim.step(200)  # at rest
    box = [c for c in sim.contacts if "box_geom" in (c.geom1, c.geom2)]
    assert box and all(c.frame.shape == (3, 3) and c.force.shape == (6,) for c in box)
    assert sum(c.force[0] for c in box) == pytest.approx(0.5 * 9.81, abs=1e-3)  # the box's weight
    assert sim.named.data.efc_force.array.shape == (sim.named.data.efc_type.array.shape[0],)


def test_cfrc_ext_is_mujocos_contact_force_on_a_body():
    # No step computes cfrc_ext (mj_rnePostConstraint does): a read of it, cacc or cfrc_int fills them. The chapter's
    # pusher driven at ctrl 1.0 reaches the box at step 150 (measured: 140 N over 4 or 5 contacts as it arrives, on
    # MuJoCo 2.2.2 and 4.0.0) and presses it for most of the next 250 steps (2.36 N on each of 2 contacts at step 200
    # on 4.0.0). At every pressed step the box's cfrc_ext force (its last three values, world frame) is the sum of
    # the forces its contacts put on it (the pusher's and the floor's, normal and friction).
    sim = simloop.Sim()
    pressed = 0
    for _ in range(400):
        sim.step(1, ctrl=1.0)
        if not any({c.geom1, c.geom2} == {"box_geom", "pusher_geom"} and c.force[0] > 1.0 for c in sim.contacts):
            continue
        pressed += 1
        on_box = np.zeros(3)
        for c in sim.contacts:
            if "box_geom" in (c.geom1, c.geom2):  # a contact's force acts on geom2, its opposite on geom1
                on_box += (1.0 if c.geom2 == "box_geom" else -1.0) * (c.frame.T @ c.force[:3])
        cfrc_ext = sim.named.data.cfrc_ext["box"]
        np.testing.assert_allclose(cfrc_ext[3:], on_box, rtol=1e-12, atol=1e-9)
        assert np.abs(cfrc_ext[3:]).max() > 0.5  # not the zeros no step fills
    assert pressed > 100
    assert sim.named.data.cacc["box"][5] > 0.0  # (MuJoCo counts gravity as the world accelerating up)


def test_every_kind_of_object_has_its_names():
    model = simloop.Model.pusher_scene()
    assert model.names("geom") == ["floor", "box_geom", "pusher_geom"]
    assert model.names("light") == [""]
    assert model.names("tendon") == []
    with pytest.raises(ValueError, match=r"^kind must be one of 'body', 'joint', 'geom'"):
        model.names("widget")
    for kind in simloop._core.OBJECT_KINDS:
        assert isinstance(model.names(kind), list)


def test_a_written_colour_is_what_the_renderer_draws():
    sim = simloop.Sim()
    renderer = simloop.Renderer(sim, width=48, height=32)
    sim.named.model.geom_rgba["box_geom"] = [0.1, 0.8, 0.1, 1.0]
    r, g, b = renderer.render(sim, track="box")[16, 24].astype(int)
    assert g > 2 * r and g > 2 * b
