"""`python -m simloop` and `sim-loop`: the chapter's command, in Python.

The command is sim_loop's own orchestration (command/command.cc, through
_core.Orchestration), taken step by step: the same flags, checks, outputs,
report and failures. This process adds its part: its report through
sys.stdout, its progress bar, and, as in the chapter, a rerun recording
sim_loop.rrd by default (--no-rerun to skip), drawn from the rows the run
kept, and --plot drawn here. `plot` and `batch` are its own
commands, their flags parsed by the same parser (command/cli_options.cc,
command/cli_batch.cc).
"""

from __future__ import annotations

import os
import signal
import sys
import threading
from pathlib import Path
from types import FrameType
from typing import Any, Dict, List, Optional, Tuple

from . import _core, _startup
from ._command import (  # noqa: F401 (the command's)
    EXIT_RUN_FAILED,
    EXIT_SIGINT,
    EXIT_SIGTERM,
    EXIT_USAGE,
    PROGRAM,
    _catch_terminating_signals,
    _fail,
    _Report,
    _ReportLost,
    _stopped_by,
    _unraisable,
    raise_swallowed_signal,
)
from .batch_command import batch_command
from .progress import progress_bar

# True once this run's outputs are in place (an interrupt after that keeps them).
_outputs_written = False


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


PLOT_USAGE = (
    "usage: python -m simloop plot trajectory|sweep [--out DIR] [--compare DIR ...] [--x auto|time|step]\n"
    "  draws DIR/trajectory.png or DIR/sweep.png from the CSV the command wrote there;\n"
    "  --compare DIR (trajectory only, repeatable): draw DIR's run on the same axes;\n"
    "  --x: sim time, or the step index (auto: time, unless the runs span different sim times)"
)


def _plot_command(args: List[str]) -> int:
    """`python -m simloop plot trajectory|sweep [--out DIR] [--compare DIR ...]
    [--x auto|time|step]`: draws the PNG from the CSV in DIR, its flags parsed
    by the commands' one parser (command/cli_options.cc). sim_loop --plot calls this."""
    try:
        opts = _core.parse_command_line(["plot", *args])
    except ValueError as e:
        return _fail(EXIT_USAGE, str(e))
    if opts.help:
        print(PLOT_USAGE)
        return 0
    what, out, x_axis = opts.plot_what, Path(opts.out), opts.plot_x
    compare = [Path(c) for c in opts.plot_compare]
    from .plots import trajectory_png
    from .sweep_plots import sweep_png

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


def main(argv: Optional[List[str]] = None) -> int:
    """The command: SIGTERM, SIGHUP, SIGQUIT (every terminating signal) stop
    it as Ctrl-C does; each ends it with one line and exit 128 + the signal's
    number (130 for SIGINT, 143 for SIGTERM), the earlier outputs kept (the
    library writes the outputs together, or none, and no temporary file)."""
    global _outputs_written
    _outputs_written = False
    _startup.started()
    if sys.stdout is None:  # started with stdout closed
        return _fail(EXIT_RUN_FAILED, "standard output is closed; nothing was run (the report would be lost)")
    previous: Dict[int, Any] = {}
    stdout, unraisablehook = sys.stdout, sys.unraisablehook
    try:
        if threading.current_thread() is threading.main_thread():
            previous = _catch_terminating_signals()
            sys.unraisablehook = _unraisable(unraisablehook)
        sys.stdout = _Report(stdout)
        code = _main(argv)
        if code == 0:  # (a failure has said its one line: a report lost as well adds none, _finish_stdout)
            raise_swallowed_signal()
            sys.stdout.flush()
    except KeyboardInterrupt as e:
        name, code = _stopped_by(e)
        kept = "after the outputs were written" if _outputs_written else "the earlier outputs were left as they were"
        code = _fail(code, f"interrupted ({name}); {kept}", signal_first=False)
    except _ReportLost as e:
        done = "the outputs were written" if _outputs_written else "nothing was written"
        code = _fail(EXIT_RUN_FAILED, f"cannot write the report to standard output ({e}); {done}", signal_first=False)
    finally:
        sys.stdout, sys.unraisablehook = stdout, unraisablehook
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
    args = sys.argv[1:] if argv is None else list(argv)
    # A path from the command line may hold bytes that are not UTF-8 (sys.argv
    # carries them as surrogates): print it back as those bytes, as sim_loop does.
    if hasattr(sys.stdout, "reconfigure"):
        sys.stdout.reconfigure(errors="surrogateescape")
    if args and args[0] == "plot":
        return _plot_command(args[1:])
    if args and args[0] == "batch":
        return batch_command(args[1:])
    return _run(args)


class _HostFailure(Exception):
    """A failure of this process's part (the recording, the plot), as the
    command's one line."""

    def __init__(self, code: int, line: str) -> None:
        super().__init__(line)
        self.code = code


def _run(args: List[str]) -> int:
    """sim_loop's orchestration (_core.Orchestration), step by step, with this
    process's part: its report on sys.stdout, its progress bar, its recording
    and --plot. Whatever is not put in place goes when it ends."""
    global _outputs_written
    try:
        command = _core.Orchestration(args)
    except _core.CommandFailure as e:
        return _fail(*e.args)
    opts = command.options
    if opts.help:
        sys.stdout.write(_help(command.sweep))
        return 0
    if opts.version:
        sys.stdout.write(f"simloop {_core.__version__} ({_core.MUJOCO_VERSION})\n")
        return 0
    try:
        return _orchestrate(command, args)
    except _core.CommandFailure as e:
        return _fail(*e.args)
    except _HostFailure as e:
        return _fail(e.code, str(e))
    except (OSError, ValueError) as e:  # the recording's file, say
        return _fail(EXIT_RUN_FAILED, str(e))
    except MemoryError:
        return _fail(EXIT_RUN_FAILED, f"out of memory while {command.doing}")
    finally:
        _outputs_written = command.committed
        command.close()


def _help(sweep: bool) -> str:
    if sweep:
        return _core.sweep_help_text("python -m simloop")
    return _core.help_text(f"python -m simloop (or {PROGRAM})", "record sim_loop.rrd in --out (the default), or not")


def _orchestrate(command: Any, args: List[str]) -> int:
    global _outputs_written
    opts = command.options
    sys.stdout.write(command.banner())
    sys.stdout.flush()
    sys.stdout.write(command.load())
    command.check()
    command.open_output()
    drawings, lines = (None, "") if command.sweep else _drawings(command, args)
    try:
        with progress_bar("sweeping" if command.sweep else "running") as progress:
            command.run(progress, drawn=drawings is not None)
        command.commit(_draw(command, drawings) if drawings else [])
    finally:
        if drawings:
            drawings.close()
    _outputs_written = True
    sys.stdout.write(command.report(lines))
    if opts.plot:
        sys.stdout.write(command.plot_line(_plot(opts.out, "sweep" if command.sweep else "trajectory")))
    sys.stdout.write(command.closing_line())
    return 0


class _Drawings:
    """The drawings of one run (the recording, the video, or both), fed alike."""

    def __init__(self, drawings: List[Any]) -> None:
        self.drawings = drawings

    def columns(self, names: Any) -> None:
        for d in self.drawings:
            d.columns(names)

    def rows(self, block: Any) -> None:
        for d in self.drawings:
            d.rows(block)

    def finish(self, result: Any) -> None:
        for d in self.drawings:
            d.finish(result)

    @property
    def files(self) -> List[Any]:
        return [f for d in self.drawings for f in d.files]

    def close(self) -> None:
        for d in self.drawings:
            d.close()


def _drawings(command: Any, args: List[str]) -> "Tuple[Optional[_Drawings], str]":
    """What draws the run (the rerun recording, --video's pictures, or both:
    each begun before anything is written) and the report's lines for them."""
    opts = command.options
    if not (opts.rerun or opts.video):
        return None, ""
    model, scenario = command.model, command.scenario
    drawings: List[Any] = []
    lines: List[str] = []
    try:
        if opts.rerun:
            rrd = Path(opts.out) / "sim_loop.rrd"
            try:
                from .recording import Recording
                from .recording_views import chapter_view, scenario_recording_id, scenario_view

                if scenario is None:
                    view = chapter_view(opts.run, opts.model_path or None, model)
                else:
                    view = scenario_view(scenario_recording_id(_run_key(args, opts)))
                drawings.append(Recording(model, rrd, view))
            except ImportError as e:
                raise _HostFailure(
                    EXIT_RUN_FAILED, f"{e} (nothing was written; --no-rerun runs without the recording)"
                ) from None
            lines.append(f"recording: {rrd} -- open it with: {_viewer()} {rrd}")
        if opts.video:
            from .video import VideoRecording

            try:
                video = VideoRecording(model, opts.video, chapter=scenario is None)
            except RuntimeError as e:  # no EGL, no OpenGL
                raise _HostFailure(EXIT_RUN_FAILED, f"--video: {e} (nothing was written)") from None
            drawings.append(video)
            lines.append(video.line)
    except BaseException:
        for drawing in drawings:
            drawing.close()
        raise
    return _Drawings(drawings), "\n".join(lines)


def _draw(command: Any, drawings: _Drawings) -> List[Any]:
    """The drawings fed the rows the run kept for them, block by block as the
    run wrote them, and its result: the files to put in place with its own."""
    drawings.columns(command.drawn_columns())
    while (block := command.next_drawn_block()) is not None:
        drawings.rows(block)
    drawings.finish(command.result)
    return drawings.files


def _plot(out: str, what: str) -> str:
    """--plot: out/<what>.png drawn here, from the CSV just written."""
    folder = Path(out)
    try:
        from .plots import trajectory_png
        from .sweep_plots import sweep_png

        if what == "sweep":
            return str(sweep_png(folder / "sweep.csv", folder / "sweep.png"))
        return str(trajectory_png(folder / "trajectory.csv", folder / "trajectory.png"))
    except ImportError as e:  # matplotlib
        written = "sweep.csv was written" if what == "sweep" else "metrics.json and trajectory.csv were written"
        raise _HostFailure(EXIT_RUN_FAILED, f"{'plot: ' if what == 'sweep' else ''}{e} ({written})") from None


if __name__ == "__main__":
    sys.exit(main())
