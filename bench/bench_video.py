"""`python -m simloop --video`: frames drawn per second, this build against another simloop install, side by side.

    .venv/bin/python bench/bench_video.py --before OTHER/.venv/bin/python [--rounds 5] [--steps 2000]

Each round runs the default run with `--video v.png` (an animated PNG: no ffmpeg needed) once with each Python,
in turn (interleaved, so the machine's load falls on both alike), each in a fresh folder, and counts the frames
the file holds. It prints the medians of wall-clock and CPU time (the child's user + system) per frame, the
ratio of frames per second (after / before) and the load average. The whole command is timed, start-up
included (the same for both); --steps 2000 draws 101 frames.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import struct
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def apng_frames(path: Path) -> int:
    data = path.read_bytes()
    at = 8
    while at < len(data):
        size, kind = struct.unpack(">I4s", data[at : at + 8])
        if kind == b"acTL":
            return struct.unpack(">I", data[at + 8 : at + 12])[0]
        at += 12 + size
    raise ValueError(f"{path}: no acTL chunk")


def one_run(python: str, steps: int) -> tuple[float, float, int]:
    """(wall s, CPU s, frames) of one video run."""
    with tempfile.TemporaryDirectory() as folder:
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        started = time.perf_counter()
        subprocess.run(
            [python, "-m", "simloop", "--steps", str(steps), "--no-rerun", "--video", "v.png", "--out", "out"],
            cwd=folder,
            check=True,
            capture_output=True,
            stdin=subprocess.DEVNULL,
        )
        wall = time.perf_counter() - started
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
        return wall, cpu, apng_frames(Path(folder) / "v.png")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--before", required=True, help="the Python of the simloop install to compare against")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--steps", type=int, default=2000)
    args = parser.parse_args()
    pythons = {"before": args.before, "after": sys.executable}
    runs: dict[str, list[tuple[float, float, int]]] = {label: [] for label in pythons}
    print(f"load average at start: {os.getloadavg()[0]:.2f}")
    for _ in range(args.rounds):
        for label, python in pythons.items():
            runs[label].append(one_run(python, args.steps))
    fps = {}
    for label, results in runs.items():
        frames = results[0][2]
        wall = statistics.median(r[0] for r in results)
        cpu = statistics.median(r[1] for r in results)
        fps[label] = frames / wall
        print(
            f"{label:6s} {frames} frames: wall {wall:.2f} s ({wall / frames * 1e3:.1f} ms a frame, "
            f"{fps[label]:.1f} frames/s), CPU {cpu:.2f} s ({cpu / frames * 1e3:.1f} ms a frame)"
        )
    print(f"frames per second, after / before: {fps['after'] / fps['before']:.2f}")
    print(f"load average at end: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
