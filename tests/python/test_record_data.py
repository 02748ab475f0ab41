"""[record]'s data: any of mjData's arrays of numbers by object (a body's cfrc_ext, cvel, subtree_com; a joint's
qfrc_actuator; a sensor's sensordata), columns `<object>_<array>` with MuJoCo's values for each row's state."""

import numpy as np
import pytest
import simloop

DATA = [("cfrc_ext", "box"), ("cvel", "box"), ("subtree_com", "pusher"), ("qfrc_actuator", "pusher_slide")]


def pushed(steps: int = 300) -> simloop.Scenario:
    # The chapter's scene, the pusher driven at ctrl 1.0 into the box (it touches the box near step 150).
    return simloop.Scenario(steps=steps, controls={"push_motor": 1.0}, record={"bodies": ["box"], "data": DATA})


def test_columns_are_named_object_then_array():
    result = simloop.run_scenario(pushed(10), seed=0)
    names = [c for c in result.columns if any(array in c for array, _ in DATA)]
    assert names == (
        [f"box_cfrc_ext{i}" for i in range(6)]
        + [f"box_cvel{i}" for i in range(6)]
        + ["pusher_subtree_com0", "pusher_subtree_com1", "pusher_subtree_com2", "pusher_slide_qfrc_actuator"]
    )


def test_each_row_holds_what_mujoco_derives_for_its_state():
    # Row k holds the state entering step k; a Sim that has taken k + 1 steps holds, in its derived arrays, what
    # MuJoCo derived for that same state (cfrc_ext filled by mj_rnePostConstraint when read): bit for bit.
    steps = 300
    result = simloop.run_scenario(pushed(steps), seed=0)
    sim = simloop.Sim()
    pressed = 0
    for k in range(steps):
        sim.step(1, ctrl=1.0)
        for array, name in DATA:
            expected = np.atleast_1d(getattr(sim.named.data, array)[name])
            got = [
                result.column(f"{name}_{array}{i}" if len(expected) > 1 else f"{name}_{array}")[k]
                for i in range(len(expected))
            ]
            assert got == expected.tolist(), (k, array)
        pressed += result.column("box_cfrc_ext3")[k] > 1.0  # the pusher's push along +x
    assert pressed > 50  # the box is pressed for many of the rows, its cfrc_ext not zero


def test_a_sensor_by_name_and_a_site_in_a_scene_with_them():
    scene = simloop.__file__.replace("__init__.py", "scenes/pusht.xml")
    scenario = simloop.Scenario(
        scene, steps=20, record={"sensors": ["tblock_pos"], "data": [("sensordata", "tblock_pos"), ("xpos", "tblock")]}
    )
    result = simloop.run_scenario(scenario, seed=0)
    for i in range(3):  # the same values as the sensor's own columns, and as the body's frame position
        np.testing.assert_array_equal(result.column(f"tblock_pos_sensordata{i}"), result.column(f"tblock_pos{i}"))
        np.testing.assert_array_equal(result.column(f"tblock_xpos{i}"), result.column(f"tblock_pos{i}"))


@pytest.mark.parametrize(
    ("data", "message"),
    [
        ([("cfrc_extt", "box")], r"record.data\[0\]: no mjData array named 'cfrc_extt' \(did you mean 'cfrc_ext'\?\)"),
        ([("cfrc_ext", "boxx")], r"record.data\[0\]: no body named 'boxx' \(did you mean 'box'\?\)"),
        ([("qpos", "pusher_slide")], r"record.data\[0\]: mjData's qpos is the state or an input: record joints"),
        ([("efc_force", "box")], r"record.data\[0\]: mjData's efc_force's rows are not objects \(its rows: nefc\)"),
        ([("cfrc_ext", "box", "pusher")], r"record.data: expected an array of \[array, object\] pairs"),
    ],
)
def test_a_wrong_entry_is_refused_naming_it(data, message):
    with pytest.raises(ValueError, match=message):
        simloop.run_scenario(simloop.Scenario(steps=5, record={"data": data}), seed=0)


# The walker (tests/scenes/walker.xml) falls to the floor under its own weight: its torso's imu site, and the
# torso's contact forces.
WALKER_RECORD = {"joints": "all", "data": [("site_xpos", "imu"), ("cfrc_ext", "torso")], "contacts": False}


def walker(steps: int = 200) -> simloop.Scenario:
    from pathlib import Path

    return simloop.Scenario(Path(__file__).parents[1] / "scenes" / "walker.xml", steps=steps, record=WALKER_RECORD)


def test_an_envs_observation_reads_them_as_a_runs_row_does():
    # Actions of zero, no controls and no disturbances: each observation is the state entering the next step, derived
    # by a whole forward pass (cfrc_ext is not of the first half of a step), the run's row k derived by its mj_step:
    # the same bits, cfrc_ext included.
    gym_module = pytest.importorskip("simloop.gym", reason="needs gymnasium (the gym extra)")
    scenario = walker()
    rows = simloop.run_scenario(scenario, seed=0)
    env = gym_module.ScenarioEnv(scenario)
    obs, _ = env.reset(seed=0)
    width = len(env.observation_names)
    torso_force_z = env.observation_names.index("torso_cfrc_ext5")
    touched = 0
    for k in range(199):
        assert obs.tolist() == rows.trajectory[k, 2 : 2 + width].tolist(), k
        touched += obs[torso_force_z] != 0.0
        obs = env.step(np.zeros(env.action_space.shape))[0]
    assert touched > 0  # the torso lands: its contact force is read, not zero


def test_a_batched_reward_over_a_sites_position_is_the_plain_ones_on_any_threads():
    # The fast path: the imu site's position recorded as columns, a reward over them batched (no Python per env),
    # against the same reward per env, on 1 and 2 threads: the same returns, bit for bit.
    gym_module = pytest.importorskip("simloop.gym", reason="needs gymnasium (the gym extra)")
    names = gym_module.ScenarioEnv(walker()).observation_names
    z = names.index("imu_site_xpos2")

    def plain(obs, action, next_obs):
        return float(next_obs[z] - obs[z])

    batched = gym_module.batched(lambda obs, action, next_obs: next_obs[:, z] - obs[:, z])
    rng = np.random.default_rng(7)
    actions = rng.uniform(-1.0, 1.0, size=(40, 3, 4))
    returns = {}
    for label, reward, threads in (("plain", plain, 1), ("batched", batched, 1), ("batched2", batched, 2)):
        env = gym_module.ScenarioVectorEnv(walker(), 3, control_every=5, reward=reward, threads=threads)
        env.reset(seed=[0, 1, 2])
        total = np.zeros(3)
        for a in actions:
            total += env.step(a)[1]
        returns[label] = total.tolist()
    assert returns["plain"] == returns["batched"] == returns["batched2"]
    assert any(r != 0.0 for r in returns["plain"])


def test_contact_forces_between_two_named_bodies_or_geoms():
    # [record] contact_forces: [a, b], the force b gets from a, summed over their contacts, world frame. Row k against
    # a Sim that has taken k + 1 steps: its contacts' forces (each acting on geom2, its frame's rows normal then
    # tangents) summed for the pair; and the box's cfrc_ext force is the pusher's on it plus the floor's.
    steps = 300
    pairs = [("pusher", "box"), ("floor", "box_geom")]  # bodies or geoms by name (the floor is a geom of the world)
    scenario = simloop.Scenario(
        steps=steps, controls={"push_motor": 1.0}, record={"data": [("cfrc_ext", "box")], "contact_forces": pairs}
    )
    result = simloop.run_scenario(scenario, seed=0)
    assert [c for c in result.columns if "contact_force" in c] == [
        f"{a}_{b}_contact_force{i}" for a, b in pairs for i in range(3)
    ]
    sim = simloop.Sim()
    pressed = 0
    for k in range(steps):
        sim.step(1, ctrl=1.0)
        for (a, b), geoms in zip(pairs, ({"pusher_geom", "box_geom"}, {"floor", "box_geom"})):
            expected = np.zeros(3)
            for c in sim.contacts:
                if {c.geom1, c.geom2} == geoms:
                    on_second = c.geom2 == ("box_geom" if b.startswith("box") else b)
                    expected += (1.0 if on_second else -1.0) * (c.frame.T @ c.force[:3])
            got = [result.column(f"{a}_{b}_contact_force{i}")[k] for i in range(3)]
            np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-12)
        total = sum(np.array([result.column(f"{a}_{b}_contact_force{i}")[k] for i in range(3)]) for a, b in pairs)
        np.testing.assert_allclose([result.column(f"box_cfrc_ext{i}")[k] for i in (3, 4, 5)], total, atol=1e-9)
        pressed += result.column("pusher_box_contact_force0")[k] > 1.0  # the pusher pushes the box along +x
    assert pressed > 50


def test_contact_forces_in_a_scenario_file_and_a_wrong_name(tmp_path):
    path = tmp_path / "pressed.toml"
    path.write_text('steps = 5\n[record]\ncontact_forces = [["pusher", "box"]]\n')
    result = simloop.run_scenario(simloop.Scenario.from_file(path), seed=0)
    assert "pusher_box_contact_force2" in result.columns
    # A side is a geom or a body: a name neither has is refused naming both, with the likely one.
    with pytest.raises(
        ValueError,
        match=r"^record.contact_forces\[0\]: no geom or body named 'boxx' \(did you mean 'box'\?\); "
        r"the scene's geoms: floor, box_geom, pusher_geom; the scene's bodies: world, box, pusher$",
    ):
        simloop.run_scenario(simloop.Scenario(steps=5, record={"contact_forces": [("pusher", "boxx")]}), seed=0)
    with pytest.raises(ValueError, match=r"no geom or body named 'flor' \(did you mean 'floor'\?\)"):
        simloop.run_scenario(simloop.Scenario(steps=5, record={"contact_forces": [("flor", "box")]}), seed=0)
    with pytest.raises(ValueError, match=r"^record.contact_forces\[0\]: body index 7 is out of range"):
        simloop.run_scenario(simloop.Scenario(steps=5, record={"contact_forces": [("7", "box")]}), seed=0)
    result = simloop.run_scenario(simloop.Scenario(steps=5, record={"contact_forces": [("1", "floor")]}), seed=0)
    assert "1_floor_contact_force0" in result.columns  # body 1 (the box), by index
