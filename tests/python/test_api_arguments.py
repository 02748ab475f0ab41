"""Arguments of the Python API: numpy's scalars are numbers wherever a number
is taken (a float64 is a float subclass whose repr is not a number in TOML);
a wrong type is a one-line TypeError naming the argument (not an
AttributeError, a RecursionError, or pybind11's four-line list of
signatures); and `python -m simloop plot` on a CSV without rows is one line,
not a traceback."""

import collections
import subprocess
import sys

import numpy as np
import pytest
import simloop
from conftest import ROOT

PUSHT = ROOT / "tests" / "scenes" / "pusht.xml"


@pytest.mark.parametrize("kind", [np.float64, np.float32])
def test_a_scenario_of_numpy_numbers_is_the_scenario_of_python_numbers(kind):
    def made(number, whole):
        return simloop.Scenario(
            scene=PUSHT,
            steps=whole(60),
            timestep=number(0.002),
            controls={"push_x": number(0.5), "push_y": [(number(0), number(0.25))]},
            disturbances=[
                dict(body="tblock", force=[number(0), number(2), number(0)], start=number(0.04), duration=number(0.02))
            ],
            reset={"qpos_noise": number(0.001), "params": [dict(kind="friction", uniform=[number(0.5), number(1)])]},
        )

    plain = made(lambda v: float(kind(v)), int)
    first, second = simloop.run_scenario(plain, seed=3), simloop.run_scenario(made(kind, np.int64), seed=3)
    assert second.trajectory.tobytes() == first.trajectory.tobytes()


def test_reset_options_take_numpy_numbers():
    gym = pytest.importorskip("gymnasium")
    env = gym.make("simloop/PushT-v0")
    try:
        options = {"qpos_noise": np.float64(0.01), "params": [dict(kind="friction", value=np.float64(0.7))]}
        observation, _ = env.reset(seed=1, options=options)
        again, _ = env.reset(seed=1, options={"qpos_noise": 0.01, "params": [dict(kind="friction", value=0.7)]})
        assert observation.tobytes() == again.tobytes()
    finally:
        env.close()


def test_plot_of_a_csv_without_rows_is_one_line(tmp_path):
    out = tmp_path / "run"
    out.mkdir()
    (out / "trajectory.csv").write_text("step,time,pusher_x,box_x,box_y,box_z,contacts,shove_y\n")
    done = subprocess.run(
        [sys.executable, "-m", "simloop", "plot", "trajectory", "--out", str(out)],
        capture_output=True,
        text=True,
        stdin=subprocess.DEVNULL,
        timeout=120,
    )
    assert done.returncode == 1, done.stderr
    assert done.stderr.count("\n") == 1 and "no rows after the header" in done.stderr, done.stderr
    assert not any(p.name.endswith(".png") or ".tmp" in p.name for p in out.iterdir())


@pytest.mark.parametrize(
    "call, words",
    [
        (
            lambda: simloop.Scenario(scene=PUSHT, controls=[1, 2]),
            r"^controls must be a dict or None, got \[1, 2\] \(list\)$",
        ),
        (lambda: simloop.Scenario(scene=PUSHT, record="all"), r"^record must be a dict or None, got 'all' \(str\)$"),
        (
            lambda: simloop.Scenario(scene=PUSHT, disturbances=5),
            r"^disturbances must be a list of dicts, got 5 \(int\)$",
        ),
        (
            lambda: simloop.Scenario(scene=PUSHT, name=collections.UserString("x")),
            r"^name must be a number, a string or a list of them, got .*UserString",
        ),
        (
            lambda: simloop.Scenario(scene=PUSHT, record={"bodies": [collections.UserString("tblock")]}),
            r"^bodies must be a number, a string or a list of them, got .*UserString",
        ),
        (lambda: simloop.Scenario.from_file(5), r"^path must be a path .*got 5 \(int\)$"),
        (lambda: simloop.BatchTable.concat(5), r"^tables must be a list of BatchTable, got int$"),
        (lambda: simloop.Model.pusher_scene().names(5), r"^kind must be a str or bytes, got 5 \(int\)$"),
        (lambda: simloop.Model.pusher_scene().object_info("body", "x"), r"^id must be an int, got 'x' \(str\)$"),
        (lambda: simloop.Model.pusher_scene().object_info(b"body", 1.0), r"^id must be an int, got 1.0 \(float\)$"),
    ],
)
def test_a_wrong_type_is_one_line_naming_the_argument(call, words):
    with pytest.raises(TypeError, match=words) as error:
        call()
    assert "\n" not in str(error.value)


def test_model_lookups_take_numpy_indices_and_refuse_text_utf8_cannot_hold():
    model = simloop.Model.pusher_scene()
    assert model.object_info("body", np.int64(1)) == model.object_info("body", 1)
    with pytest.raises(ValueError, match=r"^kind must be text that UTF-8 can encode, got '\\udcff' at index 0$"):
        model.names("\udcff")
    with pytest.raises(ValueError, match=r"^id must be an object's index, got 1267650600228229401496703205376$"):
        model.object_info("body", 2**100)
