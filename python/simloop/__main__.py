"""`python -m simloop` and `sim-loop`: the chapter's command, in Python.

Same flags and defaults as `sim_loop` (the command line is parsed by the same
C++ code), the same metrics.json and trajectory.csv bytes, the same summary;
and, as in the chapter, a rerun recording sim_loop.rrd by default
(--no-rerun to skip).
"""

from __future__ import annotations

import os
import signal
import sys
import threading
import time
from pathlib import Path
from types import FrameType
from typing import TYPE_CHECKING, Any, Dict, List, NoReturn, Optional, TextIO, Union

from .progress import progress_bar

if TYPE_CHECKING:
    from . import _core
    from .distributed import ParquetBatch

PROGRAM = "sim-loop"
EXIT_RUN_FAILED = 1
EXIT_USAGE = 2
# Ctrl-C, SIGTERM and the other terminating signals stop the work: 128 + the
# signal's number, as for sim_loop.
EXIT_SIGINT = 128 + signal.SIGINT
EXIT_SIGTERM = 128 + signal.SIGTERM

# True once this run's outputs are in place (an interrupt after that keeps them).
_outputs_written = False


class _Terminated(KeyboardInterrupt):
    """A terminating signal other than Ctrl-C (SIGTERM, SIGHUP, SIGQUIT, ...:
    _core.TERMINATING_SIGNALS), raised like Ctrl-C's KeyboardInterrupt so
    that each stops the work the same way (the C++ calls check for signals
    between chunks, and every temporary file goes with the stack)."""

    def __init__(self, signum: int = signal.SIGTERM) -> None:
        super().__init__(signum)
        self.signum = signum


def _on_signal(signum: int, frame: Optional[FrameType]) -> NoReturn:
    raise _Terminated(signum)


def _stopped_by(e: KeyboardInterrupt) -> "tuple[str, int]":
    """The signal's name and the exit code for a stop."""
    signum = e.signum if isinstance(e, _Terminated) else int(signal.SIGINT)
    return signal.Signals(signum).name, 128 + signum


def _catch_terminating_signals() -> Dict[int, Any]:
    """Installs _on_signal for every terminating signal whose action is still
    the default (one the command was started ignoring stays ignored, as
    nohup wants; SIGINT keeps Python's KeyboardInterrupt; Python ignores
    SIGPIPE itself). Returns what to restore."""
    from . import _core

    previous = {}
    for signum in _core.TERMINATING_SIGNALS:
        if signal.getsignal(signum) == signal.SIG_DFL:
            previous[signum] = signal.signal(signum, _on_signal)
    return previous


class _ReportLost(Exception):
    """Writing to stdout failed (a full disk, /dev/full): not an OSError, so
    that the handlers for the outputs' errors do not take it for theirs."""


class _Report:
    """sys.stdout while the command runs: the same stream, but a failed write
    raises _ReportLost."""

    def __init__(self, stream: TextIO) -> None:
        self._stream = stream

    def write(self, text: str) -> int:
        try:
            return self._stream.write(text)
        except OSError as e:
            raise _ReportLost(e.strerror or str(e)) from None

    def flush(self) -> None:
        try:
            self._stream.flush()
        except OSError as e:
            raise _ReportLost(e.strerror or str(e)) from None

    def __getattr__(self, name: str) -> Any:
        return getattr(self._stream, name)


def _fail(code: int, message: str) -> int:
    line = "; ".join(part.strip() for part in str(message).splitlines() if part.strip())
    if sys.stderr is not None:  # (print(file=None) would write to stdout)
        print(f"{PROGRAM}: {line}", file=sys.stderr)
    return code


def _finish_stdout(code: int) -> int:
    """A report that did not reach stdout (a full disk, /dev/full) fails the
    run: exit 1 with one line, unless it failed already."""
    try:
        sys.stdout.flush()
    except OSError as e:
        # What is still buffered would fail again at exit, with a traceback.
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
        if code == 0:
            return _fail(EXIT_RUN_FAILED, f"cannot write the report to standard output ({e.strerror or e})")
    return code


def _peak_memory_mib() -> float:
    """VmHWM of this process, MiB (-1 if unknown)."""
    try:
        with open("/proc/self/status") as status:
            for line in status:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    return -1.0


PLOT_USAGE = ("usage: python -m simloop plot trajectory|sweep [--out DIR] [--compare DIR ...] [--x auto|time|step]\n"
              "  draws DIR/trajectory.png or DIR/sweep.png from the CSV the command wrote there;\n"
              "  --compare DIR (trajectory only, repeatable): draw DIR's run on the same axes;\n"
              "  --x: sim time, or the step index (auto: time, unless the runs' timesteps differ)")


def _plot_command(args: List[str]) -> int:
    """`python -m simloop plot trajectory|sweep [--out DIR] [--compare DIR ...]
    [--x auto|time|step]`: draws the PNG from the CSV in DIR. sim_loop --plot calls this."""
    if args and args[0] in ("-h", "--help"):
        print(PLOT_USAGE)
        return 0
    if not args or args[0] not in ("trajectory", "sweep"):
        return _fail(EXIT_USAGE, "plot needs 'trajectory' or 'sweep' first (see plot --help)")
    what, rest = args[0], args[1:]
    out, compare, x_axis = Path("outputs/ch0.1-sim-loop"), [], "auto"
    i = 0
    while i < len(rest):
        flag, inline = rest[i].partition("=")[::2] if rest[i].startswith("--") else (rest[i], "")
        if flag not in ("--out", "--compare", "--x"):
            return _fail(EXIT_USAGE, f"plot: unknown argument '{rest[i]}' (see plot --help)")
        if not inline:
            if i + 1 >= len(rest):
                return _fail(EXIT_USAGE, f"plot: {flag} needs a value")
            i += 1
            inline = rest[i]
        if flag == "--out":
            out = Path(inline)
        elif flag == "--compare":
            compare.append(Path(inline))
        elif inline not in ("auto", "time", "step"):
            return _fail(EXIT_USAGE, f"plot: --x must be auto, time or step, got '{inline}'")
        else:
            x_axis = inline
        i += 1
    if compare and what != "trajectory":
        return _fail(EXIT_USAGE, "plot: --compare draws trajectories only")
    from .plots import sweep_png, trajectory_png

    csv = out / f"{what}.csv"
    for flag, path in [("--out", csv)] + [("--compare", c / "trajectory.csv") for c in compare]:
        if not path.is_file():
            return _fail(EXIT_USAGE, f"{flag}: {path}: no such file (run the command first)")
    # A comparison gets its own file, beside the run's own picture.
    png = out / (f"{what}_vs_{'_'.join(c.name or 'run' for c in compare)}.png" if compare else f"{what}.png")
    try:
        if what == "sweep":
            sweep_png(csv, png)
        else:
            trajectory_png(csv, png, compare=[c / "trajectory.csv" for c in compare], x=x_axis)
    except (OSError, ValueError, KeyError, ImportError) as e:
        return _fail(EXIT_RUN_FAILED, f"plot: {csv}: {e}")
    if compare:  # sim_loop --plot prints its own line; a comparison is asked for by hand
        print(f"plot: {png}")
    return 0


def _viewer() -> str:
    """How to start rerun's viewer from here: `rerun` when that is this Python's
    own, else the path of the one beside this Python (a venv's bin, off PATH)."""
    import os
    import shutil

    beside = Path(sys.executable).with_name("rerun")
    on_path = shutil.which("rerun")
    if not beside.exists() or (on_path and os.path.samefile(on_path, beside)):
        return "rerun"
    relative = os.path.relpath(beside)
    if relative.startswith(".."):
        return str(beside)
    return relative if os.sep in relative else os.path.join(".", relative)


def _sweep(opts: "_core.CommandLine", model: "_core.Model", out: Path,
           scenario: "Optional[_core.Scenario]" = None) -> None:
    from . import _core

    global _outputs_written
    result: Union[_core.ScenarioSweepResult, _core.SweepResult]
    with progress_bar("sweeping") as progress:
        if scenario is not None:  # sweep --scenario, --body, --ctrl
            result = _core.sweep_scenario(model, scenario, opts.sweep_timesteps, opts.sweep_duration,
                                          _core.scenario_config_from_flags(opts), opts.threads, progress)
        else:
            result = _core.sweep(model, opts.sweep_timesteps, opts.sweep_duration, opts.threads, progress)
    csv = result.write(out)
    _outputs_written = True
    print(result.summary(), end="")
    print(f"sweep: {csv}")
    if opts.plot:  # as for sim_loop sweep: the chart only when asked for
        from .plots import sweep_png

        print(f"plot: {sweep_png(csv, out / 'sweep.png')}")


def main(argv: Optional[List[str]] = None) -> int:
    """The command: SIGTERM, SIGHUP, SIGQUIT (every terminating signal) stop
    it as Ctrl-C does; each ends it with one line and exit 128 + the signal's
    number (130 for SIGINT, 143 for SIGTERM), the earlier outputs kept (the
    library writes the outputs together, or none, and no temporary file)."""
    global _outputs_written
    _outputs_written = False
    if sys.stdout is None:  # started with stdout closed
        return _fail(EXIT_RUN_FAILED, "standard output is closed; nothing was run (the report would be lost)")
    previous: Dict[int, Any] = {}
    stdout = sys.stdout
    try:
        if threading.current_thread() is threading.main_thread():
            previous = _catch_terminating_signals()
        sys.stdout = _Report(stdout)
        code = _main(argv)
        sys.stdout.flush()
    except KeyboardInterrupt as e:
        name, code = _stopped_by(e)
        kept = "after the outputs were written" if _outputs_written else "the earlier outputs were left as they were"
        code = _fail(code, f"interrupted ({name}); {kept}")
    except _ReportLost as e:
        done = "the outputs were written" if _outputs_written else "nothing was written"
        code = _fail(EXIT_RUN_FAILED, f"cannot write the report to standard output ({e}); {done}")
    finally:
        sys.stdout = stdout
        for signum, handler in previous.items():
            # The command itself (not a call from Python): a signal while the
            # interpreter shuts down ends it at once, as sim_loop does, saying
            # so; else the caller's handlers come back.
            signal.signal(signum, _exit_at_once if argv is None else handler)
    code = _finish_stdout(code)
    if argv is None:
        # The command ends its process itself: the interpreter's shutdown
        # (rerun's threads, the modules) takes a while, and once it has begun
        # Python puts every signal back to its default action, so a signal
        # then would kill the process unannounced. The report and the
        # outputs are complete; nothing is left to clean up.
        try:
            sys.stderr.flush()
        finally:
            os._exit(code)
    return code


def _exit_at_once(signum: int, frame: Optional[FrameType]) -> None:
    """A terminating signal after the work: one line, exit 128 + the signal."""
    kept = "after the outputs were written" if _outputs_written else "the earlier outputs were left as they were"
    try:
        os.write(2, f"{PROGRAM}: interrupted ({signal.Signals(signum).name}); {kept}\n".encode())
    finally:
        os._exit(128 + signum)


def _run_key(args: List[str], opts: "_core.CommandLine") -> str:
    """What decides a scenario run, for its recording id: the command line
    (but --out and the recording flags) and the scenario's and scene's bytes."""
    kept, skip = [], False
    for arg in args:
        if skip:
            skip = False
        elif arg == "--out":
            skip = True
        elif not arg.startswith(("--out=", "--rerun", "--no-rerun")):
            kept.append(arg)
    key = "\0".join(kept)
    for path in (opts.scenario_path, opts.model_path):
        if path:
            with open(path, "rb") as f:
                key += "\0" + f.read().hex()
    return key


def _scenario(opts: "_core.CommandLine", scenario: "_core.Scenario", model: "_core.Model", out: Path,
              started: float, args: List[str]) -> int:
    """A scenario's run (--scenario, --body, --ctrl): trajectory.csv written as
    the loop steps (as sim_loop writes it: the same bytes, in bounded memory),
    metrics.json, the summary, and the recording made from the same run."""
    global _outputs_written
    from . import _core

    config = _core.scenario_config_from_flags(opts)
    try:
        rrd = out / "sim_loop.rrd"
        recording = None
        if opts.rerun:  # rerun imported, and the recording's file begun, before anything is written
            from .scenario_recording import ScenarioRecording

            recording = ScenarioRecording(model, rrd, _run_key(args, opts))
        try:
            with progress_bar("running") as progress:
                result, metrics_path, trajectory_path = _core.run_scenario_to_files(
                    model, scenario, config, out, drawing=recording,
                    also=recording.files if recording is not None else [], progress=progress)
        finally:
            if recording is not None:
                recording.close()
        _outputs_written = True
        print(result.summary(), end="")
        print(f"metrics: {metrics_path}")
        print(f"trajectory: {trajectory_path} ({result.rows} rows, {len(result.column_names)} columns)")
        if opts.rerun:
            print(f"recording: {rrd} -- open it with: {_viewer()} {rrd}")
    except _core.MujocoError as e:
        return _fail(EXIT_RUN_FAILED, f"MuJoCo error while {_core.doing(opts, model, scenario)}: {e}")
    except MemoryError:
        return _fail(EXIT_RUN_FAILED, f"out of memory while {_core.doing(opts, model, scenario)}")
    except (OSError, ValueError) as e:
        return _fail(EXIT_RUN_FAILED, str(e))
    except ImportError as e:  # rerun for the recording, imported before anything is written
        return _fail(EXIT_RUN_FAILED, f"{e} (nothing was written; --no-rerun runs without the recording)")
    print(f"wall-clock: {(time.perf_counter() - started) * 1e3:.1f} ms, peak memory: {_peak_memory_mib():.1f} MiB")
    return 0


def _main(argv: Optional[List[str]]) -> int:
    global _outputs_written
    started = time.perf_counter()
    args = sys.argv[1:] if argv is None else list(argv)
    # A path from the command line may hold bytes that are not UTF-8 (sys.argv
    # carries them as surrogates): print it back as those bytes, as sim_loop does.
    if hasattr(sys.stdout, "reconfigure"):
        sys.stdout.reconfigure(errors="surrogateescape")
    if args and args[0] == "plot":
        return _plot_command(args[1:])
    if args and args[0] == "batch":
        return _batch_command(args[1:])
    from . import _core, load_model

    try:
        opts = _core.parse_command_line(args)
    except ValueError as e:
        return _fail(EXIT_USAGE, str(e))
    if opts.help and opts.command == "sweep":
        print(_core.sweep_help_text("python -m simloop"), end="")
        return 0
    if opts.help:
        print(_core.help_text(f"python -m simloop (or {PROGRAM})",
                              "record sim_loop.rrd in --out (the default), or not"), end="")
        return 0
    if opts.version:
        print(f"simloop {_core.__version__} ({_core.MUJOCO_VERSION})")
        return 0

    print(f"ch0.1-sim-loop | tier: cpu | {_core.MUJOCO_VERSION} | simloop {_core.__version__}", flush=True)
    scenario = None
    if opts.scenario_path:
        try:
            scenario = _core.Scenario.from_file(opts.scenario_path)
        except (OSError, ValueError) as e:
            return _fail(EXIT_USAGE, f"--scenario: {e}")
    try:
        model = _core.load_scene(scenario) if scenario is not None else load_model(opts.model_path or None)
    except (OSError, ValueError, _core.MujocoError) as e:
        theirs = bool(scenario.scene) if scenario is not None else bool(opts.model_path)
        flag = "--scenario" if scenario is not None else "--model"
        return _fail(EXIT_USAGE if theirs else EXIT_RUN_FAILED, f"{flag}: {e}")
    # What MuJoCo said while it loaded the scene, as sim_loop reports it.
    print(_core.load_warnings_text(model), end="")
    try:
        if opts.is_scenario and scenario is None:
            scenario = _core.scenario_from_flags(opts, model)
        _core.check_run_inputs(opts, model, scenario)
    except (OSError, ValueError) as e:
        return _fail(EXIT_USAGE, str(e))
    out = Path(opts.out)
    made = not out.exists()  # a folder this run makes goes again if the run leaves nothing in it
    try:
        _core.prepare_output_dir(out)
        # One run at a time in a folder (the lock sim_loop takes too): held
        # until the end, released after the folder's removal below.
        lock = _core.OutputLock(out)
    except OSError as e:
        return _fail(EXIT_USAGE, f"--out: {e}")
    with lock:
        try:
            return _run_into(opts, model, scenario, out, started, args)
        finally:
            if made:
                try:
                    out.rmdir()  # only when empty
                except OSError:
                    pass


def _run_into(opts: "_core.CommandLine", model: "_core.Model", scenario: "Optional[_core.Scenario]", out: Path,
              started: float, args: List[str]) -> int:
    """The run, scenario or sweep into the prepared folder `out`."""
    global _outputs_written
    from . import _core
    if opts.command == "sweep":
        try:
            _sweep(opts, model, out, scenario)
        except _core.MujocoError as e:
            return _fail(EXIT_RUN_FAILED, f"MuJoCo error while {_core.doing(opts)}: {e}")
        except MemoryError:
            return _fail(EXIT_RUN_FAILED, f"out of memory while {_core.doing(opts)}")
        except (OSError, ValueError) as e:
            return _fail(EXIT_RUN_FAILED, str(e))
        except ImportError as e:  # matplotlib, for sweep.png
            return _fail(EXIT_RUN_FAILED, f"plot: {e} (sweep.csv was written)")
        print(f"wall-clock: {(time.perf_counter() - started) * 1e3:.1f} ms, peak memory: {_peak_memory_mib():.1f} MiB")
        return 0

    if scenario is not None:
        return _scenario(opts, scenario, model, out, started, args)
    rrd = out / "sim_loop.rrd"
    try:
        recording = None
        try:
            if opts.rerun:  # rerun imported, and the recording's file begun, before anything is written
                from .recording import ChapterRecording

                recording = ChapterRecording(opts.run, opts.model_path or None, model, rrd)
        except ImportError as e:
            return _fail(EXIT_RUN_FAILED, f"{e} (nothing was written; --no-rerun runs without the recording)")
        # trajectory.csv written as the loop steps (in bounded memory, as
        # sim_loop does), the recording beside it, all put in place together.
        try:
            with progress_bar("running") as progress:
                result, metrics_path, trajectory_path = _core.run_to_files(
                    model, opts.run, out, drawing=recording,
                    also=recording.files if recording is not None else [], progress=progress)
        finally:
            if recording is not None:
                recording.close()
        _outputs_written = True
        print(result.summary(), end="")
        print(f"metrics: {metrics_path}")
        print(f"trajectory: {trajectory_path} ({result.rows} rows)")
        if opts.rerun:
            print(f"recording: {rrd} -- open it with: {_viewer()} {rrd}")
        if opts.plot:
            from .plots import trajectory_png

            print(f"plot: {trajectory_png(trajectory_path, out / 'trajectory.png')}")
    except _core.MujocoError as e:
        return _fail(EXIT_RUN_FAILED, f"MuJoCo error while {_core.doing(opts)}: {e}")
    except MemoryError:
        return _fail(EXIT_RUN_FAILED, f"out of memory while {_core.doing(opts)}")
    except (OSError, ValueError) as e:
        return _fail(EXIT_RUN_FAILED, str(e))
    except ImportError as e:  # matplotlib for --plot
        return _fail(EXIT_RUN_FAILED, f"{e} (metrics.json and trajectory.csv were written)")
    elapsed = time.perf_counter() - started
    print(f"wall-clock: {elapsed * 1e3:.1f} ms, peak memory: {_peak_memory_mib():.1f} MiB")
    return 0


# ---- python -m simloop batch ---------------------------------------------

BATCH_USAGE = """usage: python -m simloop batch [--scenario FILE] [--seeds SEEDS] [--timestep S,S,...]
                              [--friction [GEOM=]V,V,...] [--mass BODY=V,V,...] [--damping [JOINT=]V,V,...]
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
  --steps N            instead of the scenario's length
  --rng NAME           the generator that draws the scenario's random disturbances
  --no-perturb         no disturbances
  --scheduler ADDRESS  a Dask scheduler (tcp://HOST:8786); without it, this machine's threads
  --threads N          C++ threads per chunk (default: every core locally, 1 on a cluster's workers)
  --chunk-size N       runs per chunk (default: about four chunks per worker, at most 64)
  --out FILE           the Parquet file (default outputs/batch.parquet)
  --resume             finish an interrupted batch from FILE.parts/ (what it wrote is not recomputed)

Rows come in the order of itertools.product(friction..., mass..., damping...,
timesteps, seeds): the seed varies fastest. Ctrl-C stops the batch; the
chunks already done stay in FILE.parts/ for --resume, and FILE is written only
once it is complete."""


class _BatchUsage(ValueError):
    pass


def _parse_seeds(text: str) -> List[int]:
    seeds: List[int] = []
    for part in text.split(","):
        fields = part.split(":")
        if not all(f.isdigit() for f in fields) or len(fields) > 3 or not part:
            raise _BatchUsage(f"--seeds: '{text}' is not seeds (N, A:B for A to B-1, A:B:STEP, joined by commas)")
        numbers = [int(f) for f in fields]
        if len(numbers) == 1:
            seeds.append(numbers[0])
        else:
            step = numbers[2] if len(numbers) == 3 else 1
            if step == 0 or numbers[1] <= numbers[0]:
                raise _BatchUsage(f"--seeds: '{part}' is an empty range (A:B runs A to B-1)")
            seeds.extend(range(numbers[0], numbers[1], step))
    if any(seed > 2**64 - 1 for seed in seeds):
        raise _BatchUsage(f"--seeds: '{text}': seeds go from 0 to 2^64-1")
    return seeds


def _parse_numbers(flag: str, text: str) -> List[float]:
    import math

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
        "scenario": None, "seeds": [0], "timesteps": [None], "params": [], "steps": None, "rng": "mt19937_64",
        "perturb": True, "scheduler": None, "threads": None, "chunk_size": None,
        "out": "outputs/batch.parquet", "resume": False, "help": False}
    with_value = {"--scenario", "--seeds", "--timestep", "--friction", "--mass", "--damping", "--steps", "--rng",
                  "--scheduler", "--threads", "--chunk-size", "--out"}
    i = 0
    while i < len(args):
        flag, eq, value = args[i].partition("=") if args[i].startswith("--") else (args[i], "", "")
        if flag in ("--resume", "--no-perturb", "--help", "-h"):
            if eq:
                raise _BatchUsage(f"{flag} takes no value, got '{args[i]}'")
            opts["resume" if flag == "--resume" else "perturb" if flag == "--no-perturb" else "help"] = \
                flag != "--no-perturb"
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
            opts["timesteps"] = _parse_numbers(flag, value)
            bad = [t for t in opts["timesteps"] if not t > 0]
            if bad:
                raise _BatchUsage(f"--timestep: {bad[0]!r} is not a positive number of seconds")
        elif flag in ("--friction", "--mass", "--damping"):
            kind = flag[2:]
            name, has_name, values = value.rpartition("=")
            if kind == "mass" and not has_name:
                raise _BatchUsage(f"--mass: '{value}' needs a body: --mass BODY=KG,KG,...")
            if has_name and not name:
                raise _BatchUsage(f"{flag}: '{value}' has an empty name before '='")
            column = f"{kind}_{name}" if name else kind
            if any(c == column for c, _, _, _ in opts["params"]):
                raise _BatchUsage(f"{flag}: '{value}': {kind} {('of ' + repr(name)) if name else 'of everything'} "
                                  "is given twice")
            opts["params"].append((column, kind, name, _parse_numbers(flag, values)))
        elif flag in ("--steps", "--threads", "--chunk-size"):
            if not value.isdigit() or int(value) < 1 or int(value) > 2**62 - 1:
                raise _BatchUsage(f"{flag}: '{value}' is not a whole number from 1")
            opts[flag[2:].replace("-", "_")] = int(value)
        elif flag == "--rng":
            if value not in ("mt19937_64", "numpy"):
                raise _BatchUsage(f"--rng: '{value}' is not mt19937_64 or numpy")
            opts["rng"] = value
        elif flag == "--scheduler":
            opts["scheduler"] = value
        elif flag == "--out":
            if not value:
                raise _BatchUsage("--out: '' names no file")
            opts["out"] = value
    return opts


def _batch_command(args: List[str]) -> int:
    """`python -m simloop batch ...`: see BATCH_USAGE."""
    import itertools

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
    from . import _core, distributed
    from .scenario import Scenario

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
    for column, kind, name, values in opts["params"]:
        for value in values:
            try:
                _core.with_scene_params(scene, [(kind, name, value)])
            except ValueError as e:
                return _fail(EXIT_USAGE, f"batch: --{kind}: {e}")
        axes.append([(kind, name, value) for value in values])
    try:
        for t in opts["timesteps"]:
            _core.check_scenario(scene, scenario._core, _core.ScenarioConfig(0, opts["rng"], t, opts["steps"],
                                                                             opts["perturb"], _core.MAX_RECORD_EVERY))
    except ValueError as e:
        return _fail(EXIT_USAGE, f"batch: {e}")
    runs = [(i, seed, t, tuple(params))
            for i, (*params, t, seed) in enumerate(itertools.product(*axes, opts["timesteps"], opts["seeds"]))]

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
        job = distributed.scenario_job(scenario, rng=opts["rng"], steps=opts["steps"], perturb=opts["perturb"],
                                       threads=threads)
        workers = distributed._Pool(client).workers()
        size = opts["chunk_size"] or distributed.default_chunk_size(len(runs), 4 if client is None else workers)
        description = {"scenario": opts["scenario"] or "(the chapter's)", "seeds": len(opts["seeds"]),
                       "timesteps": opts["timesteps"], "params": [c for c, _, _, _ in opts["params"]]}
        batch = distributed.ParquetBatch(opts["out"], job, runs, size, description)
        try:
            earlier = batch.prepare(opts["resume"])
        except distributed.ResumeError as e:
            return _fail(EXIT_USAGE, f"batch: {e}")
        if os.path.isdir(opts["out"]):
            return _fail(EXIT_USAGE, f"batch: --out: {opts['out']} is a directory (name the Parquet file)")
        out_dir = os.path.dirname(os.path.abspath(opts["out"]))
        try:
            os.makedirs(out_dir, exist_ok=True)
        except OSError as e:
            return _fail(EXIT_USAGE, f"batch: --out: {e}")
        return _run_batch(batch, client, earlier, started)
    finally:
        if client is not None:
            client.close()


def _run_batch(batch: "ParquetBatch", client: Any, earlier: int, started: float) -> int:
    from .distributed import VersionMismatch

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
        return _fail(code, f"interrupted ({name}); {batch.out} not written; {batch.kept_runs()} of {total} runs kept "
                           f"in {batch.parts}/ (add --resume to finish)")
    except VersionMismatch as e:
        return _fail(EXIT_RUN_FAILED, f"batch: {e}")
    except Exception as e:  # a worker's failure as it came back (dask's KilledWorker, a MujocoError, ...)
        return _fail(EXIT_RUN_FAILED, f"batch: {type(e).__name__}: {e} ({batch.kept_runs()} of {total} runs kept in {batch.parts}/; "
                                      "--resume continues)")
    finally:
        if bar is not None:
            bar.close()
    print(f"batch: {total} runs ({computed} run now, {total - computed} from {batch.parts}/)"
          if earlier else f"batch: {total} runs")
    print(f"table: {batch.out}")
    print(f"wall-clock: {time.perf_counter() - started:.1f} s, peak memory: {_peak_memory_mib():.1f} MiB")
    return 0


if __name__ == "__main__":
    sys.exit(main())
