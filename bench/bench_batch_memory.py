#!/usr/bin/env python3
"""Peak memory of a batch of chapter runs, metrics-only against kept trajectories.

A batch that keeps every run's trajectory holds 2001 rows x 22 doubles (352
KB) per run of the chapter: 10,000 seeds took 3.4 GiB. A metrics-only batch
(`simloop.run_batch(..., metrics_only=True)`) keeps no rows and returns a
BatchTable of numpy columns, so its memory should not grow with the batch
beyond that table (budget: 10,000 runs under 200 MiB peak).

Each measurement runs in a fresh child Python process, which reports its own
peak resident memory (VmHWM from /proc/self/status; wait4's ru_maxrss would
also count the parent, which the child is a copy of until it execs) and the
batch's wall and CPU time (user + system). Side by side in one run:

- `import`: the interpreter with numpy and simloop imported, no batch;
- `metrics-only`: RUNS runs, metrics_only=True (the BatchTable);
- `metrics-only, to_pandas`: the same, then the table to pandas (importing
  pandas alone takes tens of MiB);
- `kept`: KEPT runs (fewer: each keeps its trajectory), as a list of results,
  and the figure for RUNS such runs extrapolated from it.

    .venv/bin/python bench/bench_batch_memory.py [--runs 10000] [--kept 500] [--threads 2] [--repeat 1]
"""

import argparse
import statistics
import subprocess
import sys
import textwrap

BUDGET_MIB = 200.0

CHILD = textwrap.dedent("""
    import resource, sys, time
    import numpy, simloop
    mode, runs, threads = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    start, cpu = time.perf_counter(), time.process_time()
    if mode.startswith("metrics-only"):
        table = simloop.run_batch(seeds=range(runs), metrics_only=True, threads=threads)
        assert len(table) == runs
        wall, cpu = time.perf_counter() - start, time.process_time() - cpu
        if mode.endswith("to_pandas"):
            table.to_pandas()
    elif mode == "kept":
        batch = simloop.run_batch(seeds=range(runs), threads=threads)
        assert len(batch.results) == runs
        wall, cpu = time.perf_counter() - start, time.process_time() - cpu
    else:
        wall = cpu = 0.0
    with open("/proc/self/status") as f:
        peak = next(int(line.split()[1]) for line in f if line.startswith("VmHWM:")) / 1024
    print(f"{peak:.1f} {wall:.3f} {cpu:.3f}")
""")


def measure(mode: str, runs: int, threads: int) -> tuple[float, float, float]:
    out = subprocess.run([sys.executable, "-c", CHILD, mode, str(runs), str(threads)], capture_output=True, text=True)
    if out.returncode != 0:
        sys.exit(f"{mode} x {runs} failed: {out.stderr.strip().splitlines()[-1:]}")
    peak, wall, cpu = (float(v) for v in out.stdout.split())
    return peak, wall, cpu


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--runs", type=int, default=10_000, help="runs in the metrics-only batch")
    parser.add_argument("--kept", type=int, default=500, help="runs in the batch that keeps trajectories")
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--repeat", type=int, default=1, help="measurements of each (medians are printed)")
    args = parser.parse_args()

    figures = {}
    modes = (("import", 0), ("metrics-only", args.runs), ("metrics-only, to_pandas", args.runs), ("kept", args.kept))
    for mode, runs in modes:
        samples = [measure(mode, runs, args.threads) for _ in range(args.repeat)]
        figures[mode] = tuple(statistics.median(s[i] for s in samples) for i in range(3))
    base = figures["import"][0]
    print(f"{'what':<28} {'runs':>7} {'peak MiB':>9} {'over import':>12} {'wall s':>8} {'CPU s':>8}")
    for mode, runs in modes:
        peak, wall, cpu = figures[mode]
        print(f"{mode:<28} {runs:>7} {peak:>9.1f} {peak - base:>12.1f} {wall:>8.2f} {cpu:>8.2f}")
    kept_per_run = (figures["kept"][0] - base) / max(args.kept, 1)
    print(
        f"{'kept, extrapolated':<28} {args.runs:>7} {base + kept_per_run * args.runs:>9.1f} "
        f"{kept_per_run * args.runs:>12.1f}"
    )
    peak = max(figures["metrics-only"][0], figures["metrics-only, to_pandas"][0])
    print(
        f"metrics-only peak (with to_pandas) {peak:.1f} MiB for {args.runs} runs: "
        f"{'within' if peak <= BUDGET_MIB else 'OVER'} the {BUDGET_MIB:.0f} MiB budget; "
        f"kept (extrapolated) / metrics-only: {(base + kept_per_run * args.runs) / figures['metrics-only'][0]:.1f}"
    )
    return 0 if peak <= BUDGET_MIB else 1


if __name__ == "__main__":
    sys.exit(main())
