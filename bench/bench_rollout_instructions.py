#!/usr/bin/env python3
"""Instructions per run: simloop's metrics-only batch against mujoco.rollout, counted by callgrind.

On a shared machine the CPU-time ratios of bench_rollout.py wander by several
percent from one process to the next; instruction counts do not. This script
runs three processes under `valgrind --tool=callgrind`, each building
bench_rollout.py's inputs (the same scene, B x T controls, initial states):
one that stops there, one that then makes simloop's metrics-only call
(`run_scenario_batch(..., metrics_only=True)`: a table row per run) and one
that makes mujoco.rollout's call keeping nothing. A side's instructions are
its process's less the first's; printed per run, with the ratio simloop /
rollout (issue 36's target: <= 1.02). One thread each (callgrind serialises
threads anyway). Needs valgrind (apt-get install valgrind) and the PyPI
build (mujoco importable); about a minute per scene at the defaults.

    .venv-pypi/bin/python bench/bench_rollout_instructions.py [--scene pusht chapter] [--batch 512] [--steps 100]
"""

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent


def child(side: str, scene: str, batch: int, steps: int) -> None:
    sys.path.insert(0, str(HERE))
    import bench_rollout
    import mujoco

    inputs = bench_rollout.Inputs(bench_rollout.scene_path(scene), batch, steps)
    datas = [mujoco.MjData(inputs.model)]
    if side == "simloop":
        inputs.simloop(1, metrics_only=True)
    elif side == "rollout":
        inputs.rollout(1, datas, keep=False)


def instructions(side: str, scene: str, batch: int, steps: int) -> int:
    """The instructions of the process that runs `side` (not of the compile children MuJoCo's loads fork)."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "callgrind.out"
        command = ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}.%p"]
        command += [sys.executable, __file__, "--child", side, scene, str(batch), str(steps)]
        done = subprocess.run(command, capture_output=True, text=True, cwd=HERE)
        if done.returncode != 0:
            sys.exit(f"bench_rollout_instructions: {side} failed: {done.stderr.strip()[-2000:]}")
        pid = done.stderr.split("==")[1]  # valgrind's first line, ==PID==, is the process it started
        counts = dict(re.findall(r"==(\d+)== I\s+refs:\s+([\d,]+)", done.stderr))
        return int(counts[pid].replace(",", ""))


def main() -> int:
    if len(sys.argv) > 1 and sys.argv[1] == "--child":
        child(sys.argv[2], sys.argv[3], int(sys.argv[4]), int(sys.argv[5]))
        return 0
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--scene", nargs="+", default=["pusht", "chapter"])
    parser.add_argument("--batch", type=int, default=512)
    parser.add_argument("--steps", type=int, default=100)
    args = parser.parse_args()
    if not shutil.which("valgrind"):
        sys.exit("bench_rollout_instructions: valgrind is not installed (apt-get install valgrind)")
    print(f"instructions per run, B={args.batch} x T={args.steps}, 1 thread (callgrind); load {os.getloadavg()}")
    print(f"  {'scene':<8} {'simloop':>12} {'rollout':>12} {'ratio':>7}")
    for scene in args.scene:
        base = instructions("none", scene, args.batch, args.steps)
        ours = (instructions("simloop", scene, args.batch, args.steps) - base) / args.batch
        theirs = (instructions("rollout", scene, args.batch, args.steps) - base) / args.batch
        print(f"  {scene:<8} {ours:>12,.0f} {theirs:>12,.0f} {ours / theirs:>7.4f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
