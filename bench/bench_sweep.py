#!/usr/bin/env python3
"""Break It's costs, side by side, as ratios (medians; the machines are noisy).

1. A sweep of 25 timesteps from 0.001 s to 0.1 s over 4 s of sim time each:
   wall time on 2 threads (budget 0.3 s) and 1 thread / 2 threads (budget
   >= 1.6), alternating.
2. The energy audit: simloop.run(audit_energy=True) / simloop.run(), 2000
   steps, paired run by run (budget <= 1.15).

    .venv/bin/python bench/bench_sweep.py [--rounds 9]
"""

import argparse
import statistics
import sys
import time

import simloop


def seconds(fn) -> float:
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rounds", type=int, default=9)
    args = parser.parse_args()
    timesteps = simloop._core.log_spaced(0.001, 0.1, 25)
    steps = sum(round(4.0 / dt) for dt in timesteps)
    simloop.sweep(timesteps)  # warm up: compile and cache the scene
    one, two = [], []
    for _ in range(args.rounds):
        one.append(seconds(lambda: simloop.sweep(timesteps, threads=1)))
        two.append(seconds(lambda: simloop.sweep(timesteps, threads=2)))
    t1, t2 = statistics.median(one), statistics.median(two)
    print(
        f"sweep, 25 timesteps 0.001..0.1 s, 4 s each ({steps} steps): 1 thread {t1:.3f} s, 2 threads {t2:.3f} s "
        f"(budget 0.3 s, ratio {t2 / 0.3:.2f}); 1 / 2 threads: {t1 / t2:.2f} (budget >= 1.6)"
    )

    plain, audited = [], []
    for _ in range(args.rounds * 10):
        plain.append(seconds(lambda: simloop.run()))
        audited.append(seconds(lambda: simloop.run(audit_energy=True)))
    ratio = statistics.median(a / p for a, p in zip(audited, plain))
    print(
        f"energy audit, 2000 steps: plain {statistics.median(plain) * 1e3:.2f} ms, audited "
        f"{statistics.median(audited) * 1e3:.2f} ms; audited / plain {ratio:.3f} "
        f"(median of {len(plain)} pairs; budget <= 1.15)"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
