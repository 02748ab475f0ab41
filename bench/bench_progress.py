"""What the progress bar costs: the same long run of each command with stderr
on a pseudo-terminal (the bar drawn) and on /dev/null (no bar; for sim_loop no
poll at all), alternated round by round; medians of wall-clock and CPU time.

    python3 bench/bench_progress.py [rounds] [steps]      (default 9 rounds of 2,000,000 steps)

Runs build/sim_loop and .venv/bin/python -m simloop --no-rerun.
"""

import os
import pty
import resource
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def timed(cmd, cwd, on_terminal):
    env = dict(os.environ, TERM="xterm")
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    started = time.perf_counter()
    if on_terminal:
        master, slave = pty.openpty()
        proc = subprocess.Popen(
            cmd, cwd=cwd, env=env, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=slave
        )
        os.close(slave)
        drawn = bytearray()

        def read():
            while True:
                try:
                    chunk = os.read(master, 4096)
                except OSError:
                    return
                if not chunk:
                    return
                drawn.extend(chunk)

        reader = threading.Thread(target=read)
        reader.start()
        proc.wait()
        reader.join()
        os.close(master)
        assert drawn, "no bar was drawn"
    else:
        proc = subprocess.run(
            cmd, cwd=cwd, env=env, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
        )
    wall = time.perf_counter() - started
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    assert proc.returncode == 0
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main():
    rounds = int(sys.argv[1]) if len(sys.argv) > 1 else 9
    steps = sys.argv[2] if len(sys.argv) > 2 else "2000000"
    commands = {
        "sim_loop": [str(ROOT / "build" / "sim_loop")],
        "python -m simloop": [str(ROOT / ".venv" / "bin" / "python"), "-m", "simloop", "--no-rerun"],
    }
    with tempfile.TemporaryDirectory() as cwd:
        for name, cmd in commands.items():
            cmd = cmd + ["--steps", steps, "--record-every", "1000", "--out", "out"]
            times = {False: [], True: []}
            for _ in range(rounds):
                for on_terminal in (False, True):
                    times[on_terminal].append(timed(cmd, cwd, on_terminal))
            plain_wall = statistics.median(t[0] for t in times[False])
            bar_wall = statistics.median(t[0] for t in times[True])
            plain_cpu = statistics.median(t[1] for t in times[False])
            bar_cpu = statistics.median(t[1] for t in times[True])
            print(
                f"{name}, {steps} steps, median of {rounds}: "
                f"no terminal {plain_wall:.3f} s wall {plain_cpu:.3f} s CPU; "
                f"bar on a terminal {bar_wall:.3f} s wall {bar_cpu:.3f} s CPU; "
                f"bar / none: {bar_wall / plain_wall:.4f} wall, {bar_cpu / plain_cpu:.4f} CPU"
            )


if __name__ == "__main__":
    main()
