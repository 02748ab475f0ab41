"""Batches and sweeps past one machine: chunks of runs on a Dask cluster or any
concurrent.futures executor, and a table of metrics back.

Work goes out in chunks. Each chunk runs the C++ batch (run_batch,
run_scenario_batch or sweep) with its own threads on whichever worker takes
it, and sends back only a compact table of metrics, never trajectories: the
client holds the table and nothing else, however many runs there are.

What travels to a worker is plain data: the scene as an MJCF path (or the
chapter's embedded scene), a scenario as its TOML text and the folder its
relative paths resolve against, the run parameters, and the simloop and
MuJoCo versions of the client. A worker refuses a chunk from a client of
another version (the bits of a run are those of one build). Files a scenario
or model names must exist at the same paths on every worker, with the same
content: the client sends the sha256 of each (input_files), and a chunk
whose worker reads other bytes raises InputMismatch.

Dask reschedules the tasks of a worker that dies (up to the scheduler's
`distributed.scheduler.allowed-failures`, 3 by default); every chunk is a
pure function of its inputs, so a chunk computed twice gives the same bits.
dask is imported only when a dask Client is passed.
"""

from __future__ import annotations

import concurrent.futures
import itertools
import math
import os
import socket
import uuid
from typing import Any, Callable, Dict, Iterable, Iterator, List, Optional, Sequence, Tuple, Union, cast

import numpy as np

from . import _core, input_files
from ._checks import MAX_CHUNK_RUNS, _check_int, _check_threads
from ._chunk_inputs import InputMismatch as InputMismatch  # public here, as VersionMismatch is
from ._chunk_inputs import SceneParam, _scenario, _scene, _with_params, scenario_source, scene_inputs, scene_source
from .policy import _check_policy_travels, _decider
from .tables import BatchTable, _table, param_column

# One run of a batch: its row index in the whole batch, seed, timestep (None:
# the scenario's own) and scene parameters.
Run = Tuple[int, int, Optional[float], Tuple[SceneParam, ...]]

MAX_CHUNK_SIZE = 64


def versions() -> Tuple[str, str]:
    """(simloop's version, MuJoCo's version) of this process."""
    return (_core.__version__, _core.MUJOCO_VERSION)


def _worker_versions() -> Tuple[str, str]:
    """versions(), as a worker reports its own (called by reference there)."""
    return versions()


class VersionMismatch(RuntimeError):
    """A worker runs another simloop or MuJoCo than the client."""


def _check_versions(expected: Sequence[str]) -> None:
    here = versions()
    if tuple(expected) != here:
        raise VersionMismatch(
            f"worker {socket.gethostname()} has simloop {here[0]} ({here[1]}), the client simloop {expected[0]} "
            f"({expected[1]}): install the same simloop on every machine (a run's bits are those of one build)"
        )


# ---- The chunk: runs on a worker, returns only metrics -------------------


# A scenario batch's own inputs ("controls", "initial_state": arrays or
# None), a chunk's: a per-run array's rows for the chunk's runs, or a shared one whole.
Inputs = Dict[str, Optional[np.ndarray]]
_PER_RUN_DIMS = {"controls": 3, "initial_state": 2}  # (runs, steps, nu), (runs, state_size)


def _rows_of(inputs: Optional[Inputs], rows: Union[slice, List[int]]) -> Optional[Inputs]:
    """`inputs` for the runs `rows` of those they were given for."""
    if not inputs:
        return None
    return {
        name: None if a is None else np.ascontiguousarray(a[rows]) if a.ndim == _PER_RUN_DIMS[name] else a
        for name, a in inputs.items()
    }


def run_chunk(job: Dict[str, Any], runs: Sequence[Run], inputs: Optional[Inputs] = None) -> BatchTable[Any]:
    """Runs `runs` of `job` as a metrics-only C++ batch (job["threads"]
    threads; no trajectory kept) and returns their table (metrics_table).
    Runs sharing scene parameters share one modified model. inputs: the
    chunk's controls and initial states (a scenario's, _rows_of)."""
    _check_versions(job["versions"])
    groups: Dict[Tuple[SceneParam, ...], List[int]] = {}
    for i, run in enumerate(runs):
        groups.setdefault(run[3], []).append(i)
    results: List[Any] = [None] * len(runs)
    for params, members in groups.items():
        out: Union[List[_core.RunResult], List[_core.ScenarioResult]]
        if job["kind"] == "chapter":
            model = _with_params(_scene(job["scene"], job["inputs"]), params)
            # cast: the chapter's runs always have a timestep (run_batch_on); RunConfig checks it anyway.
            configs = [
                _core.RunConfig(
                    runs[i][1],
                    job["steps"],
                    cast(float, runs[i][2]),
                    job["perturb"],
                    job["smoke"],
                    1,
                    job["audit_energy"],
                    job["rng"],
                )
                for i in members
            ]
            out = _core.run_batch(model, configs, job["threads"], keep_rows=False)
        else:
            scenario, scene = _scenario(job["scenario"], job["inputs"])
            model = _with_params(scene, params)
            scenario_configs = [
                _core.ScenarioConfig(runs[i][1], job["rng"], runs[i][2], job["steps"], job["perturb"], 1)
                for i in members
            ]
            own = _rows_of(inputs, members) or {}
            decide, every = (None, 1)
            if job.get("policy") is not None:  # the chunk's own copy, unpickled here
                decide, every = _decider(job["policy"], job["control_every"], model, scenario, scenario_configs[0])
            out = _core.run_scenario_batch(
                model,
                scenario,
                scenario_configs,
                job["threads"],
                controls=own.get("controls"),
                initial_state=own.get("initial_state"),
                decide=decide,
                control_every=every,
                keep_rows=False,
            )
        for i, result in zip(members, out):
            results[i] = result
    return metrics_table(runs, results)


def metrics_table(runs: Sequence[Run], results: Sequence[Any]) -> BatchTable[Any]:
    """The table of a chunk, without its results: `run` (the row's index in
    the whole batch), one column per scene parameter of the run
    (param_column), then simloop.table's other columns for the results (the
    parameters, the metrics unrounded, warning counts for every name in
    WARNING_NAMES, diverged): the same table a local metrics-only batch
    gives, so chunks join and Parquet files append."""
    local = _table(list(results), keep_results=False)
    columns: Dict[str, np.ndarray] = {"run": np.array([run[0] for run in runs], dtype=np.int64)}
    for j, (kind, name, _) in enumerate(runs[0][3] if runs else ()):
        columns[param_column(kind, name)] = np.array([run[3][j][2] for run in runs], dtype=np.float64)
    columns.update((name, values) for name, values in local.columns.items() if name != "run")
    return BatchTable(columns)


# ---- Executors -------------------------------------------------------------


def _is_dask_client(executor: object) -> bool:
    return type(executor).__module__.split(".")[0] == "distributed" and hasattr(executor, "scheduler_info")


class _Pool:
    """The submit-and-result shape shared by dask's Client and
    concurrent.futures executors; None runs chunks here, one after another,
    with the C++ threads (and Ctrl-C is heard within a chunk of steps)."""

    def __init__(self, executor: object) -> None:
        # Any: a dask.distributed Client (untyped), a concurrent.futures.Executor or None, told apart by self.dask.
        self.executor: Any = executor
        self.dask = _is_dask_client(executor)
        self.token = uuid.uuid4().hex  # dask keys: unique to this batch
        if executor is not None and not self.dask and not isinstance(executor, concurrent.futures.Executor):
            raise TypeError(
                "executor must be None, a dask.distributed Client or a concurrent.futures.Executor, "
                f"got {type(executor).__name__}"
            )

    def workers(self) -> int:
        if self.executor is None:
            return 1
        if self.dask:
            threads: int = max(1, sum(self.executor.nthreads().values()))
            return threads
        return max(1, int(getattr(self.executor, "_max_workers", 0) or os.cpu_count() or 1))

    def check_workers(self) -> None:
        """Asks every dask worker for its versions up front, for a clear
        message before any work goes out (a worker without simloop, or with
        another version). Chunks check again (workers may join later)."""
        if not self.dask:
            return
        try:
            found = self.executor.run(_worker_versions)
        except Exception as e:  # a worker that cannot import simloop at all
            raise VersionMismatch(
                f"a worker cannot run simloop ({type(e).__name__}: {e}); install simloop "
                f"{_core.__version__} on every machine"
            ) from None
        mine = versions()
        for address, theirs in found.items():
            if tuple(theirs) != mine:
                raise VersionMismatch(
                    f"worker {address} has simloop {theirs[0]} ({theirs[1]}), the client simloop "
                    f"{mine[0]} ({mine[1]}): install the same simloop on every machine"
                )

    def map_unordered(
        self, fn: Callable[..., Any], tasks: Iterable[Tuple[int, Tuple[Any, ...]]], window: int
    ) -> Iterator[Tuple[int, Any]]:
        """Yields (key, fn(*args)) as tasks finish, with at most `window` in flight."""
        tasks = iter(tasks)
        if self.executor is None:
            for key, args in tasks:
                yield key, fn(*args)
            return
        if self.dask:
            from distributed import as_completed
        pending: Dict[Any, int] = {}
        done: Iterable[Any]
        waiter = as_completed() if self.dask else None
        try:
            for key, args in itertools.islice(tasks, window):
                future = self._submit(fn, key, args)
                pending[future] = key
                if waiter is not None:
                    waiter.add(future)
            while pending:
                if waiter is not None:
                    done = [next(waiter)]
                else:
                    done, _ = concurrent.futures.wait(list(pending), return_when=concurrent.futures.FIRST_COMPLETED)
                for future in done:
                    key = pending.pop(future)
                    value = future.result()
                    for next_key, args in itertools.islice(tasks, 1):
                        new = self._submit(fn, next_key, args)
                        pending[new] = next_key
                        if waiter is not None:
                            waiter.add(new)
                    yield key, value
        finally:
            for future in pending:
                future.cancel()

    def _submit(self, fn: Callable[..., Any], key: int, args: Tuple[Any, ...]) -> Any:
        if self.dask:
            return self.executor.submit(fn, *args, pure=False, key=f"simloop-chunk-{self.token}-{key}")
        return self.executor.submit(fn, *args)


def default_chunk_size(runs: int, workers: int) -> int:
    """Chunks enough for every worker to get about four, of at most MAX_CHUNK_SIZE runs."""
    return max(1, min(MAX_CHUNK_SIZE, math.ceil(runs / (4 * max(1, workers)))))


def chunk_ranges(total: int, chunk_size: int) -> List[Tuple[int, int]]:
    return [(start, min(total, start + chunk_size)) for start in range(0, total, chunk_size)]


def iter_chunks(
    job: Dict[str, Any],
    runs: Sequence[Run],
    executor: object,
    *,
    chunk_size: Optional[int] = None,
    skip: Iterable[int] = (),
    inputs: Optional[Inputs] = None,
) -> Iterator[Tuple[int, BatchTable[Any]]]:
    """Runs `runs` in chunks on `executor` and yields (chunk index, columns)
    as chunks finish (not in order). Chunks whose index is in `skip` are
    not run. inputs: a scenario batch's, for `runs` in order; each chunk
    takes its own."""
    pool = _Pool(executor)
    pool.check_workers()
    size = chunk_size or default_chunk_size(len(runs), pool.workers())
    skipped = set(skip)
    tasks = (
        (k, (job, list(runs[a:b]), _rows_of(inputs, slice(a, b))))
        for k, (a, b) in enumerate(chunk_ranges(len(runs), size))
        if k not in skipped
    )
    yield from pool.map_unordered(run_chunk, tasks, window=max(8, 4 * pool.workers()))


def run_table(
    job: Dict[str, Any],
    runs: Sequence[Run],
    executor: object,
    *,
    chunk_size: Optional[int] = None,
    progress: Optional[Callable[[int, int], object]] = None,
    inputs: Optional[Inputs] = None,
) -> BatchTable[Any]:
    """Every run's metrics, in the order of `runs`. progress(runs_done, runs_total) after each chunk."""
    chunks: Dict[int, BatchTable[Any]] = {}
    done = 0
    for index, chunk in iter_chunks(job, runs, executor, chunk_size=chunk_size, inputs=inputs):
        chunks[index] = chunk
        done += len(chunk)
        if progress is not None:
            progress(done, len(runs))
    return BatchTable.concat([chunks[k] for k in sorted(chunks)])


def _threads(threads: Optional[int]) -> int:
    """A worker's threads: None is 1 (a cluster's worker has its own cores to share)."""
    return 1 if threads is None else _check_threads(threads)


def _chunk_size(chunk_size: Optional[int]) -> Optional[int]:
    return None if chunk_size is None else _check_int("chunk_size", chunk_size, 1, MAX_CHUNK_RUNS)


# ---- The API's executor= paths (arguments already checked by the callers) --


def run_batch_on(
    executor: object,
    configs: Sequence["_core.RunConfig"],
    model: object,
    threads: Optional[int],
    chunk_size: Optional[int],
    progress: Optional[Callable[[int, int], object]],
) -> BatchTable["_core.RunResult"]:
    """simloop.run_batch(..., executor=...): configs as run_batch built them."""
    first = configs[0] if configs else None
    source = scene_source(model)
    job = {
        "kind": "chapter",
        "scene": source,
        "inputs": scene_inputs(source),
        "versions": versions(),
        "threads": _threads(threads),
        "steps": first.steps if first else 2000,
        "perturb": first.perturb if first else True,
        "smoke": first.smoke if first else False,
        "audit_energy": first.audit_energy if first else False,
        "rng": first.rng if first else "mt19937_64",
    }
    runs = [(i, c.seed, c.timestep, ()) for i, c in enumerate(configs)]
    return run_table(job, runs, executor, chunk_size=_chunk_size(chunk_size), progress=progress)


def run_scenario_batch_on(
    executor: object,
    scenario: Any,
    seeds: Sequence[int],
    timesteps: Sequence[Optional[float]],
    *,
    rng: str,
    steps: Optional[int],
    perturb: bool,
    threads: Optional[int],
    chunk_size: Optional[int],
    progress: Optional[Callable[[int, int], object]],
    inputs: Optional[Inputs] = None,
    policy: object = None,
    control_every: int = 1,
) -> BatchTable["_core.ScenarioResult"]:
    """simloop.run_scenario_batch(..., executor=...); inputs: its controls and initial_state, shapes checked;
    policy: sent with every chunk (checked here to pickle as the executor will pickle it)."""
    job = scenario_job(scenario, rng=rng, steps=steps, perturb=perturb, threads=_threads(threads))
    if policy is not None:
        _check_policy_travels(policy, executor, dask=_is_dask_client(executor))
        job.update(policy=policy, control_every=control_every)
    runs = [(i, s, t, ()) for i, (s, t) in enumerate(itertools.product(seeds, timesteps))]
    return run_table(job, runs, executor, chunk_size=_chunk_size(chunk_size), progress=progress, inputs=inputs)


def scenario_job(
    scenario: Any, *, rng: str = "mt19937_64", steps: Optional[int] = None, perturb: bool = True, threads: int = 1
) -> Dict[str, Any]:
    return {
        "kind": "scenario",
        "scenario": scenario_source(scenario),
        "inputs": input_files.digests(input_files.scenario_files(scenario._core)),
        "versions": versions(),
        "threads": threads,
        "rng": rng,
        "steps": steps,
        "perturb": perturb,
    }


def _sweep_chunk(
    scene: Tuple[str, str],
    inputs: Dict[str, str],
    versions_expected: Sequence[str],
    timesteps: Sequence[float],
    duration: float,
    threads: int,
) -> "_core.SweepResult":
    _check_versions(versions_expected)
    return _core.sweep(_scene(scene, inputs), list(timesteps), duration, threads)  # pickles as bytes, bits unchanged


def sweep_on(
    executor: object,
    timesteps: Sequence[float],
    duration: float,
    model: object,
    threads: Optional[int],
    chunk_size: Optional[int],
    progress: Optional[Callable[[int, int], object]],
) -> "_core.SweepResult":
    """simloop.sweep(..., executor=...): the same SweepResult as a local sweep,
    its timesteps run in chunks on the executor's workers."""
    ordered = sorted(set(timesteps))  # as the C++ sweep orders them: ascending, duplicates dropped
    if not ordered:
        raise ValueError("timesteps must not be empty")  # as the C++ sweep says it
    for t in ordered:
        _core.sweep_steps(duration, t)  # refuses a point that cannot be run, before any work goes out
    pool = _Pool(executor)
    pool.check_workers()
    size = _chunk_size(chunk_size) or default_chunk_size(len(ordered), pool.workers())
    source, count = scene_source(model), _threads(threads)
    ranges = chunk_ranges(len(ordered), size)
    inputs = scene_inputs(source)
    tasks = ((k, (source, inputs, versions(), ordered[a:b], duration, count)) for k, (a, b) in enumerate(ranges))
    parts: Dict[int, "_core.SweepResult"] = {}
    done = 0
    for key, part in pool.map_unordered(_sweep_chunk, tasks, window=max(8, 4 * pool.workers())):
        parts[key] = part
        done += len(part.points)
        if progress is not None:
            progress(done, len(ordered))
    return _core.join_sweeps([parts[k] for k in sorted(parts)])  # judged as one sweep
