"""Any scene from the quick flags, in both commands: bodies and actuators by
index as well as by name (a scene may leave its bodies unnamed, as MuJoCo's
tendon_arm/arm26.xml does), --ctrl alone with no shove, a scene with nothing
to push, a MuJoCo error while stepping quoting the timestep that ran, and
MuJoCo's load-time warnings on the report."""

import pytest
import simloop
from conftest import run_command
from expected import expected, stepping_error_scene

# Two links on hinges, the bodies unnamed, driven by one unnamed motor; the scene's own timestep
# is 0.004 s.
ARM = """<mujoco model="arm">
  <option timestep="0.004" gravity="0 0 0"/>
  <worldbody>
    <body pos="0 0 0"><joint name="shoulder" type="hinge" axis="0 0 1"/>
      <geom type="capsule" fromto="0 0 0 0.5 0 0" size="0.04"/>
      <body pos="0.5 0 0"><joint type="hinge" axis="0 0 1"/><geom type="capsule" fromto="0 0 0 0.4 0 0" size="0.03"/>
      </body>
    </body>
  </worldbody>
  <actuator><motor joint="shoulder" gear="1"/></actuator>
</mujoco>
"""
BOTH = pytest.mark.parametrize("python", [True, False], ids=["python-m-simloop", "sim_loop"])


def write(tmp_path, name, text):
    (tmp_path / name).write_text(text)
    return name


@BOTH
def test_an_unnamed_body_is_shoved_by_its_index(tmp_path, python):
    arm = write(tmp_path, "arm.xml", ARM)
    proc = run_command(["--model", arm, "--body", "2", "--no-rerun", "--out", "o"], tmp_path, python)
    assert proc.returncode == 0, proc.stderr
    assert "disturbance on body2: force [+0.00, +6.96, +0.00] N" in proc.stdout
    header = (tmp_path / "o" / "trajectory.csv").read_text().splitlines()[0].split(",")
    assert "body2_fy" in header and "body2_x" in header
    refused = run_command(["--model", arm, "--body", "3", "--out", "o"], tmp_path, python)
    assert refused.returncode == 2
    assert refused.stderr.endswith(
        "--body: body index 3 is out of range: the scene has 3 bodies (0 to 2); the scene's "
        "bodies a force can move: unnamed, by index: 1, 2\n"
    ), refused.stderr
    assert refused.stderr.count("\n") == 1


@BOTH
def test_ctrl_alone_runs_any_scene_without_a_shove(tmp_path, python):
    arm = write(tmp_path, "arm.xml", ARM)
    proc = run_command(["--model", arm, "--ctrl", "0=0.5", "--no-rerun", "--out", "o"], tmp_path, python)
    assert proc.returncode == 0, proc.stderr
    assert "disturbance" not in proc.stdout, proc.stdout
    header = (tmp_path / "o" / "trajectory.csv").read_text().splitlines()
    assert header[0].split(",")[:3] == ["step", "time", "actuator0_ctrl"]
    assert header[1].split(",")[2] == "0.5"
    # The chapter's own scene keeps the chapter's shove on its box.
    chapter = run_command(["--ctrl", "push_motor=0.5", "--smoke", "--no-rerun", "--out", "c"], tmp_path, python)
    assert chapter.returncode == 0, chapter.stderr
    assert "disturbance on box" in chapter.stdout


@BOTH
def test_a_mujoco_error_while_stepping_quotes_the_timestep_that_ran(tmp_path, python):
    scene, says = stepping_error_scene()
    falls = write(tmp_path, "falls.xml", scene)
    proc = run_command(["--model", falls, "--body", "b1", "--no-rerun", "--out", "o"], tmp_path, python)
    assert proc.returncode == 1
    prefix = "sim-loop: " if python else "sim_loop: "
    assert proc.stderr.startswith(
        f"{prefix}MuJoCo error while running 2000 steps of --model falls.xml (the "
        "scenario's length, timestep 0.004 s: the scene's own, --record-every 1): running "
        "the model at timestep 0.004 s, in steps "
    ), proc.stderr
    assert f": {says}" in proc.stderr, proc.stderr
    assert proc.stderr.count("\n") == 1, proc.stderr
    given = run_command(
        ["--model", falls, "--body", "b1", "--steps", "3000", "--timestep", "0.003", "--no-rerun", "--out", "o"],
        tmp_path,
        python,
    )
    assert "(--steps 3000, --timestep 0.003, --record-every 1): running the model at timestep 0.003 s" in given.stderr
    assert f": {says}" in given.stderr, given.stderr


def check_load_warning(tmp_path, python, name, warning):
    proc = run_command(["--model", name, "--smoke", "--no-rerun", "--out", "o"], tmp_path, python)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.splitlines()[1] == f"MuJoCo warning while loading the model: {warning}", proc.stdout
    assert simloop.Model.from_file(tmp_path / name).load_warnings == [warning]


@BOTH
def test_the_parsers_load_time_warning_is_on_the_report(tmp_path, python):
    scene = simloop._core.PUSHER_SCENE_XML
    nan = write(tmp_path, "nan.xml", scene.replace('rgba="0.85 0.3 0.25 1"', 'rgba="nan 0.3 0.25 1"'))
    check_load_warning(tmp_path, python, nan, "XML contains a 'NaN'. Please check it carefully.")


@BOTH
def test_the_compilers_load_time_warning_is_on_the_report(tmp_path, python):
    # No scene is known that makes MuJoCo 4.0's compiler warn; the table has one for 2.2.
    size, warning = expected("errors.load_warning_size"), expected("errors.load_warning_says")
    scene = simloop._core.PUSHER_SCENE_XML
    full = write(
        tmp_path, "full.xml", scene.replace('<compiler autolimits="true"/>', f'<compiler autolimits="true"/>{size}')
    )
    check_load_warning(tmp_path, python, full, warning)
    plain = run_command(["--smoke", "--no-rerun", "--out", "p"], tmp_path, python)
    assert "while loading" not in plain.stdout


# Nothing a force can move and no actuator: static geoms only (dm_control's
# arena), or bodies welded to the world (MuJoCo's shared scene.xml files).
ONLY_GEOMS = """<mujoco model="arena">
  <worldbody><light pos="0 0 3"/><geom name="floor" type="plane" size="2 2 0.1"/>
    <geom name="wall" type="box" pos="1 0 0.2" size="0.05 1 0.2"/></worldbody>
</mujoco>
"""
WELDED = """<mujoco model="welded">
  <worldbody><geom type="plane" size="2 2 0.1"/>
    <body name="table" pos="0 0 0.4"><geom type="box" size="0.5 0.5 0.02"/>
      <body name="lamp" pos="0 0 0.1"><geom type="sphere" size="0.05"/></body></body>
    <body name="target" mocap="true" pos="0.2 0 0.5">
      <geom type="sphere" size="0.02" contype="0" conaffinity="0"/></body>
  </worldbody>
</mujoco>
"""


@BOTH
@pytest.mark.parametrize("scene", [ONLY_GEOMS, WELDED], ids=["only-geoms", "welded"])
def test_a_scene_with_nothing_to_push_runs_and_says_so(tmp_path, python, scene):
    name = write(tmp_path, "still.xml", scene)
    proc = run_command(["--model", name, "--steps", "50", "--out", "o"], tmp_path, python)  # recording, in Python
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    assert "model: still.xml" in lines
    assert (
        "nothing could be pushed: the scene has no body a force can move and no actuator; it ran as it is" in lines
    ), proc.stdout
    rows = (tmp_path / "o" / "trajectory.csv").read_text().splitlines()
    assert len(rows) == 1 + 51 and rows[0].startswith("step,time"), rows[:2]  # a header, then steps 0 to 50
    assert (tmp_path / "o" / "sim_loop.rrd").exists() == python


@BOTH
def test_the_summary_names_the_model_file(tmp_path, python):
    chapter = write(tmp_path, "chapter.xml", simloop._core.PUSHER_SCENE_XML)
    proc = run_command(["--model", chapter, "--smoke", "--no-rerun", "--out", "o"], tmp_path, python)
    assert proc.returncode == 0, proc.stderr
    assert "model: chapter.xml" in proc.stdout.splitlines()
    assert "nothing could be pushed" not in proc.stdout
    plain = run_command(["--smoke", "--no-rerun", "--out", "p"], tmp_path, python)
    assert "model:" not in plain.stdout
