"""A scenario's recording draws every body that moves (the walker's legs, not
only its recorded torso) with its pose over time, from the same run that
writes trajectory.csv, whose bytes do not depend on the recording."""

import numpy as np
import pytest
import simloop
from conftest import ROOT, run_command
from test_recording import load_chunks

SCENES = ROOT / "tests" / "scenes"
LEGS = {  # body: (parent, its place on the parent, its hinge), as tests/scenes/walker.xml has them
    "thigh_left": ("torso", [0.0, 0.1, -0.2], "hip_left"),
    "shin_left": ("thigh_left", [0.0, 0.0, -0.4], "knee_left"),
    "thigh_right": ("torso", [0.0, -0.1, -0.2], "hip_right"),
    "shin_right": ("thigh_right", [0.0, 0.0, -0.4], "knee_right"),
}


def quat_multiply(a, b):
    """Rows of w x y z quaternions, a * b."""
    aw, ax, ay, az = a.T
    bw, bx, by, bz = b.T
    return np.stack(
        [
            aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
        ],
        axis=1,
    )


def rotate(q, v):
    """Rotates the vector v by each row of q (w x y z)."""
    p = np.concatenate([np.zeros((len(q), 1)), np.tile(v, (len(q), 1))], axis=1)
    conjugate = q * np.array([1.0, -1.0, -1.0, -1.0])
    return quat_multiply(quat_multiply(q, p), conjugate)[:, 1:]


def forward_kinematics(result):
    """Every leg body's world pose from the torso's recorded pose and the recorded hinge angles."""
    poses = {
        "torso": (
            np.stack([result.column("torso_" + a) for a in "xyz"], axis=1),
            np.stack([result.column("torso_" + a) for a in ("qw", "qx", "qy", "qz")], axis=1),
        )
    }
    for body, (parent, offset, hinge) in LEGS.items():  # parents come first
        position, orientation = poses[parent]
        half = result.column(hinge + "_pos") / 2  # about the body's y axis
        turn = np.stack([np.cos(half), np.zeros_like(half), np.sin(half), np.zeros_like(half)], axis=1)
        poses[body] = (position + rotate(orientation, offset), quat_multiply(orientation, turn))
    return poses


@pytest.fixture(scope="module")
def walker_with_joints(tmp_path_factory):
    """The walker's scenario recording its torso and its four hinges, with a torso mass of each run's own, run with
    and without a recording."""
    tmp = tmp_path_factory.mktemp("walker")
    text = (SCENES / "walker.toml").read_text().replace('scene = "walker.xml"', f'scene = "{SCENES / "walker.xml"}"')
    scenario = tmp / "walker_joints.toml"
    scenario.write_text(
        text + '\n[record]\nbodies = ["torso"]\n'
        'joints = ["hip_left", "knee_left", "hip_right", "knee_right"]\n'
        '[[reset.param]]\nkind = "mass"\nname = "torso"\nuniform = [6.0, 9.0]\n'
    )
    for flags, out in ((["--record-every", "3"], "r"), (["--record-every", "3", "--no-rerun"], "n")):
        proc = run_command(["--scenario", str(scenario), *flags, "--out", out], tmp)
        assert proc.returncode == 0, proc.stderr
    proc = run_command(["--scenario", str(scenario), "--record-every", "3", "--out", "c"], tmp, python=False)
    assert proc.returncode == 0, proc.stderr
    return tmp, simloop.run_scenario(scenario, record_every=3)


def test_the_legs_move_as_forward_kinematics_of_the_recorded_angles(walker_with_joints):
    tmp, result = walker_with_joints
    chunks = load_chunks(tmp / "r" / "sim_loop.rrd")
    for body, (position, orientation) in forward_kinematics(result).items():
        entity = chunks[(f"/world/bodies/{body}", False)]
        assert entity["step"] == list(result.column("step").astype(int)), body  # every recorded row, in order
        translation = np.array([t[0] for t in entity["Transform3D:translation"]])
        quaternion = np.array([q[0] for q in entity["Transform3D:quaternion"]])[:, [3, 0, 1, 2]]  # x y z w -> w x y z
        # rerun keeps float32: within its precision.
        np.testing.assert_allclose(translation, position, rtol=0, atol=2e-6, err_msg=body)
        same_rotation = np.minimum(
            np.abs(quaternion - orientation).max(axis=1), np.abs(quaternion + orientation).max(axis=1)
        )
        assert same_rotation.max() < 2e-6, body
    # The legs turn over the run: the check above is not of bodies standing still.
    assert np.ptp(result.column("knee_left_pos")) > 0.3
    for geom in ("thigh_left/thigh_left", "shin_left/foot_left", "shin_right/shin_right"):
        assert (f"/world/bodies/{geom}", True) in chunks


def test_the_recording_changes_nothing_in_the_outputs(walker_with_joints):
    tmp, result = walker_with_joints
    for name in ("trajectory.csv", "metrics.json"):
        assert (tmp / "r" / name).read_bytes() == (tmp / "n" / name).read_bytes() == (tmp / "c" / name).read_bytes()
    header = (tmp / "r" / "trajectory.csv").read_text().splitlines()[0].split(",")
    assert header == list(result.column_names)
    assert not any(c.startswith(("thigh", "shin")) for c in header)  # not recorded, yet drawn


def test_every_moving_body_of_the_walker_is_drawn(tmp_path):
    proc = run_command(["--scenario", str(SCENES / "walker.toml"), "--out", "w"], tmp_path)
    assert proc.returncode == 0, proc.stderr
    chunks = load_chunks(tmp_path / "w" / "sim_loop.rrd")
    result = simloop.run_scenario(SCENES / "walker.toml")
    assert list(result.bodies) == ["torso"]  # what the scenario records
    moving = list(
        simloop._core.moving_bodies(result_model := simloop.Scenario.from_file(SCENES / "walker.toml").model())
    )
    assert sorted(moving) == sorted(["torso", *LEGS])
    for body in moving:
        assert len(chunks[(f"/world/bodies/{body}", False)]["Transform3D:translation"]) == result.rows, body
    torso = np.array([t[0] for t in chunks[("/world/bodies/torso", False)]["Transform3D:translation"]])
    np.testing.assert_allclose(torso[:, 2], result.column("torso_z"), rtol=0, atol=2e-6)
    z = np.array([v[0] for v in chunks[("/plots/torso_z", False)]["Scalars:scalars"]])
    np.testing.assert_array_equal(z, result.column("torso_z"))  # the plots keep float64, every row
    assert result_model.nq == 11


def test_a_drawing_that_fails_writes_nothing(tmp_path, monkeypatch):
    """The command's run into --out with a recording whose rows() raises: the
    error reaches Python as itself, and nothing is put in place."""
    from simloop import __main__ as command

    class Broken:
        files: list = []

        def columns(self, names):
            pass

        def rows(self, block):
            raise RuntimeError("the drawing broke (test)")

        def close(self):
            pass

    monkeypatch.setattr(command, "_drawings", lambda *args: (command._Drawings([Broken()]), "recording: none (test)"))
    (tmp_path / "o").mkdir()  # the run's folder: left as it was
    args = ["--scenario", str(SCENES / "pusht.toml"), "--steps", "50", "--out", str(tmp_path / "o")]
    with pytest.raises(RuntimeError, match="the drawing broke"):
        command._run(args)
    assert list((tmp_path / "o").iterdir()) == []  # no outputs, no temporary files


def test_a_scenarios_plots_are_grouped_by_quantity_with_units():
    """One panel per quantity, named with its unit: a pose's quaternion is not
    plotted with its positions, nor a force with a velocity."""
    from simloop._rerun_parts import QUANTITIES

    result = simloop.run_scenario(simloop.Scenario.from_file(ROOT / "tests/scenes/pusht.toml"), steps=2)
    panels = {}
    for name, unit in result.column_units.items():
        if name not in ("step", "time"):
            panels.setdefault(next(title for title, holds in QUANTITIES if holds(name, unit)), []).append(name)
    assert {"tblock_x", "tblock_y", "tblock_z", "pusher_x", "slide_x_pos"} <= set(panels["positions (m)"])
    assert {"tblock_qw", "tblock_qz"} <= set(panels["orientations (quaternion w x y z)"])
    assert {"tblock_vx", "tblock_wz", "slide_x_vel"} <= set(panels["velocities (m/s, rad/s)"])
    assert {"tblock_fx", "tblock_tz", "push_x_force"} <= set(panels["forces (N, N m)"])
    assert panels["controls"] == ["push_x_ctrl", "push_y_ctrl"]
    assert panels["contacts"] == ["contacts"]
    assert not any(name.endswith(("_qw", "_qx", "_qy", "_qz")) for name in panels["positions (m)"])
