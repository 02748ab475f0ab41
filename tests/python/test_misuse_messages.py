"""Misuse of the newer API gets one line that names what is wrong (found by a
review as a new user: each of these once passed silently or said the wrong
thing), and an interrupted command leaves no folder it made behind."""

import signal
import subprocess
import sys
import time

import numpy as np
import pytest
import simloop
from conftest import ROOT, sim_loop_exe

SCENES = ROOT / "tests" / "scenes"


def test_one_number_for_several_actuators_is_refused():
    sim = simloop.Sim(SCENES / "walker.xml")
    with pytest.raises(ValueError, match=r"ctrl must be 4 numbers, one per actuator"):
        sim.ctrl = 1.0
    with pytest.raises(ValueError, match=r"ctrl must be 4 numbers"):
        sim.step(5, ctrl=1.0)
    assert sim.steps_taken == 0 and not sim.ctrl_array.any()
    chapter = simloop.Sim()  # one actuator: a number is its ctrl
    chapter.ctrl = 0.5
    assert chapter.ctrl == 0.5


def test_a_state_that_is_not_finite_is_refused():
    sim = simloop.Sim(SCENES / "pusht.xml")
    state = sim.get_state()
    state[3] = np.nan
    with pytest.raises(ValueError, match=r"state must be finite, got nan at index 3"):
        sim.set_state(state)
    assert np.isfinite(sim.get_state()).all()


def test_a_scene_without_keyframes_says_so():
    with pytest.raises(ValueError, match=r"no keyframe named 'kf'.*the scene has no keyframes"):
        simloop.Sim(SCENES / "pusht.xml").reset(keyframe="kf")


def test_a_policy_that_returns_nothing_is_told_what_to_return():
    with pytest.raises(ValueError, match=r"the policy must return 2 ctrl values .*got None .* at decision step 0"):
        simloop.run_scenario(SCENES / "pusht.toml", steps=20, policy=lambda obs: None, control_every=5)


def test_an_unknown_observation_name_lists_the_names():
    def policy(obs):
        return [obs["tblok_x"], 0.0]

    with pytest.raises(KeyError, match=r"did you mean 'tblock_x'\?\); the observation has: push_x_ctrl") as error:
        simloop.run_scenario(SCENES / "pusht.toml", steps=20, policy=policy, control_every=5)
    if sys.version_info >= (3, 11):
        assert "(policy at decision step 0)" in error.value.__notes__


@pytest.mark.parametrize(
    "call",
    [
        lambda: simloop.run_scenario(SCENES / "pusht.toml", steps=20, control_every=5),
        lambda: simloop.run_scenario_batch(SCENES / "pusht.toml", seeds=[0], steps=20, control_every=5),
        lambda: simloop.run(steps=20, control_every=5),
    ],
)
def test_control_every_without_a_policy_is_refused(call):
    with pytest.raises(ValueError, match=r"control_every=5 needs a policy"):
        call()


@pytest.mark.parametrize("python", [False, True])
def test_an_interrupted_command_removes_the_folder_it_made(tmp_path, python):
    out = tmp_path / "new" / "outputs"
    args = ["--steps", "100000000", "--record-every", "1000000", "--no-rerun", "--out", str(out)]
    cmd = [sys.executable, "-m", "simloop", *args] if python else [str(sim_loop_exe()), *args[:4], *args[5:]]
    with subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) as child:
        deadline = time.monotonic() + 20
        while not out.exists() and time.monotonic() < deadline:
            time.sleep(0.02)
        assert out.is_dir()  # made, and the run under way
        time.sleep(0.3)
        child.send_signal(signal.SIGINT)
        _, stderr = child.communicate(timeout=20)
    assert child.returncode == 130, stderr
    assert not out.exists() and (tmp_path / "new").exists()  # the folder it made; not its parents
    existing = tmp_path / "kept"
    existing.mkdir()
    with subprocess.Popen(
        [*cmd[:-1], str(existing)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    ) as child:
        time.sleep(1.0)
        child.send_signal(signal.SIGINT)
        child.communicate(timeout=20)
    assert existing.is_dir()  # a folder that was there before stays
