"""python -m simloop streams the chapter's run (trajectory.csv and the
recording) as it steps: its peak memory does not grow with the run's length.
(bench/bench_rss.py measures it to 10^6 steps; this checks 10^5 against
2000.) Before streaming, 10^5 steps took 15 MiB more without the recording
and 92 MiB more with it."""

import re
import subprocess
import sys

import pytest

GROWTH_LIMIT_MIB = 10.0


def peak_mib(args, tmp_path) -> float:
    proc = subprocess.run(
        [sys.executable, "-m", "simloop", *args, "--out", str(tmp_path / "o")],
        capture_output=True,
        text=True,
        stdin=subprocess.DEVNULL,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    return float(re.search(r"peak memory: ([0-9.]+) MiB", proc.stdout.splitlines()[-1]).group(1))


@pytest.mark.parametrize("recording", [[], ["--no-rerun"]], ids=["recording", "no-rerun"])
def test_peak_memory_does_not_grow_with_the_steps(tmp_path, recording):
    short = peak_mib(["--steps", "2000", *recording], tmp_path)
    long = peak_mib(["--steps", "100000", *recording], tmp_path)
    print(f"peak memory: {short:.1f} MiB at 2000 steps, {long:.1f} MiB at 100000")
    assert long - short < GROWTH_LIMIT_MIB
