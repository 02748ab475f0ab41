#!/usr/bin/env python3
"""The Python side's costs, measured side by side and printed as ratios.

1. simloop.run() for 2000 steps against the same run inside C++ (bench_loop
   --serve times simloop::run as sim_loop calls it), alternating run by run.
   Budget: <= 1.05.
2. run_batch over 64 seeds on 2 threads against 1 thread, alternating, in
   steps per second. Budget: >= 1.8 (on 2 cores).
3. `python -m simloop --no-rerun` as a whole process (budget 0.25 s), and the
   recording's extra cost, `python -m simloop` minus that (budget 0.25 s).

Medians throughout: the machines are shared and noisy.

    .venv/bin/python bench/bench_python.py [--build build] [--rounds 5]
"""

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import simloop


def median_seconds(fn, repeat):
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


class CppRunner:
    """bench_loop --serve: one C++ simloop::run per request, timed in C++."""

    def __init__(self, build: Path):
        self.proc = subprocess.Popen(
            [str(build / "bench_loop"), "--serve"], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True
        )

    def seconds(self) -> float:
        self.proc.stdin.write("run\n")
        self.proc.stdin.flush()
        return float(self.proc.stdout.readline())

    def close(self):
        self.proc.stdin.close()
        self.proc.wait()


def process_seconds(args, cwd) -> float:
    start = time.perf_counter()
    subprocess.run([sys.executable, "-m", "simloop", *args], cwd=cwd, check=True, capture_output=True)
    return time.perf_counter() - start


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--build", type=Path, default=Path("build"), help="CMake build directory (bench_loop)")
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args()
    if not (args.build / "bench_loop").exists():
        sys.exit(f"--build: {args.build / 'bench_loop'} not found; build first (README)")

    # 1. Binding overhead.
    simloop.run(smoke=True)  # compile and cache the scene first
    cpp_runner = CppRunner(args.build)
    py, cpp = [], []
    for _ in range(args.rounds * 20):
        cpp.append(cpp_runner.seconds())
        start = time.perf_counter()
        result = simloop.run()
        py.append(time.perf_counter() - start)
        del result  # freed outside the timing, as bench_loop frees its own
    cpp_runner.close()
    py_s, cpp_s = statistics.median(py), statistics.median(cpp)
    ratio = statistics.median(p / c for p, c in zip(py, cpp))
    print(
        f"simloop.run(), 2000 steps: median {py_s * 1e3:.2f} ms   C++ simloop::run: {cpp_s * 1e3:.2f} ms   "
        f"ratio {ratio:.3f} (median of {len(py)} paired runs; budget <= 1.05)"
    )

    # 2. Batch scaling.
    seeds = range(64)
    one, two = [], []
    for _ in range(args.rounds):
        one.append(median_seconds(lambda: simloop.run_batch(seeds=seeds, threads=1), 1))
        two.append(median_seconds(lambda: simloop.run_batch(seeds=seeds, threads=2), 1))
    steps = 64 * 2000
    rate1, rate2 = steps / statistics.median(one), steps / statistics.median(two)
    print(
        f"run_batch, 64 runs x 2000 steps: 1 thread {rate1:,.0f} steps/s   2 threads {rate2:,.0f} steps/s   "
        f"ratio {rate2 / rate1:.2f} (budget >= 1.8)"
    )

    # 3. The command as a whole process.
    with tempfile.TemporaryDirectory() as tmp:
        process_seconds(["--no-rerun"], tmp)  # warm the page cache
        plain, recorded = [], []
        for _ in range(args.rounds * 2):
            plain.append(process_seconds(["--no-rerun"], tmp))
            recorded.append(process_seconds([], tmp))
    plain_s, recorded_s = statistics.median(plain), statistics.median(recorded)
    print(f"python -m simloop --no-rerun: median {plain_s:.3f} s (budget 0.25 s, ratio {plain_s / 0.25:.2f})")
    print(
        f"python -m simloop (recording): median {recorded_s:.3f} s, {recorded_s - plain_s:.3f} s more "
        f"(budget 0.25 s more, ratio {(recorded_s - plain_s) / 0.25:.2f})"
    )
    start = time.perf_counter()
    subprocess.run([sys.executable, "-c", "import rerun"], check=True)
    print(f"  of which `import rerun` alone (a fresh interpreter): {time.perf_counter() - start:.3f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
