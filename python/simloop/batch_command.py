"""`python -m simloop batch`: a scenario over seeds and a grid of parameters
on this machine's threads or a Dask cluster, into one Parquet file
(parquet_batch), resumable after a stop.
"""

from __future__ import annotations

import itertools
import math
import os
import sys
import time
from typing import TYPE_CHECKING, Any, Dict, List

from . import _core
from ._command import (
    EXIT_RUN_FAILED,
    EXIT_USAGE,
    _fail,
    _peak_memory_mib,
    _ReportLost,
    _stopped_by,
    raise_swallowed_signal,
)
from .scenario import Scenario

if TYPE_CHECKING:
    from .parquet_batch import ParquetBatch


BATCH_USAGE = """usage: python -m simloop batch [--scenario FILE] [--seeds SEEDS] [--timestep S,S,...]
                              [--friction [GEOM=]V,V,...] [--mass BODY=V,V,...] [--damping [JOINT=]V,V,...]
                              [--gravity G,G,...]
                              [--steps N] [--rng mt19937_64|numpy] [--no-perturb]
                              [--scheduler ADDRESS] [--threads N] [--chunk-size N] [--out FILE.parquet] [--resume]

Runs a scenario over seeds and a grid of parameters (their cartesian product)
and writes one Parquet file with a row per run: the parameters, the seed, the
metrics (unrounded), a count per warning and a diverged flag.

  --scenario FILE      a scenario file (TOML); default: the chapter's run
  --seeds SEEDS        ranges and lists: 0:10000 (0 to 9999), 0:100:5, 1,5,9, 0:10,20:30 (default 0)
  --timestep S,...     timesteps, s (default: the scenario's own)
  --friction [GEOM=]V,...  sliding friction of every geom, or of GEOM (repeatable)
  --mass BODY=V,...    BODY's mass, kg, its inertia scaled alike (repeatable)
  --damping [JOINT=]V,...  damping of every joint, or of JOINT (repeatable)
  --gravity G,...      gravity's strength, m/s^2 (its direction kept)
  --steps N            instead of the scenario's length
  --rng NAME           the generator that draws the scenario's random disturbances
  --no-perturb         no disturbances
  --scheduler ADDRESS  a Dask scheduler (tcp://HOST:8786); without it, this machine's threads
  --threads N          C++ threads per chunk (default: every core locally, 1 on a cluster's workers)
  --chunk-size N       runs per chunk (default: about four chunks per worker, at most 64)
  --out FILE           the Parquet file (default outputs/batch.parquet)
  --resume             finish an interrupted batch from FILE.parts/ (what it wrote is not recomputed)

Rows come in the order of itertools.product(the parameters as given,
timesteps, seeds): the seed varies fastest. Ctrl-C stops the batch; the
chunks already done stay in FILE.parts/ for --resume, and FILE is written only
once it is complete."""


# The most runs one batch takes (the client holds each run's parameters):
# command/cli_options.hpp's, as the parser that counts the seeds has it.
MAX_BATCH_RUNS = _core.MAX_BATCH_RUNS


def _parse_batch_args(args: List[str]) -> Dict[str, Any]:
    """The flags, parsed and refused by the commands' one parser
    (command/cli_batch.cc): ValueError in one line naming the flag and the value."""
    parsed = _core.parse_command_line(["batch", *args])
    b = parsed.batch
    return {
        "scenario": b.scenario,
        "seeds": b.seeds,
        "timesteps": b.timesteps or [None],
        "params": b.params,
        "steps": b.steps,
        "rng": b.rng,
        "perturb": b.perturb,
        "scheduler": b.scheduler,
        "threads": b.threads,
        "chunk_size": b.chunk_size,
        "out": b.out,
        "resume": b.resume,
        "help": parsed.help,
    }


def batch_command(args: List[str]) -> int:
    """`python -m simloop batch ...`: see BATCH_USAGE."""
    started = time.perf_counter()
    try:
        opts = _parse_batch_args(args)
    except ValueError as e:
        return _fail(EXIT_USAGE, str(e))
    if opts["help"]:
        print(BATCH_USAGE)
        return 0
    try:
        import pyarrow  # noqa: F401  (the Parquet writer, before any work)
    except ImportError as e:
        return _fail(EXIT_USAGE, f"batch: {e} (pip install 'simloop[dask]' for the batch command)")
    # numpy and pyarrow: loaded for this command only
    from . import distributed, input_files, tables
    from .parquet_batch import ParquetBatch, ResumeError

    # Everything is checked before any file is touched: the scenario, its
    # names, every parameter value on the scene, the length at every timestep.
    try:
        scenario = Scenario.from_file(opts["scenario"]) if opts["scenario"] else Scenario.chapter()
    except (OSError, ValueError) as e:
        return _fail(EXIT_USAGE, f"batch: --scenario: {e}")
    try:
        scene = scenario.model()
        _core.check_scenario_names(scenario._core, scene)
    except (OSError, ValueError, _core.MujocoError) as e:
        return _fail(EXIT_USAGE, f"batch: --scenario: {e}")
    axes = []
    for kind, name, values in opts["params"]:
        # The scenario's own draw at each reset would override the grid's value, which the table would still show.
        for drawn_kind, drawn_name in scenario._core.reset_params:
            if drawn_kind == kind and (drawn_name == name or not drawn_name or not name):
                what = f"{kind} of '{drawn_name}'" if drawn_name else f"{kind} of everything"
                return _fail(
                    EXIT_USAGE,
                    f"batch: --{kind}: the scenario's [[reset.param]] sets {what} at each "
                    "run's reset, which would override the grid: grid it or draw it, not both",
                )
        for value in values:
            try:
                _core.with_scene_params(scene, [(kind, name, value)])
            except ValueError as e:
                return _fail(EXIT_USAGE, f"batch: --{kind}: {e}")
        axes.append([(kind, name, value) for value in values])
    try:
        _core.ScenarioConfig(0, opts["rng"], None, None, True, 1)
    except ValueError as e:
        return _fail(EXIT_USAGE, f"batch: --rng: {e}")
    for t in opts["timesteps"]:
        config = _core.ScenarioConfig(0, opts["rng"], t, opts["steps"], opts["perturb"], _core.MAX_RECORD_EVERY)
        try:
            _core.check_scenario(scene, scenario._core, config)
        except ValueError as e:
            return _fail(EXIT_USAGE, f"batch: {'' if t is None else '--timestep: '}{e}")
    count = math.prod([len(opts["seeds"]), len(opts["timesteps"]), *(len(axis) for axis in axes)])
    if count > MAX_BATCH_RUNS:
        return _fail(
            EXIT_USAGE,
            f"batch: the seeds and the grid make {count} runs; a batch runs at most {MAX_BATCH_RUNS} (split it)",
        )
    runs = [
        (i, seed, t, tuple(params))
        for i, (*params, t, seed) in enumerate(itertools.product(*axes, opts["timesteps"], opts["seeds"]))
    ]

    client = None
    if opts["scheduler"]:
        try:
            from distributed import Client
        except ImportError as e:
            return _fail(EXIT_USAGE, f"batch: --scheduler: {e} (pip install 'simloop[dask]')")
        try:
            client = Client(opts["scheduler"], timeout="10s")
        except (OSError, ValueError, TypeError) as e:
            return _fail(EXIT_USAGE, f"batch: --scheduler {opts['scheduler']}: cannot connect ({e})")
    try:
        threads = opts["threads"] or (1 if client is not None else 0)
        job = distributed.scenario_job(
            scenario, rng=opts["rng"], steps=opts["steps"], perturb=opts["perturb"], threads=threads
        )
        workers = distributed._Pool(client).workers()
        size = opts["chunk_size"] or distributed.default_chunk_size(len(runs), 4 if client is None else workers)
        description = {
            "scenario": opts["scenario"] or "(the chapter's)",
            "seeds": len(opts["seeds"]),
            "timesteps": opts["timesteps"],
            "params": [tables.param_column(kind, name) for kind, name, _ in opts["params"]],
        }
        # The files the batch reads, as they are now: a part written while any was otherwise is refused.
        inputs = {
            **input_files.digests([os.path.abspath(opts["scenario"])] if opts["scenario"] else []),
            **job["inputs"],
        }
        batch = ParquetBatch(opts["out"], job, runs, size, description, inputs)
        if os.path.isdir(opts["out"]):
            return _fail(EXIT_USAGE, f"batch: --out: {opts['out']} is a directory (name the Parquet file)")
        out_dir = os.path.dirname(os.path.abspath(opts["out"]))
        try:
            os.makedirs(out_dir, exist_ok=True)
            # One writer per folder, as for the run commands: two batches on one FILE would mix their parts.
            lock = _core.OutputLock(out_dir)
        except OSError as e:
            return _fail(EXIT_USAGE, f"batch: --out: {e}")
        with lock:
            try:
                earlier = batch.prepare(opts["resume"])
            except ResumeError as e:
                return _fail(EXIT_USAGE, f"batch: {e}")
            return _run_batch(batch, client, earlier, started)
    finally:
        if client is not None:
            client.close()


def _run_batch(batch: "ParquetBatch", client: Any, earlier: int, started: float) -> int:
    from .distributed import InputMismatch, VersionMismatch  # (loaded by batch_command already; numpy)

    total = len(batch.runs)
    bar = None
    if sys.stderr is not None and sys.stderr.isatty():
        from tqdm import tqdm

        bar = tqdm(total=total, initial=earlier, unit="run", file=sys.stderr, dynamic_ncols=True)

    def progress(done: int, _total: int) -> None:
        raise_swallowed_signal()  # a Ctrl-C that Python only reported stops the batch here
        if bar is not None:
            bar.update(done - bar.n)

    try:
        computed = batch.run(client, progress)
    except KeyboardInterrupt as e:
        name, code = _stopped_by(e)
        return _fail(
            code,
            f"interrupted ({name}); {batch.out} not written; {batch.kept_runs()} of {total} runs kept "
            f"in {batch.parts}/ (add --resume to finish)",
        )
    except (VersionMismatch, InputMismatch) as e:
        return _fail(EXIT_RUN_FAILED, f"batch: {e}")
    except Exception as e:  # a worker's failure as it came back (dask's KilledWorker, a MujocoError, ...)
        return _fail(
            EXIT_RUN_FAILED,
            f"batch: {type(e).__name__}: {e} ({batch.kept_runs()} of {total} runs kept in {batch.parts}/; "
            "--resume continues)",
        )
    finally:
        if bar is not None:
            bar.close()
    try:  # FILE is in place: a report that cannot be written says so, not that nothing was
        print(
            f"batch: {total} runs ({computed} run now, {total - computed} from {batch.parts}/)"
            if earlier
            else f"batch: {total} runs"
        )
        print(f"table: {batch.out}")
        print(f"wall-clock: {time.perf_counter() - started:.1f} s, peak memory: {_peak_memory_mib():.1f} MiB")
        sys.stdout.flush()
    except _ReportLost as e:
        return _fail(
            EXIT_RUN_FAILED, f"batch: cannot write the report to standard output ({e}); {batch.out} was written"
        )
    return 0
