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


def main(argv: Optional[List[str]] = None) -> int:
    started = time.perf_counter()
    from . import _core, load_model

    args = sys.argv[1:] if argv is None else list(argv)
    try:
        opts = _core.parse_command_line(args)
    except ValueError as e:
        return _fail(EXIT_USAGE, str(e))
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
    except (OSError, _core.MujocoError, ValueError) as e:
        return _fail(EXIT_RUN_FAILED, str(e))
    elapsed = time.perf_counter() - started
    print(f"wall-clock: {elapsed * 1e3:.1f} ms, peak memory: {_peak_memory_mib():.1f} MiB")
    return 0


if __name__ == "__main__":
    sys.exit(main())
