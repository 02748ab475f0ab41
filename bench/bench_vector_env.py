#!/usr/bin/env python3
"""The vector environment's steps per second on 2 threads against 1.

ScenarioVectorEnv over the PushT scenario (python/simloop/scenes/pusht.toml):
--envs episodes (default 32), each env.step taking --every physics steps
(default 50) per episode, random actions drawn up front; rounds alternate
1 and 2 threads (two environments, reset with the same seed), each round
--calls calls of step(). Physics steps per second, wall-clock, and process
CPU time beside it; medians, and the median of the per-round ratios.
Target: 2 threads >= 1.8 x 1 thread (on 2 cores).

--pause US: the caller sleeps US microseconds between calls, as a trainer's
own code runs between steps; the time is then that of the step() calls
alone. The threads then sleep between calls, and waking them costs the
calling thread (cpp/worker_pool.hpp): on a VM, 2 threads can be slower than
1 for calls of under a millisecond of work.

--overhead: the Python each step() call adds, at 1 and 64 envs (--sizes),
one physics step a call, one thread: CPU time per call of env.step against
the C++ step it makes (Episodes.step, the bare loop of calls), in
interleaved rounds of --calls calls. --only K: just K step() calls of --envs
envs (--bare: of Episodes.step), for instruction counts: run it under
valgrind --tool=callgrind with K and 2K and take the difference.

    .venv/bin/python bench/bench_vector_env.py [--rounds 15] [--envs 32] [--every 50] [--calls 20] [--pause 0]
    .venv-pypi/bin/python bench/bench_vector_env.py --overhead [--sizes 1,64] [--rounds 15] [--calls 2000]
    valgrind --tool=callgrind .venv-pypi/bin/python bench/bench_vector_env.py --only 2000 --envs 64 [--bare]
"""

import argparse
import os
import statistics
import time

import numpy as np
from simloop.gym import PUSHT_SCENARIO, ScenarioVectorEnv


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=15)
    parser.add_argument("--envs", type=int, default=32)
    parser.add_argument("--every", type=int, default=50)
    parser.add_argument("--calls", type=int, default=20)
    parser.add_argument("--pause", type=float, default=0.0, help="microseconds between calls")
    parser.add_argument("--overhead", action="store_true", help="step()'s Python per call, at --sizes envs")
    parser.add_argument("--sizes", default="1,64")
    parser.add_argument("--only", type=int, default=0, help="just this many step() calls (for callgrind)")
    parser.add_argument("--bare", action="store_true", help="with --only: Episodes.step calls instead")
    args = parser.parse_args()
    if args.only:
        return only(args.envs, args.only, args.bare)
    if args.overhead:
        return overhead([int(n) for n in args.sizes.split(",")], args.rounds, args.calls)
    envs = {t: ScenarioVectorEnv(PUSHT_SCENARIO, args.envs, control_every=args.every, threads=t) for t in (1, 2)}
    actions = np.random.default_rng(0).uniform(-1, 1, size=(args.calls, args.envs, 2))
    steps = args.envs * args.every * args.calls
    pause = args.pause * 1e-6

    def timed(env):
        env.reset(seed=0)
        wall, cpu = 0.0, time.process_time()
        for a in actions:
            start = time.perf_counter()
            env.step(a)
            wall += time.perf_counter() - start
            if pause:
                time.sleep(pause)
        return wall, time.process_time() - cpu

    timed(envs[1]), timed(envs[2])  # warm up
    times = {1: [], 2: []}
    for r in range(args.rounds):
        for t in (1, 2) if r % 2 else (2, 1):
            times[t].append(timed(envs[t]))
    print(
        f"ScenarioVectorEnv(PushT): {args.envs} envs x {args.every} steps per call x {args.calls} calls "
        f"= {steps} physics steps a round, {args.rounds} rounds"
        + (
            f", {args.pause:g} us paused between calls (not timed; CPU time includes any spent meanwhile)"
            if pause
            else ""
        )
    )
    for t in (1, 2):
        wall = statistics.median(x[0] for x in times[t])
        cpu = statistics.median(x[1] for x in times[t])
        print(
            f"  {t} thread{'s' if t > 1 else ' '}: {steps / wall:10.0f} steps/s wall (median {wall * 1e3:7.2f} ms), "
            f"cpu median {cpu * 1e3:7.2f} ms"
        )
    ratio = statistics.median(one[0] / two[0] for one, two in zip(times[1], times[2]))
    print(f"  2 threads / 1 thread: {ratio:.3f} x the steps per second (median of per-round ratios; target >= 1.8)")
    return 0


def stepper(n, bare):
    """One env.step call of n envs (or the bare C++ step it makes), reset."""
    env = ScenarioVectorEnv(PUSHT_SCENARIO, n, threads=1, steps=10**6)
    env.reset(seed=0)
    if bare:
        episodes = env._setup.episodes
        return lambda a: episodes.step(a, 1, None, 1)
    return env.step


def only(n, calls, bare):
    step, action = stepper(n, bare), np.zeros((n, 2))
    for _ in range(calls):
        step(action)
    return 0


def overhead(sizes, rounds, calls):
    print(
        f"ScenarioVectorEnv(PushT) step() against the C++ step it makes (Episodes.step), 1 physics step a call, "
        f"1 thread, {calls} calls a round, {rounds} rounds, load average {os.getloadavg()[0]:.2f}"
    )
    for n in sizes:
        steppers = {"env.step": stepper(n, False), "bare": stepper(n, True)}
        actions = np.random.default_rng(0).uniform(-1, 1, size=(calls, n, 2))
        times = {name: [] for name in steppers}
        for r in range(rounds + 1):
            for name in list(steppers) if r % 2 else list(steppers)[::-1]:
                step = steppers[name]
                wall, cpu = time.perf_counter(), time.process_time()
                for a in actions:
                    step(a)
                if r:  # (round 0 warms up)
                    times[name].append((time.perf_counter() - wall, time.process_time() - cpu))
        cpu = {name: statistics.median(t[1] for t in ts) / calls * 1e6 for name, ts in times.items()}
        wall = {name: statistics.median(t[0] for t in ts) / calls * 1e6 for name, ts in times.items()}
        print(
            f"  {n:3d} envs: env.step {cpu['env.step']:7.2f} us CPU ({wall['env.step']:7.2f} wall), bare "
            f"{cpu['bare']:7.2f} us CPU ({wall['bare']:7.2f} wall) a call: Python {cpu['env.step'] - cpu['bare']:6.2f} "
            f"us CPU a call; env.step makes {cpu['bare'] / cpu['env.step']:.3f} x the bare loop's calls a CPU second"
        )
    print(f"  load average after: {os.getloadavg()[0]:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
