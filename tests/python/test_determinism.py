"""Byte-identical outputs: twice the same, and the same from every front end."""

import json
import math

import numpy as np
import pytest
import simloop
from conftest import run_command, without_wall_clock


def read_outputs(directory):
    return {name: (directory / name).read_bytes() for name in ("metrics.json", "trajectory.csv")}


def test_smoke_twice_is_byte_identical(tmp_path):
    for name in ("a", "b"):
        proc = run_command(["--smoke", "--no-rerun", "--out", name], tmp_path)
        assert proc.returncode == 0, proc.stderr
    assert read_outputs(tmp_path / "a") == read_outputs(tmp_path / "b")


@pytest.mark.parametrize(
    "flags",
    [
        ["--smoke"],
        ["--seed", "2", "--timestep", "0.01", "--record-every", "3"],
        ["--no-perturb", "--steps", "777"],
        ["--seed", "3", "--rng", "numpy", "--smoke"],
    ],
)
def test_python_command_sim_loop_and_run_agree_byte_for_byte(tmp_path, flags):
    for name in ("py", "cpp"):
        (tmp_path / name).mkdir()
    py = run_command([*flags, "--no-rerun", "--out", "out"], tmp_path / "py")
    cpp = run_command([*flags, "--no-rerun", "--out", "out"], tmp_path / "cpp", python=False)
    assert py.returncode == 0, py.stderr
    assert cpp.returncode == 0, cpp.stderr
    assert read_outputs(tmp_path / "py" / "out") == read_outputs(tmp_path / "cpp" / "out")
    # The same summary, line for line (the wall-clock line is a measurement).
    assert without_wall_clock(py.stdout) == without_wall_clock(cpp.stdout)
    # And simloop.run with the same arguments writes the same bytes.
    kwargs = {"smoke": "--smoke" in flags, "perturb": "--no-perturb" not in flags}
    for flag, key, cast in (
        ("--seed", "seed", int),
        ("--timestep", "timestep", float),
        ("--rng", "rng", str),
        ("--record-every", "record_every", int),
        ("--steps", "steps", int),
    ):
        if flag in flags:
            kwargs[key] = cast(flags[flags.index(flag) + 1])
    simloop.run(**kwargs).write(tmp_path / "api")
    assert read_outputs(tmp_path / "api") == read_outputs(tmp_path / "cpp" / "out")


def test_metrics_json_is_what_python_json_writes():
    # The C++ writer against Python's own json.dumps, over runs whose numbers
    # span signs, magnitudes and exponent forms.
    for result in simloop.run_batch(seeds=range(8), timesteps=(0.002, 0.03, 0.5, 3.0), steps=300).results:
        assert result.metrics_json() == json.dumps(result.metrics, indent=2, sort_keys=True) + "\n"


def test_csv_reads_back_to_the_exact_arrays(tmp_path):
    result = simloop.run(seed=5, steps=500, record_every=2)
    metrics_path, csv_path = result.write(tmp_path)
    lines = csv_path.read_text().splitlines()
    assert tuple(lines[0].split(",")) == simloop.COLUMN_NAMES
    parsed = np.array([[float(cell) if cell else math.nan for cell in line.split(",")] for line in lines[1:]])
    np.testing.assert_array_equal(parsed, result.trajectory)  # NaN == NaN here: the final row's inputs
    assert json.loads(metrics_path.read_text()) == result.metrics


def test_run_batch_over_100_seeds_equals_sequential_runs():
    seeds = range(100)
    sequential = [simloop.run(seed=s, steps=400) for s in seeds]
    for threads in (1, 2):
        batch = simloop.run_batch(seeds=seeds, steps=400, threads=threads)
        assert len(batch) == 100
        for one, many in zip(sequential, batch.results):
            assert many.metrics == one.metrics
            assert many.trajectory.tobytes() == one.trajectory.tobytes()


def test_run_batch_orders_seeds_then_timesteps():
    batch = simloop.run_batch(seeds=[3, 4], timesteps=[0.002, 0.01], steps=50)
    assert [(r.metrics["seed"], r.timestep) for r in batch.results] == [(3, 0.002), (3, 0.01), (4, 0.002), (4, 0.01)]
