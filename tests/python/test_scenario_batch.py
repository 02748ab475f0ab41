"""Batches of scenario runs: the same bits as running each one alone,
whatever the thread count, in itertools.product(seeds, timesteps) order."""

import itertools

import numpy as np
import pytest
import simloop
from conftest import ROOT

SCENES = ROOT / "tests" / "scenes"


def same(a: simloop.ScenarioResult, b: simloop.ScenarioResult) -> bool:
    return (
        a.column_names == b.column_names
        and a.trajectory.tobytes() == b.trajectory.tobytes()
        and a.metrics_json() == b.metrics_json()
        and a.summary() == b.summary()
    )


@pytest.mark.parametrize(
    "name, seeds, timesteps",
    [
        ("pusht.toml", [0, 1, 5], [0.002, 0.004]),  # random bumps: the seed matters
        ("walker.toml", [0], [0.002, None, 0.005]),  # None: the scenario's own timestep
    ],
)
def test_a_batch_is_bitwise_what_the_runs_give_alone(name, seeds, timesteps):
    scenario = simloop.Scenario.from_file(SCENES / name)
    scene = scenario.model()
    alone = [
        simloop.run_scenario(scenario, seed=s, timestep=t, model=scene) for s, t in itertools.product(seeds, timesteps)
    ]
    for threads in (1, 2, 7):
        batch = simloop.run_scenario_batch(scenario, seeds=seeds, timesteps=timesteps, threads=threads)
        assert len(batch) == len(alone)
        for i, (a, b) in enumerate(zip(batch.results, alone)):
            assert same(a, b), f"{name} run {i}, {threads} threads"


def test_the_order_is_itertools_product_and_options_reach_every_run():
    batch = simloop.run_scenario_batch(
        SCENES / "pusht.toml",
        seeds=[3, 4],
        timesteps=[0.004, 0.002],
        steps=200,
        record_every=10,
        perturb=False,
        threads=2,
    )
    assert [(r.seed, r.timestep) for r in batch.results] == [(3, 0.004), (3, 0.002), (4, 0.004), (4, 0.002)]
    assert all(r.steps == 200 and r.rows == 21 and r.disturbances == [] for r in batch.results)
    # no disturbances: the seed changes nothing
    assert batch.results[0].trajectory.tobytes() == batch.results[2].trajectory.tobytes()
    assert np.isfinite(batch.results[1].column("tblock_x")).all()


def test_progress_counts_every_run_and_bad_arguments_are_refused_first():
    calls = []
    simloop.run_scenario_batch(
        SCENES / "pusht.toml",
        seeds=[0, 1, 2],
        steps=300,
        threads=2,
        progress=lambda done, total: calls.append((done, total)),
    )
    assert calls[-1] == (900, 900)
    assert all(total == 900 for _, total in calls)
    with pytest.raises(ValueError, match=r"^run 1: timestep must be a positive, finite number of seconds, got -1.0$"):
        simloop.run_scenario_batch(SCENES / "pusht.toml", timesteps=[0.002, -1.0])
    with pytest.raises(ValueError, match=r"^steps 1000000000000 with record_every 1 \(run 0, the largest of 2 runs\)"):
        simloop.run_scenario_batch(SCENES / "pusht.toml", seeds=[0, 1], steps=10**12)
    with pytest.raises(TypeError, match="seeds must be a sequence"):
        simloop.run_scenario_batch(SCENES / "pusht.toml", seeds=3)
    with pytest.raises(ValueError, match="no body named"):
        simloop.run_scenario_batch(simloop.Scenario(SCENES / "pusht.xml", record={"bodies": ["tblok"]}), seeds=[0, 1])
    empty = simloop.run_scenario_batch(SCENES / "pusht.toml", seeds=[])
    assert len(empty) == 0 and empty.column_names == [] and empty.results == []


def test_drawn_scene_parameters_are_reported_per_run_and_are_what_ran(tmp_path):
    """A domain-randomisation batch is read by its draws: each run's, in its result, its table row and its
    metrics, and each is the value that ran (a run on a model with that value gives the same bits)."""
    (tmp_path / "drawn.toml").write_text(
        f'scene = "{SCENES / "walker.xml"}"\nsteps = 40\n[[reset.param]]\n'
        'kind = "mass"\nname = "torso"\nuniform = [5.0, 7.0]\n'
    )
    table = simloop.run_scenario_batch(tmp_path / "drawn.toml", seeds=range(3))
    masses = [r.params[0]["value"] for r in table.results]
    assert len(set(masses)) == 3 and all(5.0 <= m < 7.0 for m in masses)
    assert list(table["mass_torso"]) == masses
    first = table.results[0]
    assert first.params == [{"kind": "mass", "name": "torso", "value": masses[0]}]
    assert first.metrics["params"] == [{"kind": "mass", "name": "torso", "value": round(masses[0], 6)}]
    (tmp_path / "undrawn.toml").write_text(f'scene = "{SCENES / "walker.xml"}"\nsteps = 40\n')
    undrawn = simloop.Scenario.from_file(tmp_path / "undrawn.toml")
    heavier = simloop._core.with_scene_params(undrawn.model(), [("mass", "torso", masses[0])])
    again = simloop.run_scenario(undrawn, seed=0, model=heavier)
    assert np.array_equal(again.trajectory, first.trajectory, equal_nan=True) and "params" not in again.metrics
