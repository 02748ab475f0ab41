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
from ._checks import MAX_CHUNK_RUNS, MAX_STEPS, MAX_THREADS
from ._command import EXIT_RUN_FAILED, EXIT_USAGE, _fail, _peak_memory_mib, _ReportLost, _stopped_by
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


class _BatchUsage(ValueError):
    pass


# The most runs one batch takes: the client holds each run's parameters (196
# bytes measured, so about 2 GB at this) before the first starts. Split a
# larger study into batches.
MAX_BATCH_RUNS = 10**7


def _is_whole(text: str) -> bool:
    """ASCII digits only (str.isdigit also takes '²', which int() refuses)."""
    return text.isascii() and text.isdigit()


def _parse_seeds(text: str) -> List[int]:
    ranges: List[range] = []
    for part in text.split(","):
        fields = part.split(":")
        if not all(_is_whole(f) for f in fields) or len(fields) > 3 or not part:
            raise _BatchUsage(f"--seeds: '{text}' is not seeds (N, A:B for A to B-1, A:B:STEP, joined by commas)")
        numbers = [int(f) for f in fields]
        if len(numbers) == 1:
            ranges.append(range(numbers[0], numbers[0] + 1))
        else:
            step = numbers[2] if len(numbers) == 3 else 1
            if step == 0 or numbers[1] <= numbers[0]:
                raise _BatchUsage(f"--seeds: '{part}' is an empty range (A:B runs A to B-1)")
            ranges.append(range(numbers[0], numbers[1], step))
        if ranges[-1][-1] > 2**64 - 1:
            raise _BatchUsage(f"--seeds: '{text}': seeds go from 0 to 2^64-1")
    count = sum(len(r) for r in ranges)  # before any list is made of them
    if count > MAX_BATCH_RUNS:
        raise _BatchUsage(f"--seeds: '{text}' is {count} seeds; a batch runs at most {MAX_BATCH_RUNS} (split it)")
    return [seed for r in ranges for seed in r]


def _parse_numbers(flag: str, text: str) -> List[float]:
    values = []
    for item in text.split(","):
        try:
            value = float(item)
        except ValueError:
            raise _BatchUsage(f"{flag}: '{item}' is not a number (values are joined by commas)") from None
        if not math.isfinite(value):
            raise _BatchUsage(f"{flag}: '{item}' is not a finite number")
        values.append(value)
    return values


def _parse_batch_args(args: List[str]) -> Dict[str, Any]:
    # Any: each option's own type (str, list of seeds, timesteps, parameters, bool, ...), checked as parsed.
    opts: Dict[str, Any] = {
        "scenario": None,
        "seeds": [0],
        "timesteps": [None],
        "params": [],
        "steps": None,
        "rng": "mt19937_64",
        "perturb": True,
        "scheduler": None,
        "threads": None,
        "chunk_size": None,
        "out": "outputs/batch.parquet",
        "resume": False,
        "help": False,
    }
    with_value = {
        "--scenario",
        "--seeds",
        "--timestep",
        "--friction",
        "--mass",
        "--damping",
        "--gravity",
        "--steps",
        "--rng",
        "--scheduler",
        "--threads",
        "--chunk-size",
        "--out",
    }
    i = 0
    while i < len(args):
        flag, eq, value = args[i].partition("=") if args[i].startswith("--") else (args[i], "", "")
        if flag in ("--resume", "--no-perturb", "--help", "-h"):
            if eq:
                raise _BatchUsage(f"{flag} takes no value, got '{args[i]}'")
            opts["resume" if flag == "--resume" else "perturb" if flag == "--no-perturb" else "help"] = (
                flag != "--no-perturb"
            )
            i += 1
            continue
        if flag not in with_value:
            raise _BatchUsage(f"unknown argument '{args[i]}' (see batch --help)")
        if not eq:
            if i + 1 >= len(args):
                raise _BatchUsage(f"{flag} needs a value")
            i += 1
            value = args[i]
        i += 1
        if flag == "--scenario":
            opts["scenario"] = value
        elif flag == "--seeds":
            opts["seeds"] = _parse_seeds(value)
        elif flag == "--timestep":
            opts["timesteps"] = _parse_numbers(flag, value)  # their range: the library's (check_scenario)
        elif flag in ("--friction", "--mass", "--damping", "--gravity"):
            kind = flag[2:]
            name, has_name, values = value.rpartition("=")
            if kind == "mass" and not has_name:
                raise _BatchUsage(f"--mass: '{value}' needs a body: --mass BODY=KG,KG,...")
            if kind == "gravity" and has_name:
                raise _BatchUsage(
                    f"--gravity: '{value}': gravity is the whole scene's, give values only: --gravity G,G,..."
                )
            if has_name and not name:
                raise _BatchUsage(f"{flag}: '{value}' has an empty name before '='")
            if any((k, n) == (kind, name) for k, n, _ in opts["params"]):
                raise _BatchUsage(
                    f"{flag}: '{value}': {kind} {('of ' + repr(name)) if name else 'of everything'} is given twice"
                )
            opts["params"].append((kind, name, _parse_numbers(flag, values)))
        elif flag in ("--steps", "--threads", "--chunk-size"):
            # The most each takes: as the API's steps, threads and chunk_size.
            most = {"--steps": MAX_STEPS, "--threads": MAX_THREADS, "--chunk-size": MAX_CHUNK_RUNS}[flag]
            if not _is_whole(value) or not 1 <= int(value) <= most:
                raise _BatchUsage(f"{flag}: '{value}' is not a whole number from 1 to {most}")
            opts[flag[2:].replace("-", "_")] = int(value)
        elif flag == "--rng":
            opts["rng"] = value  # the library's to check (ScenarioConfig)
        elif flag == "--scheduler":
            opts["scheduler"] = value
        elif flag == "--out":
            if not value:
                raise _BatchUsage("--out: '' names no file")
            opts["out"] = value
    return opts


def batch_command(args: List[str]) -> int:
    """`python -m simloop batch ...`: see BATCH_USAGE."""
    started = time.perf_counter()
    try:
        opts = _parse_batch_args(args)
    except _BatchUsage as e:
        return _fail(EXIT_USAGE, f"batch: {e}")
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
