"""Shared helpers: the two commands, run as a user runs them."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def sim_loop_exe() -> Path:
    """The C++ command, from SIMLOOP_SIM_LOOP or the README's build/ folder."""
    exe = Path(os.environ.get("SIMLOOP_SIM_LOOP", ROOT / "build" / "sim_loop"))
    if not exe.exists():
        pytest.fail(f"sim_loop not found at {exe}: build it (scripts/test.sh does) or set SIMLOOP_SIM_LOOP")
    return exe


def run_command(args, cwd: Path, python: bool = True) -> subprocess.CompletedProcess:
    """`python -m simloop ARGS` (or sim_loop ARGS) in cwd, stdin closed, with a time limit."""
    cmd = [sys.executable, "-m", "simloop", *args] if python else [str(sim_loop_exe()), *args]
    return subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, stdin=subprocess.DEVNULL, timeout=120)


def without_wall_clock(stdout: str) -> str:
    return "".join(line for line in stdout.splitlines(keepends=True) if not line.startswith("wall-clock:"))


def snapshot(directory: Path) -> dict:
    """Every file under directory: bytes and modification time."""
    return {p: (p.read_bytes(), p.stat().st_mtime_ns) for p in sorted(directory.rglob("*")) if p.is_file()}


def run_python(code: str, timeout: float = 120) -> subprocess.CompletedProcess:
    """`python -c CODE` (dedented) in a child process, so a crash is a result, not the end of pytest."""
    return subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True,
                          stdin=subprocess.DEVNULL, timeout=timeout)
