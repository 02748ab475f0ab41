#!/usr/bin/env python3
"""Peak memory of `sim_loop --steps N` as N grows: it must stay bounded.

sim_loop writes trajectory.csv as it steps, so its peak memory should not
grow with the run (budget: under 64 MiB at 10^7 steps; before streaming it
held the whole trajectory and then the whole CSV text, about 704 bytes a
step: 6.7 GiB at 10^7). For each N this runs the command, reads the VmHWM it
reports on its last line (wait4's ru_maxrss would also count this Python
process, which the child is a copy of until it execs), and takes the wall
and CPU time (user + system, from wait4) of the process. It prints medians
side by side: peak memory against the 64 MiB budget and against the
smallest run's peak, and CPU time beside wall time.

    python3 bench/bench_memory.py [--build build] [--runs 3] [--big-runs 1]

10^7 steps take about a minute a run on the 2-core machine: --big-runs sets
how many of those (default 1).
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

PEAK_BUDGET_MIB = 64.0
STEPS = (10**5, 10**6, 10**7)


def run_once(exe: Path, steps: int, out: Path) -> tuple[float, float, float]:
    """One `sim_loop --steps N`: (wall s, CPU s, peak memory MiB)."""
    start = time.perf_counter()
    proc = subprocess.Popen([str(exe), "--steps", str(steps), "--out", str(out)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - start
    proc.returncode = os.waitstatus_to_exitcode(status)
    stdout, stderr = proc.stdout.read(), proc.stderr.read()
    if proc.returncode != 0:
        sys.exit(f"sim_loop --steps {steps} failed ({proc.returncode}): {stderr.strip()}")
    last = stdout.splitlines()[-1]
    match = re.search(r"peak memory: ([0-9.]+) MiB", last)
    if not match:
        sys.exit(f"sim_loop did not report its peak memory: {last!r}")
    return wall, usage.ru_utime + usage.ru_stime, float(match.group(1))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--build", type=Path, default=Path("build"), help="CMake build directory")
    parser.add_argument("--runs", type=int, default=3, help="runs at 10^5 and 10^6 steps")
    parser.add_argument("--big-runs", type=int, default=1, help="runs at 10^7 steps (about a minute each)")
    args = parser.parse_args()
    exe = args.build / "sim_loop"
    if not exe.exists():
        sys.exit(f"--build: {exe} not found; build first (README)")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for steps in STEPS:
            runs = args.big_runs if steps >= 10**7 else args.runs
            results = [run_once(exe, steps, Path(tmp)) for _ in range(runs)]
            walls, cpus, peaks = zip(*results)
            rows.append((steps, runs, statistics.median(walls), statistics.median(cpus), statistics.median(peaks),
                         max(peaks)))
            trajectory = Path(tmp) / "trajectory.csv"
            rows[-1] += (trajectory.stat().st_size / 2**20,)
    base_peak = rows[0][4]
    print(f"sim_loop --steps N: medians; peak memory is VmHWM (budget {PEAK_BUDGET_MIB:.0f} MiB at any N)")
    print(f"{'steps':>10} {'runs':>4} {'wall s':>8} {'CPU s':>8} {'CPU/wall':>8} {'peak MiB':>9} "
          f"{'/budget':>8} {'/peak@1e5':>9} {'csv MiB':>9}")
    for steps, runs, wall, cpu, peak, peak_max, csv_mib in rows:
        print(f"{steps:>10} {runs:>4} {wall:>8.2f} {cpu:>8.2f} {cpu / wall:>8.2f} {peak:>9.1f} "
              f"{peak / PEAK_BUDGET_MIB:>8.2f} {peak / base_peak:>9.2f} {csv_mib:>9.1f}")
    worst = max(row[5] for row in rows)
    print(f"largest peak {worst:.1f} MiB: {'within' if worst < PEAK_BUDGET_MIB else 'OVER'} the budget")
    return 0 if worst < PEAK_BUDGET_MIB else 1


if __name__ == "__main__":
    sys.exit(main())
