#!/usr/bin/env python3
"""ScenarioVectorEnv against EnvPool and mujoco.batch.Batch on Gymnasium's HalfCheetah.

The same task on three stacks, N envs stepped together, 5 physics steps per
env step (HalfCheetah's frame_skip), random actions in [-1, 1] drawn up front:

  simloop   ScenarioVectorEnv over Gymnasium's half_cheetah.xml (read from
            the installed gymnasium), every joint's position and velocity
            recorded (18 values), a @batched reward over them (forward
            progress minus 0.1 x |action|^2, HalfCheetah's), autoreset after
            1000 env steps, on `threads` C++ threads.
  EnvPool   envpool.make_gymnasium("HalfCheetah-v5", num_envs=N,
            batch_size=N, num_threads=threads): its own C++ env, reward and
            observation (17 values), and its own bundled MuJoCo, so its
            physics is not ours to compare bit for bit: reported, no target.
  Batch     mujoco.batch.Batch(model, N, nthread=threads, persistent=True):
            ctrl written, step(nstep=5), qpos and qvel copied out; the same
            libmujoco as simloop's on the PyPI build, no reward, no resets:
            the floor under a vector env.

Rounds interleave the stacks (the order rotates round by round); each round
is --calls env.step calls of each. Printed per env step: CPU time of the
process (every thread; time.process_time) and wall-clock time, medians over
rounds, and the medians of per-round ratios simloop / EnvPool and simloop /
Batch, in CPU and in wall-clock throughput (steps per second: above 1,
simloop steps more).

--load K starts K busy processes (a bare `while True` each) for the whole
run, as a busy machine's other work: with 2 threads on 2 cores and K = 2,
the wall-clock throughput then says how well each stack's threads get their
share. Their CPU is not the measured process's. The load average is printed
before and after.

    .venv-pypi/bin/python bench/bench_envpool.py [--envs 1,64] [--threads 1,2] [--rounds 15] [--calls 200] [--load 0]

--instructions counts instructions per env step instead, under valgrind's
callgrind (apt-get install valgrind), one thread, for each N in --envs:
what load does not move, where a CPU-time ratio cannot be trusted.

    .venv-pypi/bin/python bench/bench_envpool.py --instructions [--envs 1,64] [--calls 2000]

Needs the PyPI build (mujoco.batch comes with mujoco 3.17+); EnvPool where
`pip install envpool` works (skipped, with a line saying so, where not).
"""

import os

# numpy's OpenBLAS threads spin after a BLAS call, and the CPU time measured
# here is the whole process's: keep them out of it.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import importlib.util
import re
import statistics
import subprocess
import sys
import time
from pathlib import Path

import gymnasium
import mujoco
import numpy as np
import simloop
from bench_gym_env import quiet_mujoco  # (this folder: the script's own, first on sys.path)
from simloop.gym import ScenarioVectorEnv, batched

XML = Path(gymnasium.__file__).parent / "envs" / "mujoco" / "assets" / "half_cheetah.xml"
FRAME_SKIP = 5
EPISODE = 1000  # env steps, HalfCheetah's max_episode_steps


def mujoco_model() -> "mujoco.MjModel":
    """The XML through mujoco, its compiler's warnings kept from MuJoCo's default
    handler (bench_gym_env.quiet_mujoco: Gymnasium's XML uses the deprecated settotalmass)."""
    with quiet_mujoco():
        return mujoco.MjModel.from_xml_path(str(XML))


def simloop_env(n: int, threads: int):
    scenario = simloop.Scenario(
        str(XML), steps=10**9, record={"joints": "all", "bodies": [], "actuators": [], "contacts": False}
    )
    dt = simloop.Model.from_file(str(XML)).timestep * FRAME_SKIP

    @batched
    def reward(before, action, after):  # HalfCheetah's: forward speed less the control cost
        return (after[:, 0] - before[:, 0]) / dt - 0.1 * np.square(action).sum(axis=1)

    env = ScenarioVectorEnv(
        scenario, n, control_every=FRAME_SKIP, reward=reward, max_episode_steps=EPISODE, threads=threads
    )
    env.reset(seed=0)
    return env.step


def envpool_env(n: int, threads: int):
    try:
        import envpool
    except ImportError:
        return None
    env = envpool.make_gymnasium("HalfCheetah-v5", num_envs=n, batch_size=n, num_threads=threads, seed=0)
    env.reset()
    return env.step


def batch_env(n: int, threads: int):
    try:
        import mujoco.batch
    except ImportError:  # before mujoco 3.17
        return None
    batch = mujoco.batch.Batch(mujoco_model(), n, nthread=threads, persistent=True)
    ctrl, qpos, qvel = batch.bind("ctrl"), batch.bind("qpos"), batch.bind("qvel")

    def step(actions):
        ctrl[:] = actions
        batch.step(nstep=FRAME_SKIP)
        return np.concatenate([qpos[:, 1:], qvel], axis=1)

    return step


def timed(step, actions) -> tuple:
    wall, cpu = time.perf_counter(), time.process_time()
    for a in actions:
        step(a)
    return time.perf_counter() - wall, time.process_time() - cpu


def busy_processes(count: int) -> list:
    return [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(count)]


def compare(n: int, threads: int, rounds: int, calls: int) -> None:
    actions = np.random.default_rng(0).uniform(-1.0, 1.0, (calls, n, 6))
    makers = (("simloop", simloop_env), ("EnvPool", envpool_env), ("Batch", batch_env))
    stacks = {name: make(n, threads) for name, make in makers}
    for name in [k for k, v in stacks.items() if v is None]:
        print(f"  ({name} left out: not installed here)")
        del stacks[name]
    for step in stacks.values():
        timed(step, actions[: max(1, calls // 10)])  # warm up
    times = {name: [] for name in stacks}
    names = list(stacks)
    for r in range(rounds):
        for name in names[r % len(names) :] + names[: r % len(names)]:
            times[name].append(timed(stacks[name], actions))
    steps = calls * n
    print(f"  {n} envs, {threads} thread(s):")
    for name, t in times.items():
        cpu = statistics.median(x[1] for x in t) / steps * 1e6
        wall = statistics.median(x[0] for x in t) / steps * 1e6
        print(f"    {name:8s} {cpu:8.2f} us CPU, {wall:8.2f} us wall per env step")
    for other in names[1:]:
        cpu = statistics.median(a[1] / b[1] for a, b in zip(times["simloop"], times[other]))
        speed = statistics.median(b[0] / a[0] for a, b in zip(times["simloop"], times[other]))
        print(f"    simloop / {other}: {cpu:.3f} x the CPU per step; {speed:.3f} x the steps per second (wall)")


MAKERS = {"simloop": simloop_env, "EnvPool": envpool_env, "Batch": batch_env}


def instructions(name: str, n: int, calls: int) -> int:
    """The instructions (every thread's) of a process making `calls` step calls of `name`'s N envs, one thread."""
    command = ["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null", sys.executable, __file__]
    done = subprocess.run([*command, "--child", name, str(n), str(calls)], capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit(f"bench_envpool: {name} under callgrind failed: {done.stderr.strip()[-2000:]}")
    pid = done.stderr.split("==")[1]  # valgrind's first line, ==PID==, is the process it started
    counts = dict(re.findall(r"==(\d+)== I\s+refs:\s+([\d,]+)", done.stderr))
    return int(counts[pid].replace(",", ""))


def count_instructions(n: int, calls: int) -> None:
    """Instructions per env step: each stack's process with 2 x calls step calls less the one with calls, over
    calls x N (what building the env and importing cost drops out), on one thread; the ratios simloop / the others.
    Unlike CPU time, these do not move with the machine's load."""
    per_step = {}
    for name, make in MAKERS.items():
        if make is envpool_env and importlib.util.find_spec("envpool") is None:
            print(f"  ({name} left out: not installed here)")
            continue
        per_step[name] = (instructions(name, n, 2 * calls) - instructions(name, n, calls)) / (calls * n)
    print(f"  {n} envs, 1 thread, instructions per env step (callgrind, {calls} and {2 * calls} calls):")
    for name, count in per_step.items():
        ratio = "" if name == "simloop" else f"   simloop / {name}: {per_step['simloop'] / count:.3f}"
        print(f"    {name:8s} {count:10,.0f}{ratio}")


def child(name: str, n: int, calls: int) -> None:
    step = MAKERS[name](n, 1)
    for a in np.random.default_rng(0).uniform(-1.0, 1.0, (calls, n, 6)):
        step(a)


def main() -> int:
    if len(sys.argv) > 1 and sys.argv[1] == "--child":
        child(sys.argv[2], int(sys.argv[3]), int(sys.argv[4]))
        return 0
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--envs", default="1,64")
    parser.add_argument("--threads", default="1,2")
    parser.add_argument("--rounds", type=int, default=15)
    parser.add_argument("--calls", type=int, default=200)
    parser.add_argument("--load", type=int, default=0, help="busy processes to start beside the benchmark")
    parser.add_argument("--instructions", action="store_true", help="count instructions instead (callgrind)")
    args = parser.parse_args()
    if args.instructions:
        for n in (int(x) for x in args.envs.split(",")):
            count_instructions(n, max(1, args.calls // n))
        return 0
    print(
        f"bench_envpool: HalfCheetah, frame_skip {FRAME_SKIP}, MuJoCo {mujoco.__version__}, simloop "
        f"{simloop.__version__}, {args.rounds} rounds of {args.calls} calls, {args.load} busy processes; "
        f"load average {' '.join(f'{x:.2f}' for x in os.getloadavg())}"
    )
    busy = busy_processes(args.load)
    try:
        for n in (int(x) for x in args.envs.split(",")):
            for threads in (int(x) for x in args.threads.split(",")):
                compare(n, threads, args.rounds, args.calls)
    finally:
        for p in busy:
            p.kill()
            p.wait()
    print(f"load average after: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
