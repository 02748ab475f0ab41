#!/usr/bin/env python3
"""What a Python-driven loop on simloop.Sim costs per step, beside the bulk step.

On the walker (tests/scenes/walker.xml), per physics step, medians of
--repeats runs of --steps steps each, wall and CPU time side by side:

  bulk        sim.step(N)                          the C++ floor
  view        sim.ctrl[:] = u; sim.step(1)         ctrl written through the view
  step_ctrl   sim.step(1, ctrl=u)                  ctrl checked (shape, finite) each call
  state       get_state() + set_state()            one save and restore
  copy        copy.copy(sim)                       an independent Sim
  pickle      pickle.loads(pickle.dumps(sim))      model bytes + state

and the ratios of the per-step loops to bulk. The machine is shared: run it
when it is quiet, and read the medians.

    .venv/bin/python bench/bench_sim.py [--steps 2000] [--repeats 11]
"""

import argparse
import copy
import pickle
import statistics
import time
from pathlib import Path

import numpy as np
import simloop

WALKER = Path(__file__).resolve().parents[1] / "tests" / "scenes" / "walker.xml"


def timed(work, count: int) -> tuple[float, float]:
    """(wall, cpu) seconds per item for work() doing `count` items."""
    wall, cpu = time.perf_counter(), time.process_time()
    work()
    return (time.perf_counter() - wall) / count, (time.process_time() - cpu) / count


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--steps", type=int, default=2000)
    parser.add_argument("--repeats", type=int, default=11)
    args = parser.parse_args()
    n = args.steps
    model = simloop.Model.from_file(WALKER)
    u = np.array([0.3, -0.2, 0.1, 0.0])

    def bulk():
        sim = simloop.Sim(model)
        sim.ctrl[:] = u
        sim.step(n)

    def view():
        sim = simloop.Sim(model)
        ctrl = sim.ctrl
        for _ in range(n):
            ctrl[:] = u
            sim.step(1)

    def step_ctrl():
        sim = simloop.Sim(model)
        for _ in range(n):
            sim.step(1, ctrl=u)

    sim = simloop.Sim(model)
    sim.step(100, ctrl=u)

    def state():
        for _ in range(n):
            sim.set_state(sim.get_state())

    def copies():
        for _ in range(n // 10):
            copy.copy(sim)

    def pickles():
        for _ in range(n // 10):
            pickle.loads(pickle.dumps(sim))

    cases = [
        ("bulk", bulk, n),
        ("view", view, n),
        ("step_ctrl", step_ctrl, n),
        ("state", state, n),
        ("copy", copies, n // 10),
        ("pickle", pickles, n // 10),
    ]
    medians = {}
    for name, work, count in cases:
        samples = [timed(work, count) for _ in range(args.repeats)]
        medians[name] = (statistics.median(s[0] for s in samples), statistics.median(s[1] for s in samples))
    print(f"walker, {n} steps, median of {args.repeats}")
    print(f"{'case':<10} {'wall us':>9} {'cpu us':>9} {'wall/bulk':>10} {'cpu/bulk':>9}")
    bulk_wall, bulk_cpu = medians["bulk"]
    for name, (wall, cpu) in medians.items():
        print(f"{name:<10} {wall * 1e6:9.2f} {cpu * 1e6:9.2f} {wall / bulk_wall:10.2f} {cpu / bulk_cpu:9.2f}")
    print(f"pickled Sim: {len(pickle.dumps(sim))} bytes")


if __name__ == "__main__":
    main()
