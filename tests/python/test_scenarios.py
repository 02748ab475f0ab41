"""Scenarios: the chapter's loop on scenes written here (a PushT scene, a
puck on two slides pushed by a two-link arm, a four-motor walker), from both
commands and from Python: the same bytes, twice, and a recording of the
scene's own shapes."""

import concurrent.futures
import json
import subprocess
from pathlib import Path

import numpy as np
import pytest
import simloop
from conftest import ROOT, run_command, sim_loop_exe
from test_recording import load_chunks

SCENES = ROOT / "tests" / "scenes"
SCENARIOS = ["pusht.toml", "arm_push.toml", "walker.toml"]


def outputs(directory: Path) -> tuple:
    return (directory / "metrics.json").read_bytes(), (directory / "trajectory.csv").read_bytes()


@pytest.mark.parametrize("name", SCENARIOS)
def test_both_commands_and_python_write_the_same_bytes_twice(tmp_path, name):
    scenario = SCENES / name
    runs = {}
    for label, python in (("cpp1", False), ("cpp2", False), ("py", True)):
        proc = run_command(["--scenario", str(scenario), "--no-rerun", "--out", label], tmp_path, python=python)
        assert proc.returncode == 0, proc.stderr
        assert proc.stderr == ""
        runs[label] = outputs(tmp_path / label)
    result = simloop.run_scenario(scenario)
    result.write(tmp_path / "api")
    runs["api"] = outputs(tmp_path / "api")
    assert runs["cpp1"] == runs["cpp2"] == runs["py"] == runs["api"]
    metrics_text = runs["api"][0].decode()
    # byte for byte what Python's json module writes for the same dict
    assert metrics_text == json.dumps(json.loads(metrics_text), indent=2, sort_keys=True) + "\n"
    header = runs["api"][1].decode().splitlines()[0].split(",")
    assert header == list(result.column_names)
    assert result.trajectory.shape == (result.rows, len(header))


ENERGY_COLUMNS = list(simloop.ENERGY_COLUMN_NAMES)


def test_a_scenarios_energy_audit_adds_its_columns_and_changes_nothing_else(tmp_path):
    flags = ["--scenario", str(SCENES / "pusht.toml"), "--steps", "400", "--no-rerun"]
    plain = run_command([*flags, "--out", "plain"], tmp_path, python=False)
    assert plain.returncode == 0, plain.stderr
    tables = {}
    for python in (False, True):
        proc = run_command([*flags, "--energy-audit", "--out", f"audit{python}"], tmp_path, python=python)
        assert proc.returncode == 0, proc.stderr
        (line,) = [x for x in proc.stdout.splitlines() if x.startswith("energy audit: change ")]
        assert "work by actuators " in line and "disturbances " in line and "unexplained " in line
        tables[python] = outputs(tmp_path / f"audit{python}")
    result = simloop.run_scenario(SCENES / "pusht.toml", steps=400, audit_energy=True)
    result.write(tmp_path / "api")
    assert tables[False] == tables[True] == outputs(tmp_path / "api")
    assert result.energy["unexplained"] == result.column("energy_unexplained")[-1]
    with pytest.raises(ValueError, match="audit_energy is not sent to an executor"):
        simloop.run_scenario_batch(SCENES / "pusht.toml", executor=concurrent.futures.Executor(), audit_energy=True)
    assert tables[False][0] == outputs(tmp_path / "plain")[0]  # the same metrics.json
    audited = [row.split(",") for row in tables[False][1].decode().splitlines()]
    unaudited = [row.split(",") for row in outputs(tmp_path / "plain")[1].decode().splitlines()]
    width = len(unaudited[0])
    assert audited[0] == unaudited[0] + ENERGY_COLUMNS
    assert [row[:width] for row in audited] == unaudited  # the audit changes no physics
    assert float(audited[1][width]) > 0 and float(audited[-1][width + 1]) > 0  # energy, the actuators' work


def test_the_python_result_holds_what_the_scenario_asked():
    result = simloop.run_scenario(simloop.Scenario.from_file(SCENES / "pusht.toml"), seed=3)
    assert result.timestep == 0.002 and result.steps == 1000 and result.rows == 1001
    push_y = result.column("push_y_ctrl")
    assert push_y[249] == 0.0 and push_y[250] == 0.4 and push_y[500] == 1.0  # 2.0 asked, clamped to ctrlrange
    assert np.isnan(push_y[-1])
    (bump,) = result.disturbances
    fy = result.column("tblock_fy")
    assert bump["body"] == "tblock" and bump["start_step"] == 600 and bump["end_step"] == 650
    assert fy[600] == bump["force"][1] != 0.0 and fy[599] == 0.0 and fy[650] == 0.0
    assert 0.5 <= abs(bump["force"][1]) < 1.5
    assert result.metrics["bodies"]["tblock"]["final_pos"] == [
        round(v, 6)
        for v in (result.column("tblock_x")[-1], result.column("tblock_y")[-1], result.column("tblock_z")[-1])
    ]
    assert result.column_units["tblock_x"] == "m"
    # Each column its own unit: a quaternion has none, a velocity's angular part is rad/s, a torque N m.
    units = result.column_units
    assert [units[f"tblock_{c}"] for c in ("qw", "vx", "wz", "fy", "tz")] == ["", "m/s", "rad/s", "N", "N m"]
    free = simloop.run_scenario(simloop.Scenario(steps=2, record=dict(joints="all"))).column_units  # the box's
    assert [free[f"joint0_pos{i}"] for i in (2, 3)] + [free[f"joint0_vel{i}"] for i in (2, 3)] == [
        "m",
        "",
        "m/s",
        "rad/s",
    ]
    # the seed draws the bump and nothing else
    other = simloop.run_scenario(SCENES / "pusht.toml", seed=4)
    assert other.disturbances[0]["force"][1] != bump["force"][1]
    np.testing.assert_array_equal(other.trajectory[:600], result.trajectory[:600])


def test_keyword_scenarios_read_like_files(tmp_path):
    built = simloop.Scenario(
        scene=SCENES / "pusht.xml",
        name="pusht",
        duration=2.0,
        controls={"push_x": 0.8, "push_y": [(0.0, 0.0), (0.5, 0.4), (1.0, 2.0)]},
        disturbances=[
            dict(body="tblock", newtons=[0.5, 1.5], direction=[0, 1, 0], random_sign=True, start=1.2, duration=0.1)
        ],
        record=dict(
            bodies=["tblock", "pusher"],
            joints=["slide_x", "slide_y"],
            actuators=["push_x", "push_y"],
            sensors=["tblock_pos", "tip_x"],
        ),
    )
    from_file = simloop.run_scenario(SCENES / "pusht.toml", seed=5)
    from_keywords = simloop.run_scenario(built, seed=5)
    # model= takes the scene as any run does: compiled, or an MJCF file's path.
    for scene in (built.model(), SCENES / "pusht.xml", str(SCENES / "pusht.xml")):
        np.testing.assert_array_equal(simloop.run_scenario(built, seed=5, model=scene).trajectory, from_file.trajectory)
    assert repr(simloop.sweep(scenario=built, model=SCENES / "pusht.xml", timesteps=[0.002], duration=0.1)) == repr(
        simloop.sweep(scenario=built, timesteps=[0.002], duration=0.1)
    )
    assert from_keywords.column_names == from_file.column_names
    np.testing.assert_array_equal(from_keywords.trajectory, from_file.trajectory)
    with pytest.raises(
        ValueError,
        match=r"no body named 'tblok' \(did you mean 'tblock'\?\); "
        r"the scene's bodies a force can move: tblock, pusher",
    ):
        simloop.run_scenario(
            simloop.Scenario(scene=SCENES / "pusht.xml", steps=10, disturbances=[dict(body="tblok", force=[1, 0, 0])])
        )
    with pytest.raises(ValueError, match="setps: unknown key"):
        simloop.Scenario.from_file(_write(tmp_path / "bad.toml", "setps = 3\n"))


def test_record_all_takes_every_joint_and_actuator_of_a_robot_of_hinges():
    """record "all": a hinge robot's angles without listing them, in the run and the Gymnasium env alike."""
    scene = simloop.load_model(SCENES / "walker.xml")
    every = simloop.Scenario(scene=SCENES / "walker.xml", steps=20, record={"joints": "all", "actuators": "all"})
    assert repr(every).endswith("bodies=[])")
    result = simloop.run_scenario(every)
    joints = [n for n in scene.names("joint")]
    assert [c for c in result.column_names if c.endswith("_vel")] == [f"{j}_vel" for j in joints[1:]]  # [0]: free
    assert [c for c in result.column_names if c.endswith("_force")] == [f"{a}_force" for a in scene.names("actuator")]
    listed = simloop.Scenario(
        scene=SCENES / "walker.xml", steps=20, record={"joints": joints, "actuators": scene.names("actuator")}
    )
    np.testing.assert_array_equal(simloop.run_scenario(listed).trajectory, result.trajectory)
    assert repr(simloop.Scenario(scene=SCENES / "walker.xml", record={"bodies": "all"})).endswith("bodies='all')")
    with pytest.raises(ValueError, match=r'record.joints: expected an array of names or "all", got a string'):
        simloop.Scenario(scene=SCENES / "walker.xml", record={"joints": "knee_left"})
    pytest.importorskip("gymnasium")
    from simloop.gym import ScenarioEnv

    assert list(ScenarioEnv(every).observation_names) == list(result.column_names[2:])


def test_tendons_are_recorded_by_name_or_all(tmp_path):
    scene = _write(
        tmp_path / "two_slides.xml",
        """<mujoco><worldbody>
      <body><joint name="a" type="slide" axis="1 0 0"/><geom size="0.1" mass="1"/>
        <body><joint name="b" type="slide" axis="0 1 0"/><geom size="0.1" mass="1"/></body></body></worldbody>
      <tendon><fixed name="sum"><joint joint="a" coef="1"/><joint joint="b" coef="1"/></fixed></tendon>
    </mujoco>""",
    )
    for tendons in (["sum"], "all"):
        r = simloop.run_scenario(
            simloop.Scenario(
                scene=scene, steps=20, reset={"qvel": [0.3, 0.5]}, record={"joints": "all", "tendons": tendons}
            )
        )
        assert r.column_names[-3:] == ("sum_length", "sum_vel", "contacts")
        assert r.column_units["sum_length"] == "m or rad"
        np.testing.assert_array_equal(r.column("sum_length"), r.column("a_pos") + r.column("b_pos"))
        assert r.column("sum_length")[-1] > 0.01


def _write(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


def test_quick_flags_on_any_scene(tmp_path):
    walker = str(SCENES / "walker.xml")
    proc = run_command(
        [
            "--model",
            walker,
            "--body",
            "torso",
            "--ctrl",
            "hip_left=0.5",
            "--ctrl",
            "3=-0.2",
            "--no-rerun",
            "--out",
            "w",
        ],
        tmp_path,
    )
    assert proc.returncode == 0, proc.stderr
    metrics = json.loads((tmp_path / "w" / "metrics.json").read_text())
    assert metrics["timestep"] == 0.004  # the scene's own, not the chapter's 0.002
    assert metrics["disturbances"][0]["body"] == "torso"
    header = (tmp_path / "w" / "trajectory.csv").read_text().splitlines()[0].split(",")
    assert header[:4] == ["step", "time", "hip_left_ctrl", "knee_left_ctrl"]
    # Errors name the flag, what the scene has, and a likely typo; nothing is written.
    for args, message in [
        (
            ["--model", walker],
            '--model: {}: the model has no body named "box"; for any other scene, name the body'
            " to shove (--body) or run a --scenario".format(walker),
        ),
        (
            ["--model", walker, "--body", "torsoo"],
            "--body: no body named 'torsoo' (did you mean 'torso'?); the scene's "
            "bodies a force can move: torso, thigh_left, shin_left, thigh_right, shin_right",
        ),
        (
            ["--model", walker, "--body", "torso", "--ctrl", "hip=1"],
            "--ctrl hip: no actuator named 'hip'; the scene's actuators: hip_left, knee_left, hip_right, knee_right",
        ),
        (
            ["--ctrl", "push_motor=fast"],
            "--ctrl must be ACTUATOR=VALUE (an actuator's name or index, a finite number), got 'push_motor=fast'",
        ),
    ]:
        for python in (False, True):
            proc = run_command([*args, "--out", "bad"], tmp_path, python=python)
            assert proc.returncode == 2, (args, proc.stderr)
            assert proc.stderr.splitlines() == [f"{'sim-loop' if python else 'sim_loop'}: {message}"], proc.stderr
            assert not (tmp_path / "bad" / "metrics.json").exists()


def test_a_cut_window_and_the_numpy_generator(tmp_path):
    proc = subprocess.run(
        [str(sim_loop_exe()), "--body", "box", "--steps", "1030", "--rng", "numpy", "--out", "o"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 0, proc.stderr
    metrics = json.loads((tmp_path / "o" / "metrics.json").read_text())
    (shove,) = metrics["disturbances"]
    # the chapter's shove on the box, drawn by numpy's default_rng(0): +9.82 N
    assert shove["force"][1] == round(simloop.draw_shove(0, 1030, rng="numpy").force_y, 6)
    assert shove["start_step"] == 515 and shove["steps"] == 50
    short = simloop.run_scenario(
        simloop.Scenario(steps=1030, disturbances=[dict(body="box", force=[0, 5, 0], start_step=1000, steps=50)])
    )
    (cut,) = short.disturbances
    assert cut["end_step"] == 1030 and cut["asked_end_step"] == 1050
    assert "30 steps from step 1000 (of 50: the run ended first)" in short.summary()
    late = simloop.run_scenario(
        simloop.Scenario(steps=5, disturbances=[dict(body="box", force=[0, 5, 0], start_step=250)])
    )
    assert "N m, never: it starts after the run's 5 steps\n" in late.summary(), late.summary()


def test_the_recording_draws_the_scene(tmp_path):
    proc = run_command(["--scenario", str(SCENES / "pusht.toml"), "--out", "r"], tmp_path)
    assert proc.returncode == 0, proc.stderr
    chunks = load_chunks(tmp_path / "r" / "sim_loop.rrd")
    entities = {path for path, _ in chunks}
    for entity in [
        "/world/static/floor",
        "/world/static/goal",
        "/world/bodies/tblock/t_bar",
        "/world/bodies/tblock/t_stem",
        "/world/bodies/pusher/tip",
        "/world/bodies/tblock",
        "/plots/tblock_z",
        "/plots/push_y_ctrl",
        "/plots/contacts",
    ]:
        assert entity in entities, sorted(entities)
    result = simloop.run_scenario(SCENES / "pusht.toml")
    z = np.array([v[0] for v in chunks[("/plots/tblock_z", False)]["Scalars:scalars"]])
    np.testing.assert_array_equal(z, result.column("tblock_z"))  # every row, exactly
    translations = chunks[("/world/bodies/tblock", False)]["Transform3D:translation"]
    assert len(translations) == result.rows
    assert translations[-1][0] == pytest.approx([result.column("tblock_" + a)[-1] for a in "xyz"])
    bar = chunks[("/world/bodies/tblock/t_bar", True)]
    assert bar["Boxes3D:half_sizes"][0][0] == pytest.approx([0.08, 0.02, 0.02])
    assert bar["Transform3D:translation"][0][0] == pytest.approx([0.0, 0.03, 0.0])  # its place on the body


def test_a_control_from_a_csv_file(tmp_path):
    values = [0.1 * (k % 7) - 0.3 for k in range(40)]
    (tmp_path / "u.csv").write_text("push_x\n" + "".join(f"{v!r}\n" for v in values))
    s = simloop.Scenario(scene=SCENES / "pusht.xml", steps=60, controls={"push_x": tmp_path / "u.csv"})
    applied = simloop.run_scenario(s).column("push_x_ctrl")
    np.testing.assert_array_equal(applied[:40], values)  # step by step, as written (inside ctrlrange)
    np.testing.assert_array_equal(applied[40:60], values[-1])  # then the last value holds


def test_a_scenario_the_run_would_refuse_is_bad_input(tmp_path):
    # The length and the recorded columns were checked only once the run
    # began: exit 1, in words that named no flag, file or key.
    pusht = str(SCENES / "pusht.xml")
    cases = [
        (
            "short.toml",
            f'scene = "{pusht}"\nduration = 0.0001\n',
            "the run's length (0.0001 s) is less than one step of 0.002 s",
        ),
        (
            "long.toml",
            f'scene = "{pusht}"\nduration = 1e30\n',
            "the run's length (1e+30 s) is more than 4611686018427387903 steps of 0.002 s",
        ),
        (
            "twice.toml",
            f'scene = "{pusht}"\nsteps = 10\n[record]\nbodies = ["tblock", "tblock"]\n',
            "two recorded columns would both be named 'tblock_x': rename one of the scene's elements, or record fewer",
        ),
    ]
    for name, text, message in cases:
        path = _write(tmp_path / name, text)
        for python in (False, True):
            proc = run_command(["--scenario", str(path), "--out", "bad"], tmp_path, python=python)
            assert proc.returncode == 2, (name, proc.stderr)
            program = "sim-loop" if python else "sim_loop"
            assert proc.stderr.splitlines() == [f"{program}: --scenario: {path}: {message}"], proc.stderr
            assert not (tmp_path / "bad").exists()


def test_keyword_scenarios_refuse_odd_values_in_one_line_naming_them():
    # These raised Python's own words ("'bool' object is not iterable",
    # "not enough values to unpack") or a TOML error about the generated text.
    pusht = str(SCENES / "pusht.xml")
    for controls in (
        {"push_x": "1"},
        {"push_x": True},
        {"push_x": None},
        {"push_x": [(0.0, 1.0, 2.0)]},
        {"push_x": [("a", 1.0)]},
        {"push_x": 10**400},
    ):
        with pytest.raises((TypeError, ValueError)) as error:
            simloop.Scenario(scene=pusht, controls=controls)
        assert str(error.value).startswith("controls['push_x'] must be"), str(error.value)
        assert "\n" not in str(error.value)
    s = simloop.Scenario(scene=pusht, steps=10, controls={"push_x": np.int64(1), 1: np.float32(0.5)})
    assert s.toml.count('"value" = ') == 2
    # Names outside the Basic Multilingual Plane are written as TOML escapes.
    with pytest.raises(ValueError, match="disturbance\\[0\\]: no body named 't\U0001f600'"):
        simloop.run_scenario(simloop.Scenario(scene=pusht, disturbances=[dict(body="t\U0001f600", force=[0, 1, 0])]))
    with pytest.raises(ValueError, match="^scene must be text"):
        simloop.Scenario(scene="tests/\udcffx.xml")


@pytest.mark.parametrize("seed, rng, timestep", [(0, "mt19937_64", None), (7, "numpy", None), (3, "mt19937_64", 0.05)])
def test_the_chapters_scenario_is_the_chapters_run_bit_for_bit(seed, rng, timestep):
    # Scenario.chapter() as data reproduces the chapter's run: the same inputs
    # and the same states at every step (the chapter's files keep their own
    # columns and metrics, written by its own loop).
    chapter = simloop.run(seed=seed, rng=rng, timestep=0.002 if timestep is None else timestep)
    scenario = simloop.run_scenario(simloop.Scenario.chapter(), seed=seed, rng=rng, timestep=timestep)
    pairs = {
        "ctrl": "push_motor_ctrl",
        "shove_x": "box_fx",
        "shove_y": "box_fy",
        "shove_z": "box_fz",
        "pusher_x": "pusher_slide_pos",
        "pusher_vx": "pusher_slide_vel",
    }
    for axis in ("x", "y", "z", "vx", "vy", "vz"):
        pairs["box_" + axis] = "box_" + axis
    for ours, theirs in pairs.items():
        assert np.array_equal(chapter.column(ours), scenario.column(theirs), equal_nan=True), ours
    assert chapter.metrics["box_final_pos"] == scenario.metrics["bodies"]["box"]["final_pos"]
    assert [w.name for w in chapter.warnings] == [w.name for w in scenario.warnings]


def test_the_chapters_result_is_a_run_record_with_its_report_on_top(tmp_path):
    # One record per run: the chapter's RunResult is a ScenarioResult,
    # labelled as its scenario, and its final state continues the run.
    chapter = simloop.run(seed=2, steps=400)
    assert isinstance(chapter, simloop.ScenarioResult)
    assert chapter.name == simloop.Scenario.chapter().name
    assert (chapter.seed, chapter.rng, chapter.perturb, chapter.steps) == (2, "mt19937_64", True, 400)
    [shove] = chapter.disturbances
    assert shove["body"] == "box" and shove["start_step"] == chapter.shove.start_step == 200
    assert shove["force"][1] == chapter.shove.force_y
    assert chapter.column_units["box_z"] == "m" and chapter.column_units["ncon"] == ""
    assert np.array_equal(chapter.final_row, chapter.trajectory[-1], equal_nan=True)
    # its own metrics and files are the chapter's
    assert set(chapter.metrics) == {
        "box_final_pos",
        "box_final_speed",
        "lateral_drift",
        "perturb",
        "pusher_final_x",
        "seed",
        "shove_moved_box",
        "steps",
    }
    chapter.write(tmp_path)
    assert (tmp_path / "metrics.json").read_text() == chapter.metrics_json()
    assert (tmp_path / "trajectory.csv").read_text() == chapter.trajectory_csv()
    # 400 steps, then 400 more from where it ended, are the 800-step run's
    # state (the second half unshoved, as the first half's shove is over).
    whole = simloop.run_scenario(simloop.Scenario.chapter(), seed=2, steps=800, perturb=False)
    first = simloop.run_scenario(simloop.Scenario.chapter(), seed=2, steps=400, perturb=False)
    rest = simloop.run_scenario(
        simloop.Scenario.chapter(),
        seed=2,
        steps=400,
        perturb=False,
        initial_state=simloop.run(seed=2, steps=400, perturb=False).final_state,
    )
    assert np.array_equal(first.final_state, simloop.run(seed=2, steps=400, perturb=False).final_state)
    assert np.array_equal(rest.final_state, whole.final_state)
