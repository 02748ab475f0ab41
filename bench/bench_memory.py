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
                                  [--scenario-only] [--python .venv/bin/python]

10^7 steps take about a minute a run on the 2-core machine: --big-runs sets
how many of those (default 1).

Then a scenario (tests/scenes/pusht.toml, 37 columns) the same way, from
both commands: `sim_loop --scenario`, `python -m simloop --scenario
--no-rerun` and `python -m simloop --scenario` with its recording, at 10^4,
10^5 and 10^6 steps. All three stream trajectory.csv (the Python command
kept every row in memory before: a 10^6-step PushT run held 300 MB of rows);
the recording is sent to the .rrd in blocks as the run goes. Its peak is
mostly rerun itself (importing it takes about 150 MiB): what matters is
that it does not grow with the steps.
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


SCENARIO_STEPS = (10**4, 10**5, 10**6)
SCENARIO = Path(__file__).resolve().parents[1] / "tests" / "scenes" / "pusht.toml"


def run_once(exe, steps: int, out: Path) -> tuple[float, float, float]:
    """One `sim_loop --steps N` (exe: a path, or a command as a list): (wall s, CPU s, peak memory MiB)."""
    command = [str(exe)] if isinstance(exe, Path) else list(exe)
    start = time.perf_counter()
    proc = subprocess.Popen(
        [*command, "--steps", str(steps), "--out", str(out)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - start
    proc.returncode = os.waitstatus_to_exitcode(status)
    stdout, stderr = proc.stdout.read(), proc.stderr.read()
    if proc.returncode != 0:
        sys.exit(f"{' '.join(command)} --steps {steps} failed ({proc.returncode}): {stderr.strip()}")
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
    parser.add_argument("--scenario-only", action="store_true", help="only the scenario's runs")
    parser.add_argument(
        "--python",
        type=Path,
        default=Path(".venv/bin/python"),
        help="the Python with simloop installed, for python -m simloop",
    )
    args = parser.parse_args()
    exe = args.build / "sim_loop"
    if not exe.exists():
        sys.exit(f"--build: {exe} not found; build first (README)")
    within = True
    if not args.scenario_only:
        within = chapter(exe, args)
    return 0 if scenario(exe, args) and within else 1


def scenario(exe: Path, args) -> bool:
    """The PushT scenario from both commands, with and without the recording."""
    commands = [
        ("sim_loop", [exe, "--scenario", str(SCENARIO)]),
        ("python --no-rerun", [args.python, "-m", "simloop", "--scenario", str(SCENARIO), "--no-rerun"]),
        ("python + recording", [args.python, "-m", "simloop", "--scenario", str(SCENARIO)]),
    ]
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for label, command in commands:
            for steps in SCENARIO_STEPS:
                runs = args.big_runs if steps >= 10**6 else args.runs
                results = [run_once(command, steps, Path(tmp)) for _ in range(runs)]
                walls, cpus, peaks = zip(*results)
                rows.append(
                    (
                        label,
                        steps,
                        runs,
                        statistics.median(walls),
                        statistics.median(cpus),
                        statistics.median(peaks),
                        max(peaks),
                    )
                )
    print(
        f"\n{SCENARIO.name} --steps N: medians; peak memory is VmHWM (budget {PEAK_BUDGET_MIB:.0f} MiB over "
        "the smallest run's peak, per command)"
    )
    print(
        f"{'command':>20} {'steps':>9} {'runs':>4} {'wall s':>8} {'CPU s':>8} {'CPU/wall':>8} {'peak MiB':>9} "
        f"{'/peak@1e4':>9}"
    )
    ok = True
    for label, steps, runs, wall, cpu, peak, peak_max in rows:
        base = next(r[5] for r in rows if r[0] == label)
        print(
            f"{label:>20} {steps:>9} {runs:>4} {wall:>8.2f} {cpu:>8.2f} {cpu / wall:>8.2f} {peak:>9.1f} "
            f"{peak / base:>9.2f}"
        )
        ok = ok and peak_max - base < PEAK_BUDGET_MIB
    print(f"growth from 10^4 to 10^6 steps: {'within' if ok else 'OVER'} {PEAK_BUDGET_MIB:.0f} MiB for every command")
    return ok


def chapter(exe: Path, args) -> bool:
    """sim_loop --steps N for the chapter's run."""
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for steps in STEPS:
            runs = args.big_runs if steps >= 10**7 else args.runs
            results = [run_once(exe, steps, Path(tmp)) for _ in range(runs)]
            walls, cpus, peaks = zip(*results)
            rows.append(
                (steps, runs, statistics.median(walls), statistics.median(cpus), statistics.median(peaks), max(peaks))
            )
            trajectory = Path(tmp) / "trajectory.csv"
            rows[-1] += (trajectory.stat().st_size / 2**20,)
    base_peak = rows[0][4]
    print(f"sim_loop --steps N: medians; peak memory is VmHWM (budget {PEAK_BUDGET_MIB:.0f} MiB at any N)")
    print(
        f"{'steps':>10} {'runs':>4} {'wall s':>8} {'CPU s':>8} {'CPU/wall':>8} {'peak MiB':>9} "
        f"{'/budget':>8} {'/peak@1e5':>9} {'csv MiB':>9}"
    )
    for steps, runs, wall, cpu, peak, _peak_max, csv_mib in rows:
        print(
            f"{steps:>10} {runs:>4} {wall:>8.2f} {cpu:>8.2f} {cpu / wall:>8.2f} {peak:>9.1f} "
            f"{peak / PEAK_BUDGET_MIB:>8.2f} {peak / base_peak:>9.2f} {csv_mib:>9.1f}"
        )
    worst = max(row[5] for row in rows)
    print(f"largest peak {worst:.1f} MiB: {'within' if worst < PEAK_BUDGET_MIB else 'OVER'} the budget")
    return worst < PEAK_BUDGET_MIB


if __name__ == "__main__":
    sys.exit(main())
