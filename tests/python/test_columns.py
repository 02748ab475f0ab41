"""One name, one quantity: a column name means the same quantity wherever it
appears, the chapter's trajectory, a scenario's records and a policy's
observations (docs/cli.md's table of columns)."""

import numpy as np
import pytest
import simloop

# Read the same way by the chapter and by its scenario: a shared name must
# hold the same bits.
SHARED = {"step", "time", "ncon"} | {
    "box_" + q for q in ("x", "y", "z", "qw", "qx", "qy", "qz", "vx", "vy", "vz", "wx", "wy", "wz")
}


def same_bits(a, b):
    """Equal bit for bit, NaN where NaN (the final row's inputs)."""
    return a.shape == b.shape and np.array_equal(a, b, equal_nan=True) and np.array_equal(np.signbit(a), np.signbit(b))


@pytest.mark.parametrize("audit", [False, True])
@pytest.mark.parametrize("rng", ["mt19937_64", "numpy"])
@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_every_column_the_chapter_and_its_scenario_both_name_holds_the_same_bits(seed, rng, audit):
    chapter = simloop.run(seed=seed, rng=rng, audit_energy=audit)
    scenario = simloop.run_scenario(simloop.Scenario.chapter(), seed=seed, rng=rng, audit_energy=audit)
    both = set(chapter.column_names) & set(scenario.column_names)
    assert both >= SHARED | (set(simloop.ENERGY_COLUMN_NAMES) if audit else set()), sorted(SHARED - both)
    assert chapter.energy == scenario.energy  # None without the audit
    assert chapter.rows == scenario.rows == 2001
    for name in sorted(both):
        assert same_bits(chapter.column(name), scenario.column(name)), name
        assert chapter.column_units[name] == scenario.column_units[name], name


def test_the_chapters_pusher_columns_are_its_pusher_bodys_in_its_scene():
    # pusher_x and pusher_vx are the chapter's pusher joint's; in the chapter's
    # scene the pusher body starts at x = 0 and slides along x, so a scenario
    # recording that body names the same numbers.
    chapter = simloop.run(seed=0, perturb=False)
    scenario = simloop.Scenario(controls={"push_motor": 1.0}, record={"bodies": ["box", "pusher"], "ncon": True})
    result = simloop.run_scenario(scenario)
    both = set(chapter.column_names) & set(result.column_names)
    assert both >= SHARED | {"pusher_x", "pusher_vx"}
    for name in sorted(both):
        assert same_bits(chapter.column(name), result.column(name)), name


def test_the_contacts_of_a_rows_state_have_their_own_name():
    # ncon is the count as the step began (the previous step's collision);
    # contacts is the count of the row's own state: one row later.
    scenario = simloop.Scenario(
        steps=1000, controls={"push_motor": 1.0}, record={"bodies": ["box"], "contacts": True, "ncon": True}
    )
    result = simloop.run_scenario(scenario)
    ncon, contacts = result.column("ncon"), result.column("contacts")
    assert np.array_equal(ncon[1:], contacts[:-1])
    assert ncon[0] == contacts[0] and not np.array_equal(ncon, contacts)  # row 0: the initial forward's
    assert result.column_units["contacts"] == result.column_units["ncon"] == ""
    default = simloop.run_scenario(simloop.Scenario(steps=10))
    assert "contacts" in default.column_names and "ncon" not in default.column_names


@pytest.mark.parametrize("every", [1, 7])
def test_a_policys_decisions_leave_each_rows_ncon_as_the_open_loop_runs(every):
    # A decision derives the state again (mj_step1 runs the collision), which
    # changes MuJoCo's count: the row and the observation keep the count the
    # step began with.
    seen = {}

    def full_throttle(obs):
        seen[obs.step] = (obs["ncon"], obs["box_wz"])
        return [1.0]

    open_loop = simloop.run_scenario(simloop.Scenario.chapter(), seed=3)
    closed = simloop.run_scenario(simloop.Scenario.chapter(), seed=3, policy=full_throttle, control_every=every)
    assert closed.column_names == open_loop.column_names
    for name in open_loop.column_names:
        assert same_bits(closed.column(name), open_loop.column(name)), name
    ncon, wz = open_loop.column("ncon"), open_loop.column("box_wz")
    assert seen and all(seen[step] == (ncon[step], wz[step]) for step in seen)
    assert len(set(ncon[list(seen)])) > 1  # the count changes at decision steps


TILTED = """<mujoco>
  <worldbody>
    <body name="arm" pos="0 0 1" euler="40 0 30">
      <joint name="hinge" type="hinge" axis="0 1 1" pos="-0.2 0.1 0"/>
      <geom type="capsule" size="0.05" fromto="0 0 0 0.4 0 0" mass="1"/>
      <site name="arm_frame"/>
    </body>
    <body name="free" pos="0 0 2" euler="20 50 0">
      <freejoint/>
      <geom type="box" size="0.1 0.2 0.3" mass="1"/>
      <site name="free_frame"/>
    </body>
  </worldbody>
  <sensor>
    <gyro name="arm_gyro" site="arm_frame"/>
    <gyro name="free_gyro" site="free_frame"/>
    <velocimeter name="arm_velocimeter" site="arm_frame"/>
  </sensor>
</mujoco>
"""


def test_angular_velocity_is_in_the_bodys_own_frame_for_any_body(tmp_path):
    # A gyro at the body's frame measures the angular velocity in that frame:
    # the free body's (its qvel) and the hinged body's agree with theirs.
    (tmp_path / "tilted.xml").write_text(TILTED)
    scenario = simloop.Scenario(
        scene=tmp_path / "tilted.xml",
        steps=200,
        record={"bodies": ["arm", "free"], "sensors": ["arm_gyro", "free_gyro", "arm_velocimeter"]},
        reset={"qvel": [2.0, 0.3, -0.2, 0.1, 1.5, -2.0, 0.7]},
    )
    result = simloop.run_scenario(scenario)
    for body in ("arm", "free"):
        local = np.column_stack([result.column(f"{body}_w{a}") for a in "xyz"])
        gyro = np.column_stack([result.column(f"{body}_gyro{i}") for i in range(3)])
        np.testing.assert_allclose(local, gyro, rtol=1e-12, atol=1e-12)
        assert np.abs(local).max() > 0.5
    # ... and the linear velocity is its origin's in the world frame: the
    # velocimeter's (the origin's, in the body frame) turned into the world's.
    world = np.column_stack([result.column(f"arm_v{a}") for a in "xyz"])
    body = np.column_stack([result.column(f"arm_velocimeter{i}") for i in range(3)])
    quat = np.column_stack([result.column(f"arm_q{a}") for a in "wxyz"])
    t = 2.0 * np.cross(quat[:, 1:], body)
    np.testing.assert_allclose(world, body + quat[:, :1] * t + np.cross(quat[:, 1:], t), rtol=1e-12, atol=1e-12)
    assert np.abs(world - body).max() > 0.1
    # A free body's are its joint's qvel, as written: (vx vy vz wx wy wz).
    first = [result.column(f"free_{q}")[0] for q in ("vx", "vy", "vz", "wx", "wy", "wz")]
    assert first == [0.3, -0.2, 0.1, 1.5, -2.0, 0.7]
