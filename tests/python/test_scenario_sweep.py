"""Scenario sweeps: a scenario (PushT, the walker) run at many timesteps over
the same span of sim time, from both commands and from Python, bitwise the
runs done one by one, with a general blow-up rule and its picture."""

import math

import numpy as np
import pytest
import simloop
from conftest import ROOT, run_command, without_wall_clock

SCENES = ROOT / "tests" / "scenes"
PUSHT = SCENES / "pusht.toml"
WALKER = SCENES / "walker.toml"


def read_csv(path):
    lines = path.read_text().splitlines()
    names = lines[0].split(",")
    return names, np.array([[float(cell) for cell in line.split(",")] for line in lines[1:]])


@pytest.mark.parametrize(
    "scenario,flags",
    [
        (PUSHT, ["--timesteps", "0.001,0.002,0.004,0.03", "--duration", "0.8"]),
        (WALKER, []),  # the default grid over the scenario's own 3 s
    ],
)
def test_both_commands_and_python_sweep_the_same_bytes(tmp_path, scenario, flags):
    outputs = {}
    for label, python in (("cpp1", False), ("cpp2", False), ("py", True)):
        proc = run_command(
            ["sweep", "--scenario", str(scenario), "--threads", "2", "--out", label, *flags], tmp_path, python=python
        )
        assert proc.returncode == 0, proc.stderr
        assert proc.stderr == ""
        outputs[label] = (
            (tmp_path / label / "sweep.csv").read_bytes(),
            without_wall_clock(proc.stdout).replace(label, "OUT"),
        )
    assert outputs["cpp1"] == outputs["cpp2"] == outputs["py"]
    if flags:
        timesteps = [float(t) for t in flags[1].split(",")]
        result = simloop.sweep(timesteps, duration=float(flags[3]), scenario=scenario, threads=1)
    else:
        result = simloop.sweep(scenario=simloop.Scenario.from_file(scenario))
    assert result.csv().encode() == outputs["py"][0]
    assert result.summary() in outputs["py"][1]
    names, table = read_csv(tmp_path / "py" / "sweep.csv")
    assert names[:5] == ["timestep", "steps", "mujoco_warnings", "diverged", "peak_speed"]
    assert names[-3:] == ["max_offset", "tolerance", "blew_up"]
    for body in result.bodies:
        assert [body + s for s in ("_final_x", "_final_y", "_final_z", "_offset")] == names[
            names.index(body + "_final_x") : names.index(body + "_final_x") + 4
        ]
    assert len(table) == len(result.points)


def test_each_point_is_bitwise_the_scenario_run_alone():
    timesteps = [0.004, 0.001, 0.002]
    swept = simloop.sweep(timesteps, duration=0.6, scenario=PUSHT, threads=2, seed=3, rng="numpy")
    assert [p.timestep for p in swept.points] == sorted(timesteps)
    reference = None
    for point in swept.points:
        run = simloop.run_scenario(PUSHT, timestep=point.timestep, steps=point.steps, seed=3, rng="numpy")
        assert point.steps == round(0.6 / point.timestep)
        speeds = [np.sqrt(sum(run.column(f"{body}_v{a}") ** 2 for a in "xyz")) for body in swept.bodies]
        assert np.array_equal(np.float64(point.peak_speed), np.max(speeds))
        finals = np.array([[run.column(f"{body}_{a}")[-1] for a in "xyz"] for body in swept.bodies])
        assert np.array_equal(np.array(point.final_positions), finals)
        reference = finals if reference is None else reference
        assert np.allclose(point.offsets, np.linalg.norm(finals - reference, axis=1), rtol=0, atol=1e-15)
    assert swept.points[0].max_offset == 0.0 and not swept.points[0].blew_up


def test_the_rule_marks_warnings_and_far_ends_and_the_edge_below_them():
    walker = simloop.sweep([0.001, 0.002, 0.2, 0.3], scenario=WALKER)
    assert walker.duration == pytest.approx(3.0)
    coarse = {p.timestep: p for p in walker.points}[0.2]
    assert coarse.mujoco_warnings + coarse.diverged > 0 and coarse.blew_up  # its state went bad
    assert coarse.peak_speed > 100  # m/s: the walker thrown about
    assert walker.edge is not None and walker.edge < 0.2
    pusht = simloop.sweep([0.0005, 0.03], duration=2.0, scenario=PUSHT)
    far = pusht.points[1]
    assert far.mujoco_warnings == far.diverged == 0
    assert far.max_offset > pusht.tolerance and far.blew_up  # by distance alone
    assert pusht.tolerance == simloop.SCENARIO_SWEEP_TOLERANCE * pusht.scene_size
    assert pusht.edge == 0.0005
    for point in walker.points + pusht.points:
        tolerance = walker.tolerance if point in walker.points else pusht.tolerance
        assert point.blew_up == (point.mujoco_warnings > 0 or point.diverged > 0 or not point.max_offset <= tolerance)


def test_quick_flags_sweep_any_scene(tmp_path):
    proc = run_command(
        [
            "sweep",
            "--model",
            str(SCENES / "walker.xml"),
            "--body",
            "torso",
            "--ctrl",
            "hip_left=0.3",
            "--timesteps",
            "0.002,0.004",
            "--duration",
            "0.4",
            "--out",
            "q",
        ],
        tmp_path,
        python=False,
    )
    assert proc.returncode == 0, proc.stderr
    names, table = read_csv(tmp_path / "q" / "sweep.csv")
    assert "torso_offset" in names and table.shape == (2, len(names))
    assert "swept scenario walker over 2 timesteps, 0.4 s of sim time each" in proc.stdout


@pytest.mark.parametrize(
    "args,message",
    [
        (["--scenario", str(PUSHT), "--model", str(SCENES / "pusht.xml")], "--model and --scenario"),
        (["--scenario", str(PUSHT), "--duration", "0.001"], "--duration: 0.001 s of sim time is too short"),
        (["--scenario", str(PUSHT), "--timesteps", "0.6"], "--timesteps/--duration (default: the scenario's length)"),
        (["--scenario", str(PUSHT), "--seed", "1"], "--seed is not a sweep option"),
        (["--body", "tblok", "--model", str(SCENES / "pusht.xml")], "did you mean 'tblock'"),
    ],
)
def test_bad_scenario_sweeps_are_one_line_and_exit_2(tmp_path, args, message):
    for python in (False, True):
        proc = run_command(["sweep", *args, "--out", "bad"], tmp_path, python=python)
        assert proc.returncode == 2, proc.stderr
        assert message in proc.stderr and proc.stderr.count("\n") == 1, proc.stderr
        assert not (tmp_path / "bad" / "sweep.csv").exists()


def test_python_refuses_bad_arguments_by_name():
    with pytest.raises(ValueError, match="rng must be"):
        simloop.sweep([0.002], duration=0.1, scenario=PUSHT, rng="pcg")
    with pytest.raises(TypeError, match="scenario must be"):
        simloop.sweep([0.002], duration=0.1, scenario=3)
    with pytest.raises(
        ValueError, match=r"^duration 0.001 s at timestep 0.0005 s is 2 steps; a sweep point needs 4 to "
    ):
        simloop.sweep(duration=0.001, scenario=PUSHT)
    with pytest.raises(ValueError, match="steps"):
        simloop.sweep([0.5], duration=1.0, scenario=PUSHT)


def test_the_sweep_picture_of_a_scenario(tmp_path):
    proc = run_command(
        [
            "sweep",
            "--scenario",
            str(PUSHT),
            "--timesteps",
            "0.001,0.004,0.03",
            "--duration",
            "0.8",
            "--plot",
            "--out",
            "p",
        ],
        tmp_path,
        python=False,
    )
    assert proc.returncode == 0, proc.stderr
    png = tmp_path / "p" / "sweep.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    from simloop.sweep_plots import sweep_figure

    fig = sweep_figure(tmp_path / "p" / "sweep.csv")
    offsets, speeds = fig.axes
    assert "blew up" in fig._suptitle.get_text()
    tolerance = float(read_csv(tmp_path / "p" / "sweep.csv")[1][0, -2])
    assert any(math.isclose(line.get_ydata()[0], tolerance) for line in offsets.get_lines() if len(line.get_ydata()))
    assert offsets.get_yscale() == speeds.get_yscale() == "log"


def test_progress_counts_every_step_and_its_exception_stops_the_sweep():
    seen = []
    simloop.sweep([0.002, 0.004], duration=0.4, scenario=PUSHT, progress=lambda done, total: seen.append((done, total)))
    assert seen[-1] == (300, 300)  # 200 + 100 steps

    def stop(done, total):
        raise RuntimeError("stop here (test)")

    with pytest.raises(RuntimeError, match="stop here"):
        simloop.sweep([0.0005, 0.001], duration=20.0, scenario=PUSHT, progress=stop)
