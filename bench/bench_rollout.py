#!/usr/bin/env python3
"""simloop's batch of open-loop controls against mujoco.rollout and mujoco.batch.Batch.

All take the same scene (tests/scenes/pusht.xml, or the chapter's with
--scene chapter), the same B x T x nu
controls (uniform within each actuator's ctrlrange, numpy seed 0), the same
initial state (the reset pose: simloop's flat state from Sim.get_state(),
mujoco's mj_getState(mjSTATE_FULLPHYSICS) of the same mjData, Batch's
mjSTATE_INTEGRATION rows) and the same thread count, and they step the same
libmujoco (the PyPI build links the very libmujoco file that `import mujoco`
loads). So, first, the script checks that the final qpos and qvel of every
run agree bit for bit, in both the recording and the metrics-only calls, and
stops if not. Batch (bench_batch_anchor.py) is skipped, with a line saying
so, where the mujoco package has no mujoco.batch (before 3.17).

Then it times like-for-like calls, in interleaved rounds (the order rotates
round by round), for each thread count:

  record   simloop.run_scenario_batch(controls=..., initial_state=...), full
           results: every run's trajectory, one row per step of 20 columns
           (a minimal Scenario records its free body's pose and velocity,
           the ctrls, the actuator forces, the contact count)
           vs mujoco.rollout.rollout(...) with its default outputs: every
           step's full physics state (1 + nq + nv + na = 18 values for
           PushT) and sensordata (4), allocated by rollout as it returns them;
           Batch.rollout(..., record=(mjSTATE_FULLPHYSICS, "sensordata")),
           the same arrays.
  final    the same with nothing kept per step:
           simloop ... metrics_only=True (a BatchTable: one row per run)
           vs mujoco.rollout.rollout(..., skip_checks=True, state=None,
           sensordata=None), which keeps nothing at all (not even the
           final state; simloop still computes its per-run metrics);
           Batch.rollout(..., record=()), the final states left in its rows.

Times: wall (time.perf_counter) and CPU time of the whole process, every
thread (time.process_time; with --verbose, resource.getrusage(RUSAGE_SELF)
user + sys beside it). Printed: the medians per step, the medians of the
per-round ratios simloop / rollout and simloop / Batch, and the load average
before and after. Target: <= 1.05 in CPU time per step against rollout.

Issue 36's measures: --batch 4096 --steps 100, for --scene pusht and
--scene chapter (threads 1 and 2, both calls, by default); peak memory of
the metrics-only call: bench_batch_anchor.py.

Both sides run in one process that has imported mujoco, whose bindings set
mjcb_time: MuJoCo's internal timers then read the clock in every step (about
5% of a step in clock_gettime under perf), for both alike. simloop alone
(without `import mujoco`) does not pay that.

Defaults: B=16, T=1000, 41 rounds, threads 1 and 2 (about 2 minutes). On a
shared machine many short paired rounds beat a few long ones: with B=64 and
7 rounds the per-round ratios on a loaded 2-core machine ranged 0.6 to 1.7
and their medians 1.01 to 1.11 from one process to the next, while the
instruction counts (valgrind --tool=callgrind, the same calls) differ by
under 1%: simloop 1.0035x rollout recording, 1.0093x keeping nothing.

    .venv-pypi/bin/python bench/bench_rollout.py [--rounds N] [--batch B]
        [--steps T] [--threads K [K ...]] [--scene pusht|chapter|FILE] [--only record|final]
        [--no-batch] [--verbose]

Needs the PyPI build (SIMLOOP_MUJOCO=pypi, .venv-pypi), where `mujoco`
imports in the same process as simloop.
"""

import os

# numpy's OpenBLAS threads spin after a BLAS call, and the CPU time measured
# here is the whole process's: keep them out of it.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import atexit
import gc
import resource
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

try:
    import mujoco
    import mujoco.rollout
except ImportError as error:  # the 2.2.2 build's venv has no mujoco package
    sys.exit(f"bench_rollout: needs the mujoco package beside simloop (the PyPI build, .venv-pypi): {error}")

import simloop
from batch_side import BatchSide, mujoco_batch

HERE = Path(__file__).resolve().parent
DEFAULT_SCENE = HERE.parent / "tests" / "scenes" / "pusht.xml"
TARGET = 1.05


def scene_path(name):
    """pusht, chapter (simloop's chapter scene, written to a temporary file) or an MJCF file."""
    if name == "pusht":
        return DEFAULT_SCENE
    if name != "chapter":
        return Path(name)
    folder = tempfile.mkdtemp(prefix="bench_rollout_")
    atexit.register(shutil.rmtree, folder, True)
    path = Path(folder) / "chapter.xml"
    path.write_text(simloop._core.PUSHER_SCENE_XML)
    return path


def cpu_seconds():
    """(process_time, getrusage user + sys) of the whole process: every thread."""
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return time.process_time(), usage.ru_utime + usage.ru_stime


def timed(fn):
    gc.collect()
    gc.disable()
    try:
        c0, r0 = cpu_seconds()
        t0 = time.perf_counter()
        out = fn()
        wall = time.perf_counter() - t0
        c1, r1 = cpu_seconds()
    finally:
        gc.enable()
    del out  # freed outside the timing
    return wall, c1 - c0, r1 - r0


class Inputs:
    def __init__(self, scene, batch, steps, seed=0):
        self.scene, self.batch, self.steps = str(scene), batch, steps
        self.model = mujoco.MjModel.from_xml_path(self.scene)
        m = self.model
        self.models = [m] * batch
        if m.nu == 0:
            sys.exit(f"bench_rollout: {scene} has no actuators")
        lo = np.where(m.actuator_ctrllimited, m.actuator_ctrlrange[:, 0], -1.0)
        hi = np.where(m.actuator_ctrllimited, m.actuator_ctrlrange[:, 1], 1.0)
        rng = np.random.default_rng(seed)
        self.controls = np.ascontiguousarray(rng.uniform(lo, hi, size=(batch, steps, m.nu)))

        # The same reset pose in each one's state format.
        data = mujoco.MjData(m)
        mujoco.mj_resetData(m, data)
        full = mujoco.mjtState.mjSTATE_FULLPHYSICS
        self.rollout_state0 = np.empty((batch, mujoco.mj_stateSize(m, full)))
        for row in self.rollout_state0:
            mujoco.mj_getState(m, data, row, full)
        sim = simloop.Sim(self.scene)
        self.layout = sim.state_layout()
        self.simloop_state0 = np.ascontiguousarray(np.tile(sim.get_state(), (batch, 1)))
        offset, self.parts = 0, {}
        for name, size in self.layout:
            self.parts[name] = slice(offset, offset + size)
            offset += size
        # Both starting points must say the same thing where they overlap.
        for name, part in (
            ("time", slice(0, 1)),
            ("qpos", slice(1, 1 + m.nq)),
            ("qvel", slice(1 + m.nq, 1 + m.nq + m.nv)),
        ):
            if not np.array_equal(self.simloop_state0[:, self.parts[name]], self.rollout_state0[:, part]):
                sys.exit(f"bench_rollout: the two initial states differ in {name}")

        self.scenario = simloop.Scenario(scene=self.scene, steps=steps)
        self.seeds = range(batch)  # no disturbances: the seed changes nothing
        self.simloop_model = self.scenario.model()  # compiled once, as rollout's MjModel is

    # --- the two sides; each returns what a user would keep

    def simloop(self, threads, metrics_only):
        return simloop.run_scenario_batch(
            self.scenario,
            seeds=self.seeds,
            model=self.simloop_model,
            controls=self.controls,
            initial_state=self.simloop_state0,
            threads=threads,
            metrics_only=metrics_only,
        )

    def rollout(self, threads, datas, keep):
        if keep:
            return mujoco.rollout.rollout(self.model, datas[:threads], self.rollout_state0, self.controls)
        # skip_checks passes its arguments straight through: a model per run, outputs None (kept: nothing).
        mujoco.rollout.rollout(
            self.models, datas[:threads], self.rollout_state0, self.controls, skip_checks=True, nstep=self.steps
        )
        return None

    def qpos_qvel_rollout(self, states):
        m = self.model
        last = states[:, -1, :]
        return last[:, 1 : 1 + m.nq], last[:, 1 + m.nq : 1 + m.nq + m.nv]

    def qpos_qvel_simloop(self, results):
        final = np.stack([r.final_state for r in results])
        return final[:, self.parts["qpos"]], final[:, self.parts["qvel"]]


def bits_equal(a, b):
    return np.array_equal(np.ascontiguousarray(a).view(np.uint64), np.ascontiguousarray(b).view(np.uint64))


def report_same(label, threads, mine, theirs, batch):
    """One line: label's final qpos and qvel against simloop's, bit for bit."""
    (mq, mv), (sq, sv) = mine, theirs
    same_q, same_v = bits_equal(mq, sq), bits_equal(mv, sv)
    print(
        f"  threads={threads}: {label} final qpos {'identical' if same_q else 'DIFFER'}, "
        f"qvel {'identical' if same_v else 'DIFFER'} to simloop's in all {batch} runs"
    )
    if not (same_q and same_v):
        bad = np.flatnonzero((mq != sq).any(axis=1) | (mv != sv).any(axis=1))
        i = int(bad[0])
        print(
            f"    {len(bad)} runs differ; run {i}: max |dqpos| {np.abs(mq[i] - sq[i]).max():.3g}, "
            f"max |dqvel| {np.abs(mv[i] - sv[i]).max():.3g}"
        )
    return same_q and same_v


def check_same(inputs, datas, threads, batch_side):
    """Final qpos and qvel of every run, bit for bit: rollout's and Batch's (both calls) against simloop's."""
    results = inputs.simloop(threads, metrics_only=False).results  # each run's ScenarioResult
    states, _ = inputs.rollout(threads, datas, keep=True)
    warned = [r.seed for r in results if r.warnings]
    if warned:
        print(f"  threads={threads}: simloop warnings in runs {warned}")
    ours = inputs.qpos_qvel_simloop(results)
    ok = report_same("rollout", threads, inputs.qpos_qvel_rollout(states), ours, inputs.batch)
    if batch_side is not None:
        for keep, label in ((True, "Batch (recording)"), (False, "Batch (nothing kept)")):
            ok = report_same(label, threads, batch_side.qpos_qvel(threads, keep), ours, inputs.batch) and ok
    # The metrics-only table says the same about each recorded free body's final position.
    table = inputs.simloop(threads, metrics_only=True).to_pandas()
    m, sq = inputs.model, ours[0]
    for column in [c for c in table.columns if c.endswith("_final_pos_x")]:
        body = m.body(column[: -len("_final_pos_x")])
        if body.jntnum[0] < 1 or m.jnt_type[body.jntadr[0]] != mujoco.mjtJoint.mjJNT_FREE:
            continue
        adr = m.jnt_qposadr[body.jntadr[0]]
        tq = table[[column[:-1] + axis for axis in "xyz"]].to_numpy()
        same_table = np.array_equal(tq, sq[:, adr : adr + 3])
        ok = ok and same_table
        print(
            f"  threads={threads}: metrics_only table's {column[:-2]} "
            f"{'identical' if same_table else 'DIFFERS'} to the full results' final qpos"
        )
    return ok


def load():
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rounds", type=int, default=41, help="interleaved rounds per pair (default 41)")
    parser.add_argument("--batch", type=int, default=16, help="rollouts B (default 16)")
    parser.add_argument("--steps", type=int, default=1000, help="steps T per rollout (default 1000)")
    parser.add_argument("--threads", type=int, nargs="+", default=[1, 2], help="thread counts (default 1 2)")
    parser.add_argument("--scene", default="pusht", help="pusht (default), chapter or an MJCF file")
    parser.add_argument("--only", choices=("record", "final"), help="time one pair only")
    parser.add_argument("--no-batch", action="store_true", help="leave mujoco.batch.Batch out")
    parser.add_argument("--verbose", action="store_true", help="also print rusage and every round's CPU ratios")
    args = parser.parse_args()
    scene = scene_path(args.scene)
    if not scene.is_file():
        sys.exit(f"bench_rollout: --scene {args.scene}: no such file")
    if min(args.rounds, args.batch, args.steps, min(args.threads)) < 1:
        sys.exit("bench_rollout: --rounds, --batch, --steps and --threads must be at least 1")

    inputs = Inputs(scene, args.batch, args.steps)
    m = inputs.model
    datas = [mujoco.MjData(m) for _ in range(max(args.threads))]
    print(
        f"bench_rollout: {args.scene}, B={args.batch} x T={args.steps} x nu={m.nu}, "
        f"MuJoCo {mujoco.__version__} (mujoco) / {mujoco.mj_versionString()}, simloop {simloop.__version__}, "
        f"{args.rounds} rounds; load average {load()}"
    )
    batch_side = None
    if args.no_batch:
        print("mujoco.batch.Batch: left out (--no-batch)")
    elif mujoco_batch is None:
        print(f"mujoco.batch.Batch: not in mujoco {mujoco.__version__} (3.17 and later have it); skipped")
    else:
        batch_side = BatchSide(inputs)
        if not batch_side.check_start(inputs.rollout_state0):
            sys.exit("bench_rollout: Batch's initial rows differ from rollout's initial state")
    print(
        f"simloop state: {sum(n for _, n in inputs.layout)} values "
        f"({', '.join(f'{k} {n}' for k, n in inputs.layout if n)}); "
        f"rollout state: {inputs.rollout_state0.shape[1]} values (mjSTATE_FULLPHYSICS)"
        + (f"; Batch rows: {batch_side.state0.shape[1]} values (mjSTATE_INTEGRATION)" if batch_side else "")
    )

    print("same physics?")
    ok = all([check_same(inputs, datas, k, batch_side) for k in args.threads])
    if not ok:
        print("bench_rollout: the final states differ; timings would compare different work", file=sys.stderr)
        return 1

    calls = {"s": lambda k, keep: inputs.simloop(k, not keep), "r": lambda k, keep: inputs.rollout(k, datas, keep)}
    if batch_side is not None:
        calls["b"] = batch_side.run
    sides = list(calls)
    pairs = [("record", True), ("final", False)]
    if args.only:
        pairs = [p for p in pairs if p[0] == args.only]
    keys = [(name, keep, k) for name, keep in pairs for k in args.threads]
    times = {key: {side: [] for side in sides} for key in keys}
    for _name, keep, k in keys:  # one untimed call of each first: thread pools, page faults, caches
        for side in sides:
            calls[side](k, keep)
    for round_ in range(args.rounds):
        order = sides[round_ % len(sides) :] + sides[: round_ % len(sides)]
        for key in keys:
            name, keep, k = key
            for side in order:
                times[key][side].append(timed(lambda side=side, k=k, keep=keep: calls[side](k, keep)))

    total = args.batch * args.steps
    us = 1e6 / total
    print(
        f"medians over {args.rounds} rounds, per step in us ({total} steps a call), wall and CPU; "
        f"ratios = medians of per-round simloop / rollout (s/r) and simloop / Batch (s/b); load average {load()}"
    )
    names = {"s": "simloop", "r": "rollout", "b": "Batch"}
    print(
        f"  {'call':<7} {'thr':>3} | "
        + " | ".join(f"{names[side]:>7} wall {'cpu':>7}" for side in sides)
        + " | "
        + " | ".join(f"s/{side} wall {'cpu':>6}" for side in sides[1:])
    )
    worst = 0.0
    for key in keys:
        name, keep, k = key
        t = times[key]
        med = lambda xs, i: statistics.median(x[i] for x in xs) * us  # noqa: E731
        ratio = lambda other, i, t=t: statistics.median(a[i] / b[i] for a, b in zip(t["s"], t[other]))  # noqa: E731
        worst = max(worst, ratio("r", 1))
        print(
            f"  {name:<7} {k:>3} | "
            + " | ".join(f"{med(t[side], 0):12.2f} {med(t[side], 1):7.2f}" for side in sides)
            + " | "
            + " | ".join(f"{ratio(side, 0):8.4f} {ratio(side, 1):6.4f}" for side in sides[1:])
        )
        if args.verbose:
            print("          rusage (user + sys) per step: " + " ".join(f"{med(t[x], 2):.2f}" for x in sides))
            for side in sides[1:]:
                print(
                    f"          s/{side} CPU by round: "
                    + " ".join(f"{a[1] / b[1]:.3f}" for a, b in zip(t["s"], t[side]))
                )
    print(f"worst CPU ratio against rollout {worst:.4f} (target <= {TARGET}); load average {load()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
