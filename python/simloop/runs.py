"""The chapter's runs from Python: run once, run_batch over seeds and
timesteps, and draw_shove (the shove a run would draw).

Arguments are checked for their types here and for their values by the C++
loop (simloop._checks); the long calls stop within a few milliseconds on
Ctrl-C and raise KeyboardInterrupt; `progress=` takes a callable
progress(steps_done, steps_total), called from the calling thread at most
every 20 ms and once at the end (an exception it raises stops the work and
reaches the caller).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Callable, Iterable, List, Optional, Union, overload

from . import _core
from ._checks import (
    ModelLike,
    Progress,
    _check_bool,
    _check_int,
    _check_progress,
    _check_real,
    _check_seed,
    _check_str,
    _check_threads,
    _pusher_scene,
    _sequence,
    load_model,
)
from ._core import RunResult
from .policy import _check_no_control_every
from .scenario import Scenario
from .scenario_runs import run_scenario

if TYPE_CHECKING:
    from .tables import BatchTable


def _config(
    seed: object,
    steps: object,
    timestep: object,
    perturb: object,
    smoke: object,
    record_every: object,
    audit_energy: object = False,
    rng: object = "mt19937_64",
) -> _core.RunConfig:
    """A run's config: the types checked here; the values by the C++ side
    (RunConfig an unknown rng, the run the timestep, steps and record_every)."""
    return _core.RunConfig(
        seed=_check_seed("seed", seed),
        steps=_check_int("steps", steps),
        timestep=_check_real("timestep", timestep),
        perturb=_check_bool("perturb", perturb),
        smoke=_check_bool("smoke", smoke),
        record_every=_check_int("record_every", record_every),
        audit_energy=_check_bool("audit_energy", audit_energy),
        rng=_check_str("rng", rng),
    )


@overload
def run(
    seed: int = 0,
    steps: int = 2000,
    timestep: float = 0.002,
    perturb: bool = True,
    smoke: bool = False,
    model: ModelLike = None,
    record_every: int = 1,
    audit_energy: bool = False,
    rng: str = "mt19937_64",
    *,
    progress: Progress = None,
    policy: None = None,
    control_every: int = 1,
) -> RunResult: ...


@overload
def run(
    seed: int = 0,
    steps: int = 2000,
    timestep: float = 0.002,
    perturb: bool = True,
    smoke: bool = False,
    model: ModelLike = None,
    record_every: int = 1,
    audit_energy: bool = False,
    rng: str = "mt19937_64",
    *,
    progress: Progress = None,
    policy: Callable[..., object],
    control_every: int = 1,
) -> "_core.ScenarioResult": ...


def run(
    seed: int = 0,
    steps: int = 2000,
    timestep: float = 0.002,
    perturb: bool = True,
    smoke: bool = False,
    model: ModelLike = None,
    record_every: int = 1,
    audit_energy: bool = False,
    rng: str = "mt19937_64",
    *,
    progress: Progress = None,
    policy: Optional[Callable[..., object]] = None,
    control_every: int = 1,
) -> "Union[RunResult, _core.ScenarioResult]":
    """Runs the chapter's loop once and returns what happened.

    seed: seeds the shove (0 to 2**64-1), and nothing else.
    steps: steps to run, 1 to 2**62-1 as sim_loop's --steps (ignored with
        smoke=True, which runs a fixed 300).
    timestep: sim seconds per mj_step, written into a copy of the model.
    perturb: False skips the shove (the baseline run).
    model: None (the chapter's scene), a simloop.Model, or an MJCF path.
    record_every: keep every K-th step in the trajectory (the final state is
        always kept), 1 to 2**62-1 as sim_loop's --record-every.
    audit_energy: account for every joule: the trajectory gains the
        ENERGY_COLUMN_NAMES columns and .energy holds the totals.
    rng: the generator that draws the shove from the seed: "mt19937_64"
        (std::mt19937_64, the default) or "numpy" (the chapter's
        np.random.default_rng(seed), PCG64, reproduced in C++ bit for bit;
        seed 0 shoves +9.82 N).
    progress: None, or progress(steps_done, steps_total), called at most
        every 20 ms and at the end; Ctrl-C raises KeyboardInterrupt promptly.

    The result has .metrics (the dict metrics.json holds), .trajectory (a
    read-only (rows, 22) float64 view, no copy) and .columns / .column(name),
    .shove, .warnings, .summary(), and .write(out) for metrics.json and
    trajectory.csv, byte-identical to `sim_loop` with the same flags.

    policy, control_every: a policy in the loop (see run_scenario): the run
    then goes through the chapter's scenario loop (Scenario.chapter(), with
    this call's seed, steps, timestep, perturb, model, record_every, rng)
    and returns a ScenarioResult (its columns named from the scene, its
    metrics the scenario's). The policy's ctrl replaces the chapter's 1.0;
    the shove acts as drawn. audit_energy is not available with a policy.
    """
    config = _config(seed, steps, timestep, perturb, smoke, record_every, audit_energy, rng)
    if policy is not None:
        return _run_chapter_with_policy(config, model, progress, policy, control_every)
    _check_no_control_every(control_every)
    return _core.run(load_model(model), config, progress=_check_progress(progress))


def _run_chapter_with_policy(
    config: "_core.RunConfig", model: ModelLike, progress: Progress, policy: Callable[..., object], control_every: int
) -> "_core.ScenarioResult":
    if config.audit_energy:
        raise ValueError(
            "audit_energy=True is not available with a policy (the audit is the chapter's open "
            "loop's); leave one of them out"
        )
    return run_scenario(
        Scenario.chapter(),
        seed=config.seed,
        rng=config.rng,
        timestep=config.timestep,
        steps=_core.SMOKE_STEPS if config.smoke else config.steps,
        perturb=config.perturb,
        record_every=config.record_every,
        model=load_model(model),
        progress=progress,
        policy=policy,
        control_every=control_every,
    )


def draw_shove(seed: int = 0, steps: int = 2000, rng: str = "mt19937_64") -> "_core.Shove":
    """The shove a run of `steps` steps draws from `seed`, without running it.

    The same Shove as run(seed=seed, steps=steps, rng=rng).shove: newtons,
    sign, force_y, start_step (steps // 2) and steps (50).
    """
    return _core.draw_shove(_check_seed("seed", seed), _check_int("steps", steps), _check_str("rng", rng))


def run_batch(
    seeds: Iterable[int] = (0,),
    timesteps: Iterable[float] = (0.002,),
    *,
    steps: int = 2000,
    perturb: bool = True,
    smoke: bool = False,
    model: ModelLike = None,
    record_every: int = 1,
    audit_energy: bool = False,
    threads: Optional[int] = None,
    rng: str = "mt19937_64",
    progress: Progress = None,
    metrics_only: bool = False,
    executor: object = None,
    chunk_size: Optional[int] = None,
) -> "BatchTable[RunResult]":
    """Runs every (seed, timestep) pair over one compiled model, in parallel,
    and returns a simloop.BatchTable: one row per run.

    Runs come in the order of itertools.product(seeds, timesteps), and each
    is bitwise identical to run() with the same arguments, whatever `threads`
    is (None: one worker per core). Each worker steps its own MuJoCo data;
    the model is shared. Every argument is checked before any run starts.
    progress: as for run(), over the steps of all the runs.

    The table is the same in every mode below (the same columns, order and
    dtypes, the same bits): `run` (the row's index in the batch), the
    parameters, the metrics unrounded, the shove, warning counts and
    diverged; table["lateral_drift"], table.row(i), .to_pandas(),
    .to_arrow(). Run locally without metrics_only, the batch also keeps
    each run's RunResult (trajectory and all) as table.results, in the
    rows' order: table.results[i] is run i.

    metrics_only: keep no trajectories (and no results: table.results
    raises ValueError), so that memory does not grow with the runs' lengths.

    executor: a dask.distributed Client or a concurrent.futures.Executor
    (simloop.distributed): the runs go out in chunks of chunk_size (None: a
    default), each chunk run on a worker by the C++ batch with `threads`
    threads (None: 1), metrics only (no results come back), in the same
    order. model must then be None or an MJCF path; progress is called as
    progress(runs_done, runs_total) as chunks finish.
    """
    seed_list = [_check_seed("seeds[%d]" % i, s) for i, s in enumerate(_sequence("seeds", seeds))]
    timestep_list = [_check_real("timesteps[%d]" % i, t) for i, t in enumerate(_sequence("timesteps", timesteps))]
    workers = _check_threads(threads)
    configs = [
        _config(s, steps, t, perturb, smoke, record_every, audit_energy, rng) for s in seed_list for t in timestep_list
    ]
    metrics_only = _check_bool("metrics_only", metrics_only)
    if executor is not None:
        from .distributed import run_batch_on  # numpy: `import simloop` does not load it

        _check_before_sending(configs)
        return run_batch_on(executor, configs, model, threads, chunk_size, _check_progress(progress))
    from .tables import _table  # numpy: `import simloop` does not load it

    results = _core.run_batch(
        load_model(model), configs, workers, keep_rows=not metrics_only, progress=_check_progress(progress)
    )
    return _table(results, keep_results=not metrics_only)


def _check_before_sending(configs: List[_core.RunConfig]) -> None:
    """What the C++ side checks of a run's values (timestep, steps,
    record_every), here, once per timestep, before any work goes out to an
    executor: the chapter's run is the chapter's scenario (Scenario.chapter()),
    whose checks are the same, without a run."""
    chapter = Scenario.chapter()._core
    for config in {c.timestep: c for c in configs}.values():
        steps = _core.SMOKE_STEPS if config.smoke else config.steps
        _core.check_scenario(
            _pusher_scene(),
            chapter,
            _core.ScenarioConfig(0, config.rng, config.timestep, steps, config.perturb, config.record_every),
        )
