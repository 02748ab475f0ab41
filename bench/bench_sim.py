#!/usr/bin/env python3
"""What a Python-driven loop on simloop.Sim costs per step, beside the bulk step.

On the walker (tests/scenes/walker.xml; --scene chapter for the chapter's
scene, or another MJCF path), per physics step, medians of --repeats
interleaved rounds (each round runs every case once) of --steps steps each,
wall and CPU time side by side:

  bulk        sim.step(N)                          the C++ floor
  step        sim.step(1)                          one Python call a step
  mj_step     mujoco.mj_step(m, d)                 the same in MuJoCo's own bindings (if importable)
  view        sim.ctrl_array[:] = u; sim.step(1)   ctrl written through the view
  step_ctrl   sim.step(1, ctrl=u)                  ctrl checked (shape, finite) each call
  state       get_state() + set_state()            one save and restore
  copy        copy.copy(sim)                       an independent Sim
  pickle      pickle.loads(pickle.dumps(sim))      model bytes + state

and the ratios of the per-step loops to bulk, then step against mj_step (on
the PyPI build both step the same libmujoco), with the load average. The
machine is shared: run it when it is quiet, and read the medians.

    .venv/bin/python bench/bench_sim.py [--steps 2000] [--repeats 11] [--scene chapter]
"""

import argparse
import copy
import os
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
    parser.add_argument("--scene", default=str(WALKER), help="an MJCF path, or 'chapter'")
    args = parser.parse_args()
    n = args.steps
    xml = simloop._core.PUSHER_SCENE_XML if args.scene == "chapter" else Path(args.scene).read_text()
    model = simloop.Model.from_xml_string(xml)
    u = np.linspace(0.3, -0.2, model.nu)

    def bulk():
        sim = simloop.Sim(model)
        sim.ctrl_array[:] = u
        sim.step(n)

    def step():
        sim = simloop.Sim(model)
        sim.ctrl_array[:] = u
        for _ in range(n):
            sim.step(1)

    try:
        import mujoco
    except ImportError:
        mujoco = None
    m = mujoco.MjModel.from_xml_string(xml) if mujoco else None  # compiled once, as `model`

    def mj_step():
        d = mujoco.MjData(m)
        d.ctrl[:] = u
        for _ in range(n):
            mujoco.mj_step(m, d)

    def view():
        sim = simloop.Sim(model)
        ctrl = sim.ctrl_array
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
        ("step", step, n),
        *([("mj_step", mj_step, n)] if mujoco else []),
        ("view", view, n),
        ("step_ctrl", step_ctrl, n),
        ("state", state, n),
        ("copy", copies, n // 10),
        ("pickle", pickles, n // 10),
    ]
    samples = {name: [] for name, _, _ in cases}
    for _ in range(args.repeats):  # interleaved: a busy spell on the machine hits every case alike
        for name, work, count in cases:
            samples[name].append(timed(work, count))
    medians = {name: tuple(statistics.median(s[i] for s in runs) for i in (0, 1)) for name, runs in samples.items()}
    print(f"{Path(args.scene).name}, {n} steps, median of {args.repeats} interleaved rounds")
    print(f"{'case':<10} {'wall us':>9} {'cpu us':>9} {'wall/bulk':>10} {'cpu/bulk':>9}")
    bulk_wall, bulk_cpu = medians["bulk"]
    for name, (wall, cpu) in medians.items():
        print(f"{name:<10} {wall * 1e6:9.2f} {cpu * 1e6:9.2f} {wall / bulk_wall:10.2f} {cpu / bulk_cpu:9.2f}")
    if mujoco:
        (wall, cpu), (mj_wall, mj_cpu) = medians["step"], medians["mj_step"]
        print(f"step / mj_step: {wall / mj_wall:.3f} wall, {cpu / mj_cpu:.3f} cpu (mujoco {mujoco.__version__})")
    print("load average: " + " ".join(f"{x:.2f}" for x in os.getloadavg()))
    print(f"pickled Sim: {len(pickle.dumps(sim))} bytes")


if __name__ == "__main__":
    main()
