"""Metrics-only chapter runs on a Dask LocalCluster against a local batch.

    .venv/bin/python bench/bench_dask.py [--runs 10000] [--rounds 3]

Each round runs, each in a fresh process (so peak memory is that case's own):
  local: simloop.run_batch(range(RUNS), threads=2, metrics_only=True);
  dask:  the same runs with executor= a LocalCluster of 2 worker processes x
         1 thread (scheduler in the client's process), default chunks.
  dask-quiet: the same with the workers' statistical profiler off.
It prints, per case, the median wall-clock, the client's CPU time, the
workers' CPU time and the client's peak RSS (VmHWM), then the throughput
ratio dask / local (runs per second; target at least 0.9). Both cases'
final box positions are hashed and must agree (the same bits).
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import textwrap

CASE = textwrap.dedent("""
    import hashlib, json, os, resource, sys, time
    import numpy as np
    import simloop

    def peak_mib():
        with open("/proc/self/status") as f:
            return next(int(l.split()[1]) for l in f if l.startswith("VmHWM:")) / 1024

    case, runs = sys.argv[1], int(sys.argv[2])
    workers_cpu = 0.0
    if case == "local":
        started, cpu = time.perf_counter(), time.process_time()
        table = simloop.run_batch(range(runs), threads=2, metrics_only=True)
        wall, cpu = time.perf_counter() - started, time.process_time() - cpu
        final_x = table["box_final_pos_x"]
    else:
        import dask, psutil
        from distributed import Client, LocalCluster
        # dask-quiet: the workers' statistical profiler off (it samples every
        # thread's stack every 10 ms; a setting for long batches, not a fix).
        dask.config.set({"distributed.worker.profile.enabled": case != "dask-quiet"})
        with LocalCluster(n_workers=2, processes=True, threads_per_worker=1, dashboard_address=None) as cluster, \\
                Client(cluster) as client:
            procs = [psutil.Process(pid) for pid in client.run(os.getpid).values()]
            before = sum(sum(p.cpu_times()[:2]) for p in procs)
            started, cpu = time.perf_counter(), time.process_time()
            table = simloop.run_batch(range(runs), executor=client)
            wall, cpu = time.perf_counter() - started, time.process_time() - cpu
            workers_cpu = sum(sum(p.cpu_times()[:2]) for p in procs) - before
            final_x = table["box_final_pos_x"]
    print(json.dumps({"wall": wall, "cpu": cpu, "workers_cpu": workers_cpu, "peak_mib": peak_mib(),
                      "hash": hashlib.sha256(np.ascontiguousarray(final_x).tobytes()).hexdigest()}))
""")


def run_case(case: str, runs: int) -> dict:
    done = subprocess.run([sys.executable, "-c", CASE, case, str(runs)], capture_output=True, text=True, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=10000)
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    cases = ("local", "dask", "dask-quiet")
    results: dict = {case: [] for case in cases}
    for round_index in range(args.rounds):
        for case in cases if round_index % 2 == 0 else cases[::-1]:
            r = run_case(case, args.runs)
            results[case].append(r)
            print(
                f"round {round_index + 1} {case:10s}: wall {r['wall']:.2f} s, client CPU {r['cpu']:.2f} s, "
                f"workers' CPU {r['workers_cpu']:.2f} s, client peak RSS {r['peak_mib']:.0f} MiB",
                flush=True,
            )
    hashes = {r["hash"] for rs in results.values() for r in rs}
    assert len(hashes) == 1, "the cases' final positions differ"
    med = {
        case: {k: statistics.median(r[k] for r in rs) for k in ("wall", "cpu", "workers_cpu", "peak_mib")}
        for case, rs in results.items()
    }
    print(f"\n{args.runs} chapter runs (2000 steps each), medians of {args.rounds} rounds:")
    for case, label in (
        ("local", "local run_batch, 2 threads"),
        ("dask", "LocalCluster, 2 processes x 1 thread"),
        ("dask-quiet", "the same, workers' profiler off"),
    ):
        m = med[case]
        print(
            f"  {label:38s} wall {m['wall']:7.2f} s  ({args.runs / m['wall']:6.0f} runs/s)  client CPU "
            f"{m['cpu']:6.2f} s  workers' CPU {m['workers_cpu']:6.2f} s  client peak RSS {m['peak_mib']:5.0f} MiB"
        )
    for case in ("dask", "dask-quiet"):
        ratios = [lo["wall"] / da["wall"] for lo, da in zip(results["local"], results[case])]
        cpu = [lo["cpu"] / (da["cpu"] + da["workers_cpu"]) for lo, da in zip(results["local"], results[case])]
        print(
            f"  throughput {case} / local: wall-clock median {statistics.median(ratios):.3f} (per round: "
            f"{', '.join(f'{x:.3f}' for x in ratios)}; target >= 0.9); CPU time, local / (client + workers): "
            f"median {statistics.median(cpu):.3f}"
        )
    print("  results: the same bits in both cases (final box x hashed)")


if __name__ == "__main__":
    main()
