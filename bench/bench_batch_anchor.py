#!/usr/bin/env python3
"""mujoco.batch.Batch beside simloop and mujoco.rollout: bench_rollout.py's third side, and peak memory.

`mujoco.batch` (in the mujoco wheels since 3.17; 4.0.0 here) steps nsim
simulations of one model on nthread threads, the caller's included. Each
simulation is one mjSTATE_INTEGRATION row of `Batch.state` (time, qpos, qvel,
act, qacc_warmstart, ctrl, applied forces, mocap, ...); a call loads the row
into an MjData, runs it and saves the row back, bit-identical to a loop over
one MjData per simulation at any thread count. `Batch.rollout(nstep, control,
record=...)` is mujoco.rollout's open loop on those rows: before substep k it
writes control[:, k] into the mjSTATE_CTRL part, then calls mj_step, and it
records the items of `record` after each substep (nothing with record=()).
The rows then hold each simulation's final state. By default one MjData
serves the simulations a thread runs (persistent=False), so its memory scales
with threads, not simulations.

bench_rollout.py times it beside the other two (`BatchSide`): one Batch per
thread count, made once, as rollout's MjData are; a call writes the reset
pose into the rows and rolls out the same controls, recording
(mjSTATE_FULLPHYSICS, sensordata), rollout's default outputs, or nothing.

Run on its own, this script measures each side's peak memory growth for the
metrics-only case, each in a fresh child process: the child builds the
inputs (scene, controls, initial states), resets its peak (VmHWM, through
/proc/self/clear_refs), makes what the side needs (rollout's MjData, the
Batch) and runs one call that keeps nothing per step; it prints VmHWM after
the call less VmRSS before it.

    .venv-pypi/bin/python bench/bench_batch_anchor.py [--batch 4096] [--steps 100]
        [--threads 1 2] [--scene pusht|chapter|FILE] [--repeat 3]
"""

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import statistics
import subprocess
import sys
from pathlib import Path

from batch_side import BatchSide, mujoco_batch

HERE = Path(__file__).resolve().parent


def _status_kib(field):
    with open("/proc/self/status") as f:
        return next(int(line.split()[1]) for line in f if line.startswith(field + ":"))


def child(side, threads, scene, batch, steps):
    """One metrics-only call of one side; prints MiB: VmRSS before, VmHWM after, whether the peak was reset."""
    import mujoco
    from bench_rollout import Inputs, scene_path  # (bench_rollout imports simloop: only in the child)

    inputs = Inputs(scene_path(scene), batch, steps)
    datas = None
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")  # VmHWM := VmRSS
        reset = 1
    except OSError:
        reset = 0
    before = _status_kib("VmRSS")
    if side == "simloop":
        out = inputs.simloop(threads, metrics_only=True)
    elif side == "rollout":
        datas = [mujoco.MjData(inputs.model) for _ in range(threads)]
        out = inputs.rollout(threads, datas, keep=False)
    else:
        out = BatchSide(inputs).run(threads, keep=False)
    peak = _status_kib("VmHWM")
    del out, datas
    print(f"{before / 1024:.2f} {peak / 1024:.2f} {reset}")


def measure(side, threads, scene, batch, steps):
    command = [sys.executable, __file__, "--child", side, str(threads), str(scene), str(batch), str(steps)]
    out = subprocess.run(command, capture_output=True, text=True, cwd=HERE)
    if out.returncode != 0:
        sys.exit(f"bench_batch_anchor: {side} failed: {out.stderr.strip()[-2000:]}")
    before, peak, reset = out.stdout.split()
    return float(before), float(peak), reset == "1"


def main():
    if len(sys.argv) > 1 and sys.argv[1] == "--child":
        side, threads, scene, batch, steps = sys.argv[2:7]
        sys.path.insert(0, str(HERE))
        child(side, int(threads), scene, int(batch), int(steps))
        return 0
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--batch", type=int, default=4096, help="runs B (default 4096)")
    parser.add_argument("--steps", type=int, default=100, help="steps T per run (default 100)")
    parser.add_argument("--threads", type=int, nargs="+", default=[1, 2], help="thread counts (default 1 2)")
    parser.add_argument("--scene", nargs="+", default=["pusht", "chapter"], help="pusht, chapter or MJCF files")
    parser.add_argument("--repeat", type=int, default=3, help="fresh processes per figure (medians printed)")
    args = parser.parse_args()
    sides = ["simloop", "rollout"] + (["batch"] if mujoco_batch is not None else [])
    if mujoco_batch is None:
        print("bench_batch_anchor: this mujoco has no mujoco.batch; measuring simloop and rollout only")
    print(
        f"peak memory growth of one metrics-only call (VmHWM after - VmRSS before, MiB), "
        f"B={args.batch} x T={args.steps}, medians of {args.repeat} fresh processes; "
        f"load average {' '.join(f'{x:.2f}' for x in os.getloadavg())}"
    )
    print(f"  {'scene':<8} {'thr':>3} " + " ".join(f"{s:>18}" for s in sides) + "   (growth; RSS before)")
    all_reset = True
    for scene in args.scene:
        for k in args.threads:
            cells = []
            for side in sides:
                samples = [measure(side, k, scene, args.batch, args.steps) for _ in range(args.repeat)]
                all_reset = all_reset and all(s[2] for s in samples)
                growth = statistics.median(s[1] - s[0] for s in samples)
                before = statistics.median(s[0] for s in samples)
                cells.append(f"{growth:8.2f} ({before:6.1f})")
            print(f"  {Path(scene).stem:<8} {k:>3} " + " ".join(f"{c:>18}" for c in cells))
    if not all_reset:
        print("  (the peak could not be reset here: growth counts from the setup's own peak)")
    print(f"load average {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
