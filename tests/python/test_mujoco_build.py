"""Both MuJoCos from one tree: the pin, the build's MuJoCo, scenes nobody here
wrote, plugins, sleeping bodies, and a mujoco.MjModel handed to simloop.

Checks that only the PyPI build can pass (plugins, sleep, mujoco.MjModel, a
user's own mujoco code beside simloop) skip on Debian's 2.2.2, saying so; the
rest run on both builds.
"""

from __future__ import annotations

import importlib.util
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import simloop
import tomllib
from simloop import _build
from simloop._mujoco_check import load_failure_message

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "tests" / "scenes"
PYPI = _build.MUJOCO_BUILD == "pypi"
pypi_only = pytest.mark.skipif(not PYPI, reason=f"simloop is built on the system's {simloop.MUJOCO_VERSION}")


def test_the_mujoco_pin_is_one_version():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())
    (extra,) = project["project"]["optional-dependencies"]["mujoco"]
    (override,) = [
        o for o in project["tool"]["scikit-build"]["overrides"] if "simloop.mujoco" in o["if"].get("config-setting", {})
    ]
    assert override["build"]["requires"] == [extra], "pyproject.toml pins two mujoco versions"
    if PYPI:
        assert extra == f"mujoco=={_build.MUJOCO_LIBRARY_VERSION}"


def test_the_package_names_the_mujoco_it_runs():
    assert simloop.MUJOCO_VERSION == f"MuJoCo {_build.MUJOCO_LIBRARY_VERSION}"
    assert _build.MUJOCO_BUILD in ("system", "pypi")


def test_a_missing_libmujoco_is_one_line_naming_both_versions(monkeypatch):
    from simloop import _mujoco_check

    monkeypatch.setattr(_mujoco_check, "MUJOCO_BUILD", "pypi")
    monkeypatch.setattr(_mujoco_check, "MUJOCO_LIBRARY_VERSION", "4.0.0")
    monkeypatch.setattr(_mujoco_check, "installed_mujoco_library", lambda: "3.17.0")
    error = ImportError("libmujoco.so.4.0.0: cannot open shared object file: No such file or directory")
    message = load_failure_message(error)
    assert message is not None and "\n" not in message
    assert "MuJoCo 4.0.0" in message and "MuJoCo 3.17.0" in message and "pip install mujoco==4.0.0" in message
    monkeypatch.setattr(_mujoco_check, "installed_mujoco_library", lambda: None)
    assert "no mujoco package" in (load_failure_message(error) or "")
    # The same version elsewhere (simloop installed apart from mujoco): not "built on 4.0.0, but ships 4.0.0".
    monkeypatch.setattr(_mujoco_check, "installed_mujoco_library", lambda: "4.0.0")
    message = load_failure_message(error)
    assert message is not None and "is not beside simloop" in message and "pip install mujoco" not in message
    assert load_failure_message(ImportError("No module named 'numpy'")) is None


def gymnasium_scenes() -> list[Path]:
    spec = importlib.util.find_spec("gymnasium")
    assert spec is not None and spec.origin is not None
    return sorted((Path(spec.origin).parent / "envs" / "mujoco" / "assets").glob("*.xml"))


@pytest.mark.parametrize("scene", gymnasium_scenes(), ids=lambda p: p.name)
def test_gymnasiums_scenes_load_step_and_restore(scene):
    # Scenes nobody here wrote, from a PyPI package: each loads, steps with
    # every actuator driven, and a saved state goes on bit for bit.
    sim = simloop.Sim(scene)
    if sim.model.nu:
        sim.ctrl = np.linspace(-0.5, 0.5, sim.model.nu)
    sim.step(50)
    saved = sim.get_state()
    sim.step(100)
    other = simloop.Sim(scene)
    other.set_state(saved)
    other.step(100)
    assert np.array_equal(other.get_state(), sim.get_state())
    assert not sim.warnings


@pypi_only
def test_a_plugin_scene_runs():
    sim = simloop.Sim(SCENES / "plugin_pid.xml")
    sim.ctrl = 0.5
    sim.step(500)
    assert abs(sim.joint("hinge").qpos[0] - 0.5) < 0.1  # the PID plugin holds the arm near its target


def test_a_plugin_scene_on_2_2_says_what_is_missing():
    if PYPI:
        pytest.skip("the PyPI build loads MuJoCo's plugins")
    with pytest.raises(simloop.MujocoError, match="plugin"):
        simloop.Sim(SCENES / "plugin_pid.xml")


@pypi_only
def test_sleeping_bodies_restore_bit_for_bit():
    scene = SCENES / "sleeping_boxes.xml"
    layout = dict(simloop.Sim(scene).state_layout())
    assert layout.get("tree_asleep") == 3
    for saved_at in (700, 3000):  # some trees still awake; all asleep
        sim = simloop.Sim(scene)
        sim.step(saved_at)
        saved = sim.get_state()
        sim.step(1500)
        restored = simloop.Sim(scene)
        restored.set_state(saved)
        restored.step(1500)
        assert np.array_equal(restored.get_state(), sim.get_state()), f"saved at step {saved_at}"


@pypi_only
def test_a_mujoco_mjmodel_runs_as_its_xml_does_and_the_state_is_mujocos():
    mujoco = pytest.importorskip("mujoco")
    path = SCENES / "pusht.xml"
    model = mujoco.MjModel.from_xml_path(str(path))
    model.opt.timestep = 0.001  # edited in Python: the copy takes the edit
    sim = simloop.Sim(model)
    assert sim.timestep == 0.001
    data = mujoco.MjData(model)
    ctrl = np.linspace(0.2, 0.6, model.nu)
    sim.ctrl = ctrl
    data.ctrl[:] = ctrl
    sim.step(300)
    for _ in range(300):
        mujoco.mj_step(model, data)
    # One libmujoco: simloop's steps are mujoco's, to the bit, and its state
    # starts with mj_getState's integration state.
    signature = mujoco.mjtState.mjSTATE_INTEGRATION
    theirs = np.empty(mujoco.mj_stateSize(model, signature))
    mujoco.mj_getState(model, data, theirs, signature)
    assert np.array_equal(sim.get_state()[: theirs.size], theirs)
    # ... and mujoco takes it back as it is.
    other = mujoco.MjData(model)
    mujoco.mj_setState(model, other, sim.get_state()[: theirs.size], signature)
    assert np.array_equal(other.qpos, data.qpos)
    # Every place that takes a scene takes one: a scenario run too.
    scenario = simloop.Scenario.from_file(SCENES / "pusht.toml")
    from_spec = simloop.run_scenario(scenario, seed=0, model=mujoco.MjSpec.from_file(str(path)).compile())
    from_file = simloop.run_scenario(scenario, seed=0)
    assert np.array_equal(from_spec.trajectory, from_file.trajectory, equal_nan=True)


def test_a_mujoco_mjmodel_from_another_mujoco_is_one_line():
    mujoco = pytest.importorskip("mujoco")
    if PYPI and mujoco.mj_versionString() == _build.MUJOCO_LIBRARY_VERSION:
        pytest.skip("this environment's mujoco is simloop's own")
    with pytest.raises(TypeError, match="cannot be run by this simloop") as error:
        simloop.Sim(mujoco.MjModel.from_xml_string("<mujoco/>"))
    assert "\n" not in str(error.value)


# A user's own mujoco code, in a process that has (or has not) imported
# simloop and stepped a Sim: a model that warns (a NaN in qpos).
USERS_OWN_WARNING = """
import sys
import mujoco
if sys.argv[1] == "with-simloop":
    import simloop
    simloop.Sim().step(10)
model = mujoco.MjModel.from_xml_string(
    "<mujoco><worldbody><body><freejoint/><geom size='0.1'/></body></worldbody></mujoco>"
)
data = mujoco.MjData(model)
data.qpos[0] = float("nan")
mujoco.mj_step(model, data)
"""


@pypi_only
def test_a_users_own_mujoco_warning_reaches_the_handler_that_was_there_before_simloop(tmp_path):
    # No handler of the user's own: MuJoCo's default, which prints the warning
    # (MuJoCo 4: to stderr) and appends it to MUJOCO_LOG.TXT. simloop's Sim
    # keeps its own warnings (they are on its report), and must not take the
    # user's: the process prints and logs what it would without simloop.
    seen = {}
    for mode in ("without-simloop", "with-simloop"):
        folder = tmp_path / mode
        folder.mkdir()
        proc = subprocess.run(
            [sys.executable, "-c", USERS_OWN_WARNING, mode], cwd=folder, capture_output=True, text=True, timeout=120
        )
        assert proc.returncode == 0, proc.stderr
        log = folder / "MUJOCO_LOG.TXT"
        # The log but its timestamps (asctime's or strftime's "Fri Nov 27 15:31:07 2026").
        seen[mode] = [
            proc.stdout,
            proc.stderr,
            re.sub(r"\w{3} \w{3} [ \d]\d \d\d:\d\d:\d\d \d{4}", "<time>", log.read_text() if log.exists() else ""),
        ]
    printed, logged = seen["without-simloop"][0] + seen["without-simloop"][1], seen["without-simloop"][2]
    assert "WARNING: Nan, Inf or huge value in QPOS at DOF 0" in printed, seen
    assert "Nan, Inf or huge value in QPOS at DOF 0" in logged, seen
    assert seen["with-simloop"] == seen["without-simloop"]
