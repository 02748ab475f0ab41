"""The public API as a user's script uses it, with the types mypy must infer.

tests/python/test_types.py runs mypy --strict on this file (assert_type fails
the check when an inferred type differs) and then runs it, so the types it
asserts are also what the calls return (the isinstance checks).
"""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any, Dict, List, Optional, Tuple

import numpy as np
import simloop
import simloop.gym
from numpy.typing import NDArray
from typing_extensions import assert_type

result = simloop.run(seed=1, steps=300, audit_energy=True, progress=lambda done, total: None)
assert_type(result, simloop.RunResult)
assert_type(result.trajectory, NDArray[np.float64])
assert result.trajectory.dtype == np.float64
assert_type(result.column("box_x"), NDArray[np.float64])
assert_type(result.metrics["lateral_drift"], float)
assert isinstance(result.metrics["lateral_drift"], float)
assert_type(result.metrics["box_final_pos"], List[float])
assert_type(result.metrics["steps"], int)
assert isinstance(result.metrics["steps"], int)
assert_type(result.energy, Optional[Dict[str, float]])
assert result.energy is not None and isinstance(result.energy["unexplained"], float)
assert_type(result.columns, Dict[str, NDArray[np.float64]])
assert_type(result.column_names, Tuple[str, ...])
assert_type(result.shove.newtons, float)
assert_type(result.warnings, List[simloop.MujocoWarning])
assert_type(result.summary(), str)
assert_type(result.rows, int)
assert isinstance(result.rows, int)

diverged = simloop.run(steps=200, timestep=5.0, perturb=False)
for warning in diverged.warnings:
    assert_type(warning.count, int)
    assert isinstance(warning.count, int) and warning.count > 0
    assert_type(warning.name, str)

batch = simloop.run_batch(seeds=[0, 1], steps=100, threads=1)
assert_type(batch, simloop.BatchTable[simloop.RunResult])
assert_type(batch.results, List[simloop.RunResult])
assert_type(batch.results[0].trajectory, NDArray[np.float64])
assert isinstance(batch.results[0], simloop.RunResult)
assert_type(batch["lateral_drift"], np.ndarray)
assert_type(batch.row(0), Dict[str, Any])
for column_name in batch:
    assert_type(column_name, str)
    assert isinstance(column_name, str)
assert_type(simloop.table(batch.results), simloop.BatchTable[simloop.RunResult])
assert_type(simloop.run_batch(seeds=[0], steps=10, metrics_only=True), simloop.BatchTable[simloop.RunResult])

model = simloop.load_model()
assert_type(model, simloop.Model)
assert_type(model.with_timestep(0.001).timestep, float)
assert_type(simloop.Model.pusher_scene().nq, int)

sim = simloop.Sim(model)
sim.step(10, ctrl=0.5)
sim.apply_force([0.0, 1.0, 0.0])
assert_type(sim.box_position, NDArray[np.float64])
assert isinstance(sim.box_position, np.ndarray) and sim.box_position.dtype == np.float64
assert_type(sim.time, float)
assert isinstance(sim.time, float)
for contact in sim.contacts:
    assert_type(contact.geom1, str)
    assert_type(contact.pos, NDArray[np.float64])

shove = simloop.draw_shove(seed=3)
assert_type(shove, simloop.Shove)
assert_type(shove.start_step, int)

scenario = simloop.Scenario.chapter()
assert_type(scenario.timestep, Optional[float])
scenario_result = simloop.run_scenario(scenario, seed=2, steps=100)
assert_type(scenario_result, simloop.ScenarioResult)
assert_type(scenario_result.column_names, Tuple[str, ...])
assert_type(scenario_result.metrics, Dict[str, Any])
assert_type(scenario_result.bodies, Dict[str, int])
assert_type(scenario_result.trajectory, NDArray[np.float64])

sweep = simloop.sweep([0.002, 0.01], duration=0.2, threads=1)
assert_type(sweep.edge, Optional[float])
assert sweep.edge is None or isinstance(sweep.edge, float)
assert_type(sweep.points[0].stable, bool)
assert isinstance(sweep.points[0].stable, bool)


def write_where(out: Path) -> Tuple[Path, Path]:
    return result.write(out)


# ---- Sim on any scene, state, policies, metrics-only batches, Gymnasium ----

pusht = simloop.Scenario.from_file(simloop.gym.PUSHT_SCENARIO)
scene_sim = simloop.Sim(pusht)
assert_type(scene_sim.model, simloop.Model)
assert_type(scene_sim.state_layout(), List[Tuple[str, int]])
state = scene_sim.get_state()
assert_type(state, NDArray[np.float64])
scene_sim.step(20)
scene_sim.set_state(state)
assert np.array_equal(scene_sim.get_state(), state)
assert_type(scene_sim.body(0).mass, float)
assert_type(copy.copy(scene_sim), simloop.Sim)


def hold(observation: simloop.Observation) -> List[float]:
    return [0.25]


policy_result = simloop.run_scenario(scenario, seed=1, steps=100, policy=hold, control_every=10)
assert_type(policy_result, simloop.ScenarioResult)
assert_type(policy_result.final_state, NDArray[np.float64])

table = simloop.run_scenario_batch(scenario, seeds=[0, 1], steps=50, metrics_only=True, threads=1)
assert_type(table, simloop.BatchTable[simloop.ScenarioResult])
assert isinstance(table, simloop.BatchTable) and not table.has_results
assert_type(simloop.run_scenario_batch(scenario, steps=50, threads=1).results, List[simloop.ScenarioResult])
assert_type(simloop.BatchTable.concat([table, table]), simloop.BatchTable[simloop.ScenarioResult])
assert_type(table.to_dict(), Dict[str, List[Any]])


env = simloop.gym.chapter_env()
env_observation, env_info = env.reset(seed=0)
assert_type(env_observation, NDArray[Any])
assert_type(env_info, Dict[str, Any])
_step_observation, reward, terminated, truncated, _step_info = env.step(np.zeros(1))
assert_type(reward, float)
assert isinstance(reward, float) and isinstance(terminated, bool)
