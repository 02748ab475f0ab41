#!/usr/bin/env python3
"""Whole-process cost of `sim_loop --seed 0`, and the loop's overhead.

Runs the command N times and prints medians against the budgets (30 ms and
16 MiB on a 2-core machine) as ratios, then runs build/bench_loop for the
driver-versus-bare mj_step ratios (budgets 1.03 for the chapter's run, 1.05
for a PushT scenario recording two bodies). Medians, because the machines
are shared. Wall-clock is measured here, from spawn to exit. Peak memory is
the VmHWM that sim_loop reports on its last line: wait4's ru_maxrss would also
count this Python process, which the child is a copy of until it execs.

    python3 bench/bench_command.py [--build build] [--runs 31] [--callgrind]

--callgrind also counts instructions (valgrind, about a minute): the
driver-versus-bare ratio in instructions does not move with machine load.
"""

import argparse
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

WALL_BUDGET_S = 0.030
RSS_BUDGET_MIB = 16.0


def run_once(exe: Path, out: Path) -> tuple[float, float]:
    """One `sim_loop --seed 0`: (wall seconds, peak memory in MiB)."""
    start = time.perf_counter()
    proc = subprocess.run([str(exe), "--seed", "0", "--out", str(out)], capture_output=True, text=True)
    wall = time.perf_counter() - start
    if proc.returncode != 0:
        sys.exit(f"sim_loop failed: {proc.stderr.strip()}")
    match = re.search(r"peak memory: ([0-9.]+) MiB", proc.stdout.splitlines()[-1])
    if not match:
        sys.exit(f"sim_loop did not report its peak memory: {proc.stdout.splitlines()[-1]!r}")
    return wall, float(match.group(1))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--build", type=Path, default=Path("build"), help="CMake build directory")
    parser.add_argument("--runs", type=int, default=31)
    parser.add_argument("--callgrind", action="store_true", help="also count instructions with valgrind")
    args = parser.parse_args()
    exe = args.build / "sim_loop"
    if not exe.exists():
        sys.exit(f"--build: {exe} not found; build first (README)")
    if args.callgrind and not (shutil.which("valgrind") and shutil.which("callgrind_annotate")):
        sys.exit("--callgrind: valgrind is not installed (apt-get install valgrind)")
    with tempfile.TemporaryDirectory() as tmp:
        run_once(exe, Path(tmp))  # warm the page cache
        walls, rss = zip(*(run_once(exe, Path(tmp)) for _ in range(args.runs)))
    wall = statistics.median(walls)
    mem = statistics.median(rss)
    print(f"sim_loop --seed 0, {args.runs} runs:")
    print(
        f"  wall-clock  median {wall * 1e3:.1f} ms  (min {min(walls) * 1e3:.1f}, max {max(walls) * 1e3:.1f})"
        f"  ratio to the 30 ms budget: {wall / WALL_BUDGET_S:.2f}"
    )
    print(
        f"  peak memory median {mem:.1f} MiB  (max {max(rss):.1f})"
        f"  ratio to the 16 MiB budget: {mem / RSS_BUDGET_MIB:.2f}"
    )
    print(flush=True)
    status = subprocess.call([str(args.build / "bench_loop"), "61"])
    if args.callgrind:
        print(flush=True)
        print(callgrind_ratio(args.build))
    return status


def callgrind_ratio(build: Path) -> str:
    """Instructions of simloop::run against bare_loop, inclusive, from one callgrind run."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "callgrind.out"
        subprocess.run(
            ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", str(build / "bench_loop"), "3", "2000"],
            check=True,
            capture_output=True,
        )
        report = subprocess.run(
            ["callgrind_annotate", "--inclusive=yes", str(out)], check=True, capture_output=True, text=True
        ).stdout

    def count(pattern: str) -> int:
        match = re.search(r"^\s*([0-9,]+) .*" + pattern, report, re.MULTILINE)
        if not match:
            sys.exit(f"callgrind: no line for {pattern}")
        return int(match.group(1).replace(",", ""))

    # The symbols' leading parameters: the trailing ones (defaulted) change.
    driver = count(re.escape("simloop::run(simloop::Model const&, simloop::RunConfig const&, simloop::Data&"))
    bare = count(r"\bbare_loop\(")
    scenario = count(re.escape("simloop::run_scenario(simloop::Model const&, simloop::Scenario const&"))
    bare_scenario = count(r"\bbare_scenario_loop\(")
    return (
        f"callgrind, 4 runs each: simloop::run {driver:,} instructions, bare loop {bare:,}: "
        f"ratio {driver / bare:.4f}\n"
        f"  PushT run_scenario {scenario:,} instructions, bare loop {bare_scenario:,}: "
        f"ratio {scenario / bare_scenario:.4f}"
    )


if __name__ == "__main__":
    sys.exit(main())
