"""Model, Sim, RunResult, ScenarioResult and SweepResult pickle, and come back from worker
processes as they were, bit for bit."""

from __future__ import annotations

import concurrent.futures
import multiprocessing
import pickle
from pathlib import Path

import numpy as np
import pytest
import simloop
from conftest import needs_worker_processes

SCENES = Path(__file__).resolve().parents[1] / "scenes"


def same_trajectory(a, b) -> bool:
    """Bit for bit (the final row's input columns are NaN, which == never equals)."""
    return a.shape == b.shape and a.tobytes() == b.tobytes()


def test_a_model_pickles_as_the_same_compiled_model():
    model = simloop.Model.from_file(SCENES / "walker.xml").with_timestep(0.003)
    back = pickle.loads(pickle.dumps(model))
    assert repr(back) == repr(model) and back.timestep == 0.003 and back.name == "walker"
    assert pickle.dumps(back) == pickle.dumps(model)  # the same bytes again
    scenario = simloop.Scenario.from_file(SCENES / "walker.toml")
    ours = simloop.run_scenario(scenario, seed=3, steps=300, model=model)
    theirs = simloop.run_scenario(scenario, seed=3, steps=300, model=back)
    assert same_trajectory(ours.trajectory, theirs.trajectory)


def test_the_chapters_model_pickles_and_runs_the_chapters_bits():
    back = pickle.loads(pickle.dumps(simloop.Model.pusher_scene()))
    assert back.has_chapter_layout
    assert simloop.run(model=back, steps=400).metrics_json() == simloop.run(steps=400).metrics_json()
    assert same_trajectory(simloop.run(model=back, steps=400).trajectory, simloop.run(steps=400).trajectory)


def test_damaged_pickles_are_refused_with_a_message():
    with pytest.raises(ValueError, match="<saved model>: not a model simloop saved"):
        simloop.Model.__new__(simloop.Model).__setstate__(b"not a model, but long enough")
    saved = simloop.Model.pusher_scene().__getstate__()
    for at in range(0, len(saved), 1 + len(saved) // 1500):  # any one damaged byte, before MuJoCo reads it
        damaged = bytearray(saved)
        damaged[at] ^= 1 + at % 255
        with pytest.raises(ValueError, match="<saved model>: (the saved model is damaged|not a model simloop saved)"):
            simloop.Model.__new__(simloop.Model).__setstate__(bytes(damaged))
    result = simloop.run(steps=20)
    state = result.__getstate__()  # simloop's bytes: the format's version (a uint32) first
    assert isinstance(state, bytes)
    version = int.from_bytes(state[:4], "little")  # the format this build writes and reads
    assert version >= 5  # 5: a record carries its energy audit
    with pytest.raises(ValueError, match="cannot unpickle a RunResult: the saved fields are damaged"):
        simloop.RunResult.__new__(simloop.RunResult).__setstate__(state[:-40])
    newer = rf"pickled by another simloop version \(format {version + 1}; this one reads {version}\)"
    with pytest.raises(ValueError, match=newer):
        simloop.RunResult.__new__(simloop.RunResult).__setstate__((version + 1).to_bytes(4, "little") + state[4:])
    with pytest.raises(ValueError, match="cannot unpickle a RunResult: .* from another simloop version"):
        simloop.RunResult.__new__(simloop.RunResult).__setstate__((3, state))  # format 3's (version, fields)
    with pytest.raises(ValueError, match="cannot unpickle a ScenarioResult: the saved fields are a RunResult's"):
        simloop.ScenarioResult.__new__(simloop.ScenarioResult).__setstate__(state)


@pytest.mark.parametrize("scene", ["pusht.xml", "walker.xml"])
def test_a_pickled_sim_goes_on_bit_for_bit(scene):
    sim = simloop.Sim(SCENES / scene)
    sim.timestep = 0.003
    sim.step(111, ctrl=np.linspace(-0.5, 0.5, sim.model.nu))
    sim.apply_force(body=1, force=[0.0, 0.1, 0.0])
    back = pickle.loads(pickle.dumps(sim))
    assert back.steps_taken == 111 and back.timestep == 0.003
    assert np.array_equal(back.get_state(), sim.get_state())
    sim.step(200)
    back.step(200)
    assert np.array_equal(back.get_state(), sim.get_state())


def test_results_pickle_field_by_field():
    result = simloop.run(seed=5, steps=300, record_every=7, audit_energy=True, rng="numpy")
    back = pickle.loads(pickle.dumps(result))
    assert same_trajectory(back.trajectory, result.trajectory)
    assert back.metrics == result.metrics and back.energy == result.energy
    assert back.unrounded_metrics == result.unrounded_metrics  # the tables' values, not metrics.json's
    assert back.metrics_json() == result.metrics_json() and back.summary() == result.summary()
    assert repr(back.shove) == repr(result.shove) and back.config.rng == "numpy"
    assert (back.rows, back.timestep, back.sim_time) == (result.rows, result.timestep, result.sim_time)
    # and the record under the chapter's report
    assert (back.name, back.seed, back.rng, back.steps) == (result.name, 5, "numpy", 300)
    assert repr(back.disturbances) == repr(result.disturbances) and back.column_units == result.column_units
    assert np.array_equal(back.final_state, result.final_state) and back.final_state.size > 0

    scenario = simloop.run_scenario(SCENES / "walker.toml", seed=2, steps=400, record_every=3)
    again = pickle.loads(pickle.dumps(scenario))
    assert same_trajectory(again.trajectory, scenario.trajectory)
    assert again.column_names == scenario.column_names and again.column_units == scenario.column_units
    assert again.metrics_json() == scenario.metrics_json() and again.summary() == scenario.summary()
    assert repr(again.disturbances) == repr(scenario.disturbances)
    assert np.array_equal(again.final_state, scenario.final_state)  # where a continuation starts
    assert again.final_state.size > 0

    sweep = simloop.sweep([0.002, 0.005, 0.02], duration=1.0)
    swept = pickle.loads(pickle.dumps(sweep))
    assert swept.csv() == sweep.csv() and swept.summary() == sweep.summary() and swept.edge == sweep.edge


@needs_worker_processes
def test_results_come_back_from_worker_processes():
    spawn = multiprocessing.get_context("spawn")
    sim = simloop.Sim(SCENES / "pusht.xml")
    sim.step(50, ctrl=[0.4, -0.2])
    with concurrent.futures.ProcessPoolExecutor(max_workers=2, mp_context=spawn) as pool:
        chapter = pool.submit(simloop.run, seed=4, steps=200)
        scenario = pool.submit(simloop.run_scenario, str(SCENES / "pusht.toml"), seed=1, steps=200)
        sim_back = pool.submit(pickle.loads, pickle.dumps(sim))  # a Sim through a process and back
        chapter, scenario, sim_back = chapter.result(), scenario.result(), sim_back.result()
    assert same_trajectory(chapter.trajectory, simloop.run(seed=4, steps=200).trajectory)
    assert same_trajectory(
        scenario.trajectory, simloop.run_scenario(SCENES / "pusht.toml", seed=1, steps=200).trajectory
    )
    assert np.array_equal(sim_back.get_state(), sim.get_state())


@pytest.mark.parametrize("made", ["keywords", "file", "chapter"])
def test_an_unpickled_scenario_is_the_scenario_everywhere_even_on_an_executor(made):
    scenario = {
        "keywords": lambda: simloop.Scenario(scene=str(SCENES / "pusht.xml"), steps=60, record={"bodies": ["tblock"]}),
        "file": lambda: simloop.Scenario.from_file(SCENES / "pusht.toml"),
        "chapter": simloop.Scenario.chapter,
    }[made]()
    again = pickle.loads(pickle.dumps(scenario))
    assert again.toml == scenario.toml and repr(again) == repr(scenario)
    with concurrent.futures.ThreadPoolExecutor(1) as pool:
        there = simloop.run_scenario_batch(again, seeds=range(2), steps=40, executor=pool)
    here = simloop.run_scenario_batch(scenario, seeds=range(2), steps=40)
    assert there == here  # the same table, bit for bit (an executor's keeps no results to compare)
