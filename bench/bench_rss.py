#!/usr/bin/env python3
"""Peak memory against run length, for both commands: it must not grow.

For the chapter's run at 10^3, 10^4, 10^5 and 10^6 steps, this runs

    sim_loop --steps N                      (writes no recording)
    python -m simloop --steps N --no-rerun
    python -m simloop --steps N             (with its recording, sim_loop.rrd)

each in a fresh process, reads the peak resident memory (VmHWM) the command
reports on its last line, and takes the process's wall and CPU time (user +
system, from wait4). It prints medians over --runs runs (--big-runs at 10^6
steps), each command's peak against its own 10^3-step peak (target: at most
1.5 at 10^6), and the recording's size per step. Both commands stream
trajectory.csv (and the recording) as they step, so only the interpreter,
numpy and rerun (importing rerun is about 130 MiB) should show.

    python3 bench/bench_rss.py [--build build] [--python .venv/bin/python]
                               [--runs 3] [--big-runs 1] [--steps 1000,10000,...]

A benchmark, not a test: it prints figures (and exits 1 if a ratio is over
the target). 10^6 steps with the recording take about half a minute a run
on the 2-core development machine and write a 200 MB .rrd and a 330 MB CSV
into a temporary folder.
"""

import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

STEPS = (10**3, 10**4, 10**5, 10**6)
TARGET_RATIO = 1.5


def run_once(command, steps: int, out: Path):
    """(wall s, CPU s, peak MiB, .rrd bytes or None) of one run."""
    start = time.perf_counter()
    proc = subprocess.Popen(
        [*map(str, command), "--steps", str(steps), "--out", str(out)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - start
    stdout, stderr = proc.stdout.read(), proc.stderr.read()
    if os.waitstatus_to_exitcode(status) != 0:
        sys.exit(f"{' '.join(map(str, command))} --steps {steps} failed: {stderr.strip()}")
    match = re.search(r"peak memory: ([0-9.]+) MiB", stdout.splitlines()[-1])
    if not match:
        sys.exit(f"no peak memory in {stdout.splitlines()[-1]!r}")
    rrd = out / "sim_loop.rrd"
    size = rrd.stat().st_size if rrd.exists() else None
    for name in ("metrics.json", "trajectory.csv", "sim_loop.rrd"):
        (out / name).unlink(missing_ok=True)  # the next run starts from an empty folder
    return wall, usage.ru_utime + usage.ru_stime, float(match.group(1)), size


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--build", type=Path, default=Path("build"), help="CMake build directory (for sim_loop)")
    parser.add_argument("--python", type=Path, default=Path(".venv/bin/python"), help="a Python with simloop")
    parser.add_argument("--runs", type=int, default=3, help="runs per point below 10^6 steps")
    parser.add_argument("--big-runs", type=int, default=1, help="runs per point at 10^6 steps and more")
    parser.add_argument("--steps", default=",".join(map(str, STEPS)), help="the run lengths, comma-separated")
    args = parser.parse_args()
    steps_list = [int(s) for s in args.steps.split(",")]
    exe = args.build / "sim_loop"
    if not exe.exists():
        sys.exit(f"--build: {exe} not found; build first (README)")
    commands = [
        ("sim_loop", [exe]),
        ("python -m simloop --no-rerun", [args.python, "-m", "simloop", "--no-rerun"]),
        ("python -m simloop (recording)", [args.python, "-m", "simloop"]),
    ]
    rows = []
    with tempfile.TemporaryDirectory(prefix="bench_rss.") as tmp:
        for label, command in commands:
            for steps in steps_list:
                runs = args.big_runs if steps >= 10**6 else args.runs
                results = [run_once(command, steps, Path(tmp)) for _ in range(runs)]
                walls, cpus, peaks, sizes = zip(*results)
                rows.append(
                    (
                        label,
                        steps,
                        runs,
                        statistics.median(walls),
                        statistics.median(cpus),
                        statistics.median(peaks),
                        sizes[0],
                    )
                )
                print(f"  {label} {steps}: peak {rows[-1][5]:.1f} MiB", file=sys.stderr, flush=True)
    print("the chapter's run, --steps N: medians; peak = VmHWM of the command's process")
    print(
        f"{'command':>30} {'steps':>8} {'runs':>4} {'wall s':>8} {'CPU s':>8} {'peak MiB':>9} "
        f"{'/peak@1st':>9} {'rrd B/step':>10}"
    )
    ok = True
    for label, steps, runs, wall, cpu, peak, size in rows:
        base = next(r[5] for r in rows if r[0] == label)
        per_step = f"{size / (steps + 1):10.1f}" if size else f"{'-':>10}"
        print(f"{label:>30} {steps:>8} {runs:>4} {wall:>8.2f} {cpu:>8.2f} {peak:>9.1f} {peak / base:>9.2f} {per_step}")
    for label, _ in commands:
        mine = [r for r in rows if r[0] == label]
        ratio = mine[-1][5] / mine[0][5]
        verdict = "within" if ratio <= TARGET_RATIO else "OVER"
        ok = ok and ratio <= TARGET_RATIO
        print(f"{label}: peak at {mine[-1][1]} / at {mine[0][1]} steps = {ratio:.2f} ({verdict} {TARGET_RATIO})")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
