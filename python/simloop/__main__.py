"""`python -m simloop` and `sim-loop`: the chapter's command, in Python.

Same flags and defaults as `sim_loop` (the command line is parsed by the same
C++ code), the same metrics.json and trajectory.csv bytes, the same summary;
and, as in the chapter, a rerun recording sim_loop.rrd by default
(--no-rerun to skip).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path
from typing import List, Optional

PROGRAM = "sim-loop"
EXIT_RUN_FAILED = 1
EXIT_USAGE = 2


def _fail(code: int, message: str) -> int:
    line = "; ".join(part.strip() for part in str(message).splitlines() if part.strip())
    print(f"{PROGRAM}: {line}", file=sys.stderr)
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


def _plot_command(args: List[str]) -> int:
    """`python -m simloop plot trajectory|sweep [--out DIR]`: draws the PNG from
    the CSV in DIR. sim_loop --plot calls this."""
    usage = "usage: python -m simloop plot trajectory|sweep [--out DIR]"
    if not args or args[0] not in ("trajectory", "sweep") or len(args) not in (1, 3) or \
            (len(args) == 3 and args[1] != "--out"):
        return _fail(EXIT_USAGE, usage)
    from .plots import sweep_png, trajectory_png

    out = Path(args[2] if len(args) == 3 else "outputs/ch0.1-sim-loop")
    csv = out / f"{args[0]}.csv"
    if not csv.is_file():
        return _fail(EXIT_USAGE, f"--out: {csv}: no such file (run the command first)")
    draw = trajectory_png if args[0] == "trajectory" else sweep_png
    try:
        draw(csv, out / f"{args[0]}.png")
    except (OSError, ValueError, KeyError) as e:
        return _fail(EXIT_RUN_FAILED, f"plot: {csv}: {e}")
    return 0


def _sweep(opts, model, out: Path) -> None:
    from . import _core

    result = _core.sweep(model, opts.sweep_timesteps, opts.sweep_duration, opts.threads)
    csv = result.write(out)
    print(result.summary(), end="")
    print(f"sweep: {csv}")
    # The chart is the point of a sweep: drawn always here (--plot or not).
    from .plots import sweep_png

    print(f"plot: {sweep_png(csv, out / 'sweep.png')}")


def main(argv: Optional[List[str]] = None) -> int:
    started = time.perf_counter()
    args = sys.argv[1:] if argv is None else list(argv)
    # A path from the command line may hold bytes that are not UTF-8 (sys.argv
    # carries them as surrogates): print it back as those bytes, as sim_loop does.
    if hasattr(sys.stdout, "reconfigure"):
        sys.stdout.reconfigure(errors="surrogateescape")
    if args and args[0] == "plot":
        return _plot_command(args[1:])
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
    try:
        model = load_model(opts.model_path or None)
    except (OSError, ValueError, _core.MujocoError) as e:
        return _fail(EXIT_USAGE if opts.model_path else EXIT_RUN_FAILED, f"--model: {e}")
    out = Path(opts.out)
    try:
        _core.prepare_output_dir(out)
    except OSError as e:
        return _fail(EXIT_USAGE, f"--out: {e}")

    if opts.command == "sweep":
        try:
            _sweep(opts, model, out)
        except (OSError, _core.MujocoError, ValueError) as e:
            return _fail(EXIT_RUN_FAILED, str(e))
        print(f"wall-clock: {(time.perf_counter() - started) * 1e3:.1f} ms, peak memory: {_peak_memory_mib():.1f} MiB")
        return 0

    try:
        result = _core.run(model, opts.run)
        metrics_path, trajectory_path = result.write(out)
        print(result.summary(), end="")
        print(f"metrics: {metrics_path}")
        print(f"trajectory: {trajectory_path} ({result.rows} rows)")
        if opts.rerun:
            from .recording import record

            rrd = record(result, out / "sim_loop.rrd", model)
            print(f"recording: {rrd} -- open it with: rerun {rrd}")
        if opts.plot:
            from .plots import trajectory_png

            print(f"plot: {trajectory_png(trajectory_path, out / 'trajectory.png')}")
    except (OSError, _core.MujocoError, ValueError) as e:
        return _fail(EXIT_RUN_FAILED, str(e))
    elapsed = time.perf_counter() - started
    print(f"wall-clock: {elapsed * 1e3:.1f} ms, peak memory: {_peak_memory_mib():.1f} MiB")
    return 0


if __name__ == "__main__":
    sys.exit(main())
