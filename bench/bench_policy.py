#!/usr/bin/env python3
"""A policy in the loop against the open-loop run of the same scenario.

The PushT scenario (python/simloop/scenes/pusht.toml, recording two bodies,
two joints, two actuators and two sensors) run by run_scenario open loop,
and with a policy called every 50 steps (control_every=50) that returns a
constant ctrl: paired rounds, alternating which goes first, on one scene
compiled once. The policy writes what the scenario's controls write
(push_x 0.8; push_y 0, 0.4 from 0.5 s, 2.0 from 1 s: changes at decision
steps), so both runs do the same physics: the script checks that their
trajectories are equal. Wall-clock and process CPU time; the
medians of the per-round ratios. Target: policy / open loop <= 1.10.

    .venv/bin/python bench/bench_policy.py [--rounds 41] [--steps 5000] [--every 50]
"""

import argparse
import statistics
import time

import numpy as np
import simloop
from simloop.gym import PUSHT_SCENARIO


def timed(fn):
    wall, cpu = time.perf_counter(), time.process_time()
    fn()
    return time.perf_counter() - wall, time.process_time() - cpu


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=41)
    parser.add_argument("--steps", type=int, default=5000)
    parser.add_argument("--every", type=int, default=50)
    args = parser.parse_args()
    scenario = simloop.Scenario.from_file(PUSHT_SCENARIO)
    scene = scenario.model()

    def policy(obs):  # the scenario's own controls
        return 0.8, (0.0 if obs.time < 0.5 - 1e-9 else 0.4 if obs.time < 1.0 - 1e-9 else 2.0)

    def open_loop():
        return simloop.run_scenario(scenario, steps=args.steps, model=scene)

    def with_policy():
        return simloop.run_scenario(scenario, steps=args.steps, model=scene, policy=policy, control_every=args.every)

    if 250 % args.every or 500 % args.every:
        parser.error("--every must divide 250 (the scenario's ctrl changes at steps 250 and 500)")
    if not np.array_equal(open_loop().trajectory, with_policy().trajectory, equal_nan=True):
        raise SystemExit("the policy run's trajectory differs from the open loop's")
    times = {"open": [], "policy": []}
    for r in range(args.rounds):
        order = [("open", open_loop), ("policy", with_policy)]
        for name, fn in order if r % 2 else order[::-1]:
            times[name].append(timed(fn))
    decisions = -(-args.steps // args.every)
    print(
        f"PushT, {args.steps} steps, a policy every {args.every} steps ({decisions} decisions), "
        f"{args.rounds} paired rounds"
    )
    for name in ("open", "policy"):
        wall = statistics.median(t[0] for t in times[name])
        cpu = statistics.median(t[1] for t in times[name])
        print(
            f"  {name:>6}: wall median {wall * 1e3:8.3f} ms ({wall / args.steps * 1e6:5.2f} us/step), "
            f"cpu median {cpu * 1e3:8.3f} ms"
        )
    wall_ratio = statistics.median(p[0] / o[0] for p, o in zip(times["policy"], times["open"]))
    cpu_ratio = statistics.median(p[1] / o[1] for p, o in zip(times["policy"], times["open"]))
    print(
        f"  policy / open loop: {wall_ratio:.4f} wall, {cpu_ratio:.4f} cpu (medians of per-round ratios; "
        f"target <= 1.10)"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
