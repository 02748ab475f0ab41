"""Shared helpers: the two commands, run as a user runs them."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

# triton (torch's compiler, which simloop.sb3 loads first thing) before any
# test renders: loaded after Mesa's software driver has drawn, it crashes the
# process in its own LLVM's initializers (after Gymnasium's renderer too;
# docs/training.md). Where it is installed.
try:
    import triton  # noqa: F401
except ImportError:
    pass


# The signal tests stand for a user at a terminal, whose Ctrl-C reaches the
# command. A launcher may have left SIGINT, SIGQUIT or SIGHUP ignored (a
# script's background job, nohup), and a child inherits an ignored signal,
# so the commands under test would rightly ignore it too: the suite puts the
# defaults back for its children (and Python's KeyboardInterrupt for itself).
for _number, _handler in (
    (signal.SIGINT, signal.default_int_handler),
    (signal.SIGQUIT, signal.SIG_DFL),
    (signal.SIGHUP, signal.SIG_DFL),
):
    if signal.getsignal(_number) == signal.SIG_IGN:
        signal.signal(_number, _handler)

# A test that fails inside `with subprocess.Popen(...)` (an assertion, a
# communicate timeout) would wait in Popen.__exit__ for a child that may run
# for minutes: the child is killed first, so a failure stays a failure, not a hang.
_popen_exit = subprocess.Popen.__exit__


def _exit_killing_on_failure(self, exc_type, value, traceback):
    if exc_type is not None and self.poll() is None:
        self.kill()
    return _popen_exit(self, exc_type, value, traceback)


subprocess.Popen.__exit__ = _exit_killing_on_failure


def _why_no_worker_processes() -> str:
    """'' if this machine lets Python's multiprocessing make the POSIX
    semaphores every worker process (ProcessPoolExecutor, a Dask nanny)
    needs; else why not. A chroot that does not mount /dev/shm, for one,
    refuses them to every user but root: such a machine cannot run worker
    processes at all, so the tests that start them are skipped, saying so."""
    import multiprocessing

    try:
        multiprocessing.get_context("spawn").Lock()
    except OSError as e:
        return f"this machine cannot make the semaphores worker processes need ({e}; is /dev/shm mounted and writable?)"
    return ""


NO_WORKER_PROCESSES = _why_no_worker_processes()
# For tests that start worker processes.
needs_worker_processes = pytest.mark.skipif(bool(NO_WORKER_PROCESSES), reason=NO_WORKER_PROCESSES)

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


def batch(args, cwd: Path, timeout: float = 300, **kwargs) -> subprocess.CompletedProcess:
    """`python -m simloop batch ARGS` in cwd, stdin closed, with a time limit (kwargs: subprocess.run's, env=...)."""
    return subprocess.run(
        [sys.executable, "-m", "simloop", "batch", *args],
        cwd=cwd,
        capture_output=True,
        text=True,
        stdin=subprocess.DEVNULL,
        timeout=timeout,
        **kwargs,
    )


def without_wall_clock(stdout: str) -> str:
    return "".join(line for line in stdout.splitlines(keepends=True) if not line.startswith("wall-clock:"))


def snapshot(directory: Path) -> dict:
    """Every file under directory: bytes and modification time."""
    return {p: (p.read_bytes(), p.stat().st_mtime_ns) for p in sorted(directory.rglob("*")) if p.is_file()}


def run_python(code: str, timeout: float = 120) -> subprocess.CompletedProcess:
    """`python -c CODE` (dedented) in a child process, so a crash is a result, not the end of pytest."""
    return subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)],
        capture_output=True,
        text=True,
        stdin=subprocess.DEVNULL,
        timeout=timeout,
    )
