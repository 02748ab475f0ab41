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
from typing import Any, Callable, Dict, List, Optional, TextIO, Union

from . import _core
from ._checks import load_model
from ._command import (EXIT_RUN_FAILED, EXIT_SIGINT, EXIT_SIGTERM, EXIT_USAGE, PROGRAM,  # noqa: F401 (the command's)
                       _catch_terminating_signals, _fail, _peak_memory_mib, _stopped_by)
from .batch_command import batch_command
from .progress import progress_bar

# True once this run's outputs are in place (an interrupt after that keeps them).
_outputs_written = False


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


def _main(argv: Optional[List[str]]) -> int:
    started = time.perf_counter()
    args = sys.argv[1:] if argv is None else list(argv)
    # A path from the command line may hold bytes that are not UTF-8 (sys.argv
    # carries them as surrogates): print it back as those bytes, as sim_loop does.
    if hasattr(sys.stdout, "reconfigure"):
        sys.stdout.reconfigure(errors="surrogateescape")
    if args and args[0] == "plot":
        return _plot_command(args[1:])
    if args and args[0] == "batch":
        return batch_command(args[1:])
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
    if opts.command == "sweep":
        return _reporting_failures(lambda: _sweep(opts, model, out, scenario), lambda: _core.doing(opts), started,
                                   lambda e: f"plot: {e} (sweep.csv was written)")  # matplotlib, for sweep.png
    return _reporting_failures(
        lambda: _run(opts, model, scenario, out, args),
        lambda: _core.doing(opts) if scenario is None else _core.doing(opts, model, scenario), started,
        # rerun for the recording, imported before anything is written; matplotlib for --plot, after
        lambda e: f"{e} (metrics.json and trajectory.csv were written)" if _outputs_written
        else f"{e} (nothing was written; --no-rerun runs without the recording)")


def _reporting_failures(work: Callable[[], None], doing: Callable[[], str], started: float,
                        import_failed: Callable[[ImportError], str]) -> int:
    """work(), then the wall-clock line; a failure as one line (doing(): what
    the run was doing), exit 1."""
    try:
        work()
    except _core.MujocoError as e:
        return _fail(EXIT_RUN_FAILED, f"MuJoCo error while {doing()}: {e}")
    except MemoryError:
        return _fail(EXIT_RUN_FAILED, f"out of memory while {doing()}")
    except (OSError, ValueError) as e:
        return _fail(EXIT_RUN_FAILED, str(e))
    except ImportError as e:
        return _fail(EXIT_RUN_FAILED, import_failed(e))
    print(f"wall-clock: {(time.perf_counter() - started) * 1e3:.1f} ms, peak memory: {_peak_memory_mib():.1f} MiB")
    return 0


def _run(opts: "_core.CommandLine", model: "_core.Model", scenario: "Optional[_core.Scenario]", out: Path,
         args: List[str]) -> None:
    """The chapter's run, or a scenario's (--scenario, --body, --ctrl):
    trajectory.csv written as the loop steps (as sim_loop writes it: the same
    bytes, in bounded memory), metrics.json, the summary, and the recording
    made from the same run, all put in place together."""
    global _outputs_written
    rrd = out / "sim_loop.rrd"
    recording: Any = None  # a recording.Recording: the chapter's (ChapterRecording) or a scenario's
    result: Union[_core.RunResult, _core.ScenarioResult]
    if opts.rerun:  # rerun imported, and the recording's file begun, before anything is written
        from .chapter_recording import ChapterRecording
        from .recording import Recording, scenario_recording_id

        if scenario is None:
            recording = ChapterRecording(opts.run, opts.model_path or None, model, rrd)
        else:
            recording = Recording(model, rrd, scenario_recording_id(_run_key(args, opts)))
    also = recording.files if recording is not None else []
    try:
        with progress_bar("running") as progress:
            if scenario is None:
                result, metrics_path, trajectory_path = _core.run_to_files(
                    model, opts.run, out, drawing=recording, also=also, progress=progress)
                columns = ""
            else:
                result, metrics_path, trajectory_path = _core.run_scenario_to_files(
                    model, scenario, _core.scenario_config_from_flags(opts), out, drawing=recording, also=also,
                    progress=progress)
                columns = f", {len(result.column_names)} columns"
    finally:
        if recording is not None:
            recording.close()
    _outputs_written = True
    print(result.summary(), end="")
    print(f"metrics: {metrics_path}")
    print(f"trajectory: {trajectory_path} ({result.rows} rows{columns})")
    if opts.rerun:
        print(f"recording: {rrd} -- open it with: {_viewer()} {rrd}")
    if opts.plot and scenario is None:
        from .plots import trajectory_png

        print(f"plot: {trajectory_png(trajectory_path, out / 'trajectory.png')}")


if __name__ == "__main__":
    sys.exit(main())
