"""Break It, measured: the baseline (or a scenario) at many timesteps over the
same span of sim time, and whether each is stable (the C++ sweep, in
parallel over one compiled model; or in chunks on an executor).
"""

from __future__ import annotations

from typing import Any, Iterable, List, Optional, Union, overload

from . import _core
from ._checks import (
    ModelLike,
    Progress,
    _check_bool,
    _check_progress,
    _check_real,
    _check_seed,
    _check_str,
    _check_threads,
    _reals,
    load_model,
)
from ._core import SweepResult
from .scenario import _scenario_and_scene


# Typed for the checker: the chapter's SweepResult, or a ScenarioSweepResult for scenario=.
@overload
def sweep(
    timesteps: Optional[Iterable[float]] = None,
    duration: Optional[float] = None,
    threads: Optional[int] = None,
    model: ModelLike = None,
    *,
    scenario: None = None,
    seed: int = 0,
    rng: str = "mt19937_64",
    perturb: bool = True,
    progress: Progress = None,
    executor: object = None,
    chunk_size: Optional[int] = None,
) -> SweepResult: ...


@overload
def sweep(
    timesteps: Optional[Iterable[float]] = None,
    duration: Optional[float] = None,
    threads: Optional[int] = None,
    model: ModelLike = None,
    *,
    scenario: object,
    seed: int = 0,
    rng: str = "mt19937_64",
    perturb: bool = True,
    progress: Progress = None,
    executor: object = None,
    chunk_size: Optional[int] = None,
) -> "_core.ScenarioSweepResult": ...


def sweep(
    timesteps: Optional[Iterable[float]] = None,
    duration: Optional[float] = None,
    threads: Optional[int] = None,
    model: ModelLike = None,
    *,
    scenario: Any = None,
    seed: int = 0,
    rng: str = "mt19937_64",
    perturb: bool = True,
    progress: Progress = None,
    executor: object = None,
    chunk_size: Optional[int] = None,
) -> "Union[SweepResult, _core.ScenarioSweepResult]":
    """The baseline (no shove) at many timesteps over the same span of sim time.

    timesteps: None for the default: 25 round timesteps (1, 2, 3, 4, 5, 6 and
        8 per decade) from 0.0005 s to 1 s, from the stable range through the
        edge to the box sinking into the floor.
    duration: sim seconds each run covers (round(duration / timestep) steps);
        None: 4 s (a scenario's: its own length).

    scenario: a simloop.Scenario or a scenario file's path sweeps that
        scenario instead (with seed, rng and perturb; model: its scene
        already compiled), and returns a ScenarioSweepResult: per timestep
        the warnings, simloop_DIVERGED, the largest speed of any recorded
        body, each one's final position and its distance from the finest
        timestep's, and whether it blew up (warned, or a body ended more than
        SCENARIO_SWEEP_TOLERANCE times the scene's size from the finest
        timestep's). The default grid drops timesteps that would leave a run
        under 4 steps. Each point is bitwise run_scenario at that timestep.

    Runs in parallel over one compiled model with the energy audit on. The
    result's .points hold, per timestep, peak box z, largest |y|, the final
    positions, warnings, the audit's figures and whether it is stable; .edge
    is the largest timestep below which all are stable; .summary() the table,
    .write(out) sweep.csv. The criterion: the box rises at most 5 mm above
    rest, ends at most 1 mm below rest, and MuJoCo raised no warning.
    progress: as for run(), over the steps of all the timesteps.
    executor: a dask.distributed Client or a concurrent.futures.Executor: the
    timesteps go out in chunks (chunk_size), each swept on a worker with
    `threads` threads (None: 1); the same SweepResult comes back. model must
    then be None or an MJCF path; progress(points_done, points_total).
    """
    values = None if timesteps is None else _reals("timesteps", timesteps)
    span = None if duration is None else _check_real("duration", duration)
    if executor is not None:
        if scenario is not None:
            raise ValueError(
                "sweep(scenario=..., executor=...) is not supported: a scenario sweep runs locally "
                "(use run_scenario_batch(..., timesteps=..., executor=...) for its runs on a cluster)"
            )
        from .distributed import sweep_on  # numpy: `import simloop` does not load it

        return sweep_on(
            executor,
            _core.default_sweep_timesteps() if values is None else values,
            4.0 if span is None else span,
            model,
            threads,
            chunk_size,
            _check_progress(progress),
        )
    workers = _check_threads(threads)
    if scenario is not None:
        return _sweep_scenario(scenario, values, span, workers, model, seed, rng, perturb, progress)
    return _core.sweep(
        load_model(model),
        _core.default_sweep_timesteps() if values is None else values,
        4.0 if span is None else span,
        workers,
        progress=_check_progress(progress),
    )


def _sweep_scenario(
    scenario: Any,
    timesteps: Optional[List[float]],
    duration: Optional[float],
    workers: int,
    model: Any,
    seed: object,
    rng: object,
    perturb: object,
    progress: Progress,
) -> "_core.ScenarioSweepResult":
    """sweep(scenario=...): the arguments' types checked, then the C++ sweep."""
    scenario, scene = _scenario_and_scene(scenario, model)
    config = _core.ScenarioConfig(
        _check_seed("seed", seed), _check_str("rng", rng), None, None, _check_bool("perturb", perturb), 1
    )
    span = _core.scenario_duration(scene, scenario._core) if duration is None else duration
    values = _core.default_scenario_sweep_timesteps(span) if timesteps is None else timesteps
    if timesteps is None and not values:
        # No default timestep gives a run of 4 steps: the C++ check of the
        # finest one says why (or that the duration is not a duration).
        _core.sweep_steps(span, min(_core.default_sweep_timesteps()))
    return _core.sweep_scenario(
        scene, scenario._core, values, span, config, workers, progress=_check_progress(progress)
    )
