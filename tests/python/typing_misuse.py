"""Misuse of the API that mypy --strict must flag, each line with its error code
(tests/python/test_types.py checks the codes line by line). Never run."""

from __future__ import annotations

import simloop

# run is overloaded (a policy makes it a scenario run), so a wrong argument matches no overload.
simloop.run(seed="0")  # error: call-overload
result = simloop.run(seed=0)
drift: str = result.metrics["lateral_drift"]  # error: assignment
result.metrics["no_such_metric"]  # error: typeddict-item
rows: str = result.rows  # error: assignment
result.trajectory = result.trajectory  # error: misc
simloop.run(progress=lambda done: None)  # error: arg-type
simloop.Model.from_file(3)  # error: arg-type
simloop.Sim().step("10")  # error: arg-type
position: float = simloop.Sim().box_position  # error: assignment
simloop.sweep([0.001]).edge + 1.0  # error: operator
for warning in result.warnings:
    name: int = warning.name  # error: assignment
contacts: int = simloop.Sim().contacts  # error: assignment
simloop.run_scenario(simloop.Scenario.chapter()).column(0)  # error: arg-type
# A batch is a table: indexed by column name (a run is batch.results[i]), iterated over its column names.
simloop.run_batch(steps=10)[0]  # error: index
for run_result in simloop.run_batch(steps=10):
    run_result.metrics  # error: attr-defined
