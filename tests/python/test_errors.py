"""Every bad argument is refused by name, and nothing on disk changes."""

import math
from pathlib import Path

import numpy as np
import pytest
import simloop
from conftest import run_command, snapshot

BAD_RUN_ARGUMENTS = [
    ({"seed": -1}, ValueError, "seed must be an integer from 0 to 18446744073709551615, got -1"),
    ({"seed": 2**64}, ValueError, "seed must be an integer from 0 to 18446744073709551615, got 18446744073709551616"),
    ({"seed": 1.5}, TypeError, "seed must be an int, got 1.5 (float)"),
    ({"seed": "0"}, TypeError, "seed must be an int, got '0' (str)"),
    ({"steps": 0}, ValueError, "steps must be at least 1, got 0"),
    ({"steps": -5}, ValueError, "steps must be at least 1, got -5"),
    ({"steps": 10.0}, TypeError, "steps must be an int, got 10.0 (float)"),
    ({"steps": True}, TypeError, "steps must be an int, got True (bool)"),
    ({"timestep": 0}, ValueError, "timestep must be a positive, finite number of seconds, got 0.0"),
    ({"timestep": -0.002}, ValueError, "timestep must be a positive, finite number of seconds, got -0.002"),
    ({"timestep": math.nan}, ValueError, "timestep must be a positive, finite number of seconds, got nan"),
    ({"timestep": math.inf}, ValueError, "timestep must be a positive, finite number of seconds, got inf"),
    ({"timestep": "0.002"}, TypeError, "timestep must be a number, got '0.002' (str)"),
    ({"perturb": "yes"}, TypeError, "perturb must be a bool, got 'yes' (str)"),
    ({"smoke": 1}, TypeError, "smoke must be a bool, got 1 (int)"),
    ({"record_every": 0}, ValueError, "record_every must be at least 1, got 0"),
    (
        {"model": 3},
        TypeError,
        "model must be None, a simloop.Model, a mujoco.MjModel or MjSpec, or a path to an MJCF file, got 3 (int)",
    ),
    ({"steps": 4_000_000_000_000}, ValueError, "raise record_every"),
    ({"rng": "pcg64"}, ValueError, "rng must be 'mt19937_64' or 'numpy', got 'pcg64'"),
    ({"rng": None}, TypeError, "rng must be a str, got None (NoneType)"),
]


@pytest.mark.parametrize("kwargs, error, message", BAD_RUN_ARGUMENTS)
def test_run_refuses_bad_arguments(kwargs, error, message):
    with pytest.raises(error) as caught:
        simloop.run(**kwargs)
    assert message in str(caught.value)


def test_numpy_scalars_are_fine():
    result = simloop.run(seed=np.uint64(3), steps=np.int64(20), timestep=np.float32(0.002), perturb=np.bool_(False))
    assert result.metrics["seed"] == 3 and result.metrics["steps"] == 20


@pytest.mark.parametrize(
    "kwargs, error, message",
    [
        ({"seeds": [0, -1]}, ValueError, "seeds[1] must be an integer from 0 to"),
        ({"seeds": 5}, TypeError, "seeds must be a sequence, got 5 (int)"),
        (
            {"timesteps": [0.002, 0.0]},
            ValueError,
            "run 1: timestep must be a positive, finite number of seconds, got 0.0",
        ),
        ({"timesteps": "0.002"}, TypeError, "timesteps must be a sequence, got '0.002' (str)"),
        ({"threads": 4097}, ValueError, "threads must be from 1 to 4096, or 0 for one per core, got 4097"),
        ({"threads": -1}, ValueError, "threads must be from 1 to 4096, or 0 for one per core, got -1"),
        ({"threads": 1.5}, TypeError, "threads must be an int, got 1.5 (float)"),
        ({"steps": 0}, ValueError, "steps must be at least 1, got 0"),
    ],
)
def test_run_batch_refuses_bad_arguments(kwargs, error, message):
    with pytest.raises(error) as caught:
        simloop.run_batch(**kwargs)
    assert message in str(caught.value)


def test_sim_refuses_bad_arguments():
    sim = simloop.Sim()
    cases = [
        (lambda: sim.step(0), ValueError, "n must be at least 1, got 0"),
        (lambda: sim.step(1.0), TypeError, "n must be an int, got 1.0 (float)"),
        (lambda: sim.step(1, ctrl=math.nan), ValueError, "ctrl must be finite, got nan"),
        (lambda: sim.apply_force([0.0, 1.0]), ValueError, "force must have 3 components (fx, fy, fz), got 2"),
        (lambda: sim.apply_force([0.0, math.inf, 0.0]), ValueError, "force must be finite, got inf"),
        (lambda: sim.apply_force([0.0, "1", 0.0]), TypeError, "force[1] must be a number, got '1' (str)"),
        (lambda: sim.apply_force(5.0), TypeError, "force must be a sequence, got 5.0 (float)"),
        (lambda: setattr(sim, "timestep", -1), ValueError, "timestep must be a positive, finite number"),
        (lambda: simloop.Sim(model=[]), TypeError, "model must be None, a simloop.Model, a mujoco.MjModel or MjSpec"),
    ]
    for call, error, message in cases:
        with pytest.raises(error) as caught:
            call()
        assert message in str(caught.value)
    assert sim.time == 0.0 and sim.steps_taken == 0  # nothing happened


def test_a_refused_step_with_a_ctrl_writes_no_ctrl():
    sim = simloop.Sim()
    for n, message in ((0, "n must be at least 1, got 0"), (2**62, "n must be at most 4611686018427387903")):
        with pytest.raises(ValueError, match=message):
            sim.step(n, ctrl=0.5)
        assert sim.ctrl == 0.0 and sim.steps_taken == 0


def test_step_converts_what_python_calls_an_int_and_names_the_rest_in_one_line():
    # Sim.step hands n and progress to the core as given; what the core does
    # not take as it is, Python converts (numpy's ints) or names.
    sim = simloop.Sim()
    sim.step(np.int64(3))
    sim.step(np.int32(2), progress=None)
    assert sim.steps_taken == 5
    for n, progress, error, message in (
        (True, None, TypeError, "n must be an int, got True (bool)"),
        ("2", None, TypeError, "n must be an int, got '2' (str)"),
        (2**63, None, ValueError, f"n must be an integer from {-(2**63)} to {2**63 - 1}, got {2**63}"),
        (-(2**64), None, ValueError, f"n must be an integer from {-(2**63)} to {2**63 - 1}, got {-(2**64)}"),
        (1, 3, TypeError, "progress must be None or a callable progress(steps_done, steps_total), got 3 (int)"),
        (np.int64(1), "p", TypeError, "progress must be None or a callable"),
    ):
        with pytest.raises(error) as caught:
            sim.step(n, progress=progress)
        assert str(caught.value).startswith(message)
        assert caught.value.__context__ is None  # no pybind11 "incompatible function arguments" behind it
    assert sim.steps_taken == 5


def test_a_typeerror_from_progress_reaches_the_caller_once():
    sim = simloop.Sim()
    calls = []

    def progress(done, total):
        calls.append(done)
        raise TypeError("the callback's own")

    with pytest.raises(TypeError, match="the callback's own"):
        sim.step(10, progress=progress)
    assert sim.steps_taken == 10 and calls == [10]  # the steps taken once, not retried


def test_a_scenarios_steps_are_worded_as_the_chapters():
    for steps, message in (
        (0, "steps must be at least 1, got 0"),
        (2**62, "steps must be at most 4611686018427387903, got 4611686018427387904"),
    ):
        with pytest.raises(ValueError) as scenario_error:
            simloop.run_scenario(simloop.Scenario.chapter(), steps=steps)
        with pytest.raises(ValueError) as chapter_error:
            simloop.run(steps=steps)
        assert message in str(scenario_error.value) and message in str(chapter_error.value)


def test_mujoco_errors_raise_with_mujocos_message(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(simloop.MujocoError, match="XML parse error"):
        simloop.Model.from_xml_string("<mujoco><worldbody><body></mujoco>")
    (tmp_path / "broken.xml").write_text("<mujoco><worldbody><body></mujoco>")
    with pytest.raises(simloop.MujocoError, match="broken.xml: XML parse error"):
        simloop.run(model=tmp_path / "broken.xml")
    with pytest.raises(OSError, match="missing.xml: cannot open"):
        simloop.run(model="missing.xml")
    no_box = simloop._core.PUSHER_SCENE_XML.replace('name="box"', 'name="crate"')
    # Any scene loads; the chapter's loop refuses one without its box.
    with pytest.raises(ValueError, match='no body named "box"'):
        simloop.run(model=simloop.Model.from_xml_string(no_box))
    assert not (tmp_path / "MUJOCO_LOG.TXT").exists()
    # The interpreter is fine afterwards.
    assert simloop.run(smoke=True).metrics["steps"] == 300


def test_write_into_a_file_in_the_way_raises_and_keeps_it(tmp_path):
    blocker = tmp_path / "out"
    blocker.write_text("precious")
    with pytest.raises(OSError, match="exists and is not a directory"):
        simloop.run(smoke=True).write(blocker)
    assert blocker.read_text() == "precious"


COMMAND_BAD_INPUTS = [
    (["--timestep", "0"], "--timestep must be a positive, finite number of seconds, got '0'"),
    (["--timestep", "nan"], "got 'nan'"),
    (["--timestep", "inf"], "got 'inf'"),
    (["--timestep", "-1"], "got '-1'"),
    (["--steps", "0"], "--steps must be a whole number from 1 to"),
    (["--steps", "x"], "got 'x'"),
    (["--seed", "-1"], "--seed must be a whole number from 0 to 18446744073709551615, got '-1'"),
    (["--record-every", "0"], "--record-every must be a whole number from 1 to"),
    (["--out", "blocker"], "--out: blocker: exists and is not a directory"),
    (["--out", "/proc/self/simloop"], "--out: /proc/self/simloop: cannot create the output directory"),
    (["--model", "missing.xml"], "--model: missing.xml: cannot open (No such file or directory)"),
    (["--model", "broken.xml"], "--model: broken.xml: XML parse error"),
    (["--nope"], "unknown option '--nope'"),
]


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    """A directory with earlier outputs (a full recorded run) to protect."""
    cwd = tmp_path_factory.mktemp("bad")
    assert run_command(["--smoke", "--out", "out"], cwd).returncode == 0
    (cwd / "blocker").write_text("precious")
    (cwd / "broken.xml").write_text("<mujoco><worldbody><body></mujoco>")
    return cwd


@pytest.mark.parametrize("python", [True, False], ids=["python-m-simloop", "sim_loop"])
@pytest.mark.parametrize("args, message", COMMAND_BAD_INPUTS)
def test_commands_refuse_bad_input_in_one_line_and_change_nothing(workdir, python, args, message):
    before = snapshot(workdir)
    if "--out" not in args:
        args = [*args, "--out", "out"]
    proc = run_command(args, workdir, python=python)
    assert proc.returncode == 2
    assert message in proc.stderr
    assert proc.stderr.count("\n") == 1, proc.stderr
    assert proc.stderr.startswith("sim-loop: " if python else "sim_loop: ")
    assert snapshot(workdir) == before
    assert not (workdir / "MUJOCO_LOG.TXT").exists()


def test_command_help_and_version(tmp_path):
    helped = run_command(["--help"], tmp_path)
    assert helped.returncode == 0 and helped.stdout.startswith("usage: python -m simloop")
    for flag in (
        "--seed",
        "--steps",
        "--timestep",
        "--smoke",
        "--out",
        "--no-perturb",
        "--no-rerun",
        "--record-every",
        "--model",
    ):
        assert flag in helped.stdout
    version = run_command(["--version"], tmp_path)
    assert version.stdout == f"simloop {simloop.__version__} ({simloop.MUJOCO_VERSION})\n"
    assert not Path(tmp_path / "outputs").exists()


@pytest.mark.parametrize("python", [True, False], ids=["python-m-simloop", "sim_loop"])
def test_the_chapters_own_scene_xml_says_how_to_fix_it(tmp_path, python):
    # The chapter's SCENE_XML exactly (simloop's copy adds the compiler line):
    # MuJoCo 2.2 refuses its ctrlrange without ctrllimited; the message says
    # the line that fixes it. Current MuJoCo takes it as it is.
    from expected import expected

    chapter = simloop._core.PUSHER_SCENE_XML.replace('  <compiler autolimits="true"/>\n', "")
    assert "autolimits" not in chapter
    (tmp_path / "chapter.xml").write_text(chapter)
    proc = run_command(["--model", "chapter.xml", "--smoke", "--no-rerun", "--out", "o"], tmp_path, python)
    if not expected("errors.autolimits_needed"):
        assert proc.returncode == 0, proc.stderr
        return
    assert proc.returncode == 2
    assert "--model: chapter.xml: Error: actuator has `ctrlrange` but not `ctrllimited`" in proc.stderr, proc.stderr
    assert (
        '(to fix it, put <compiler autolimits="true"/> inside <mujoco>, before <worldbody>: current MuJoCo does '
        f"this by default, {simloop.MUJOCO_VERSION} does not)\n"
    ) in proc.stderr, proc.stderr
    assert proc.stderr.count("\n") == 1
