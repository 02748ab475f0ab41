"""Ctrl-C stops the long calls promptly, and progress= watches them."""

import select
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest
import simloop

# Each would run for minutes (or, the sweep, seconds) if not stopped, in
# little memory (record_every keeps the trajectories short).
LONG_CALLS = {
    "run": "simloop.run(steps=10**8, record_every=10**6)",
    "run_batch": "simloop.run_batch(seeds=range(4), steps=10**8, record_every=10**6, threads=2)",
    "Sim.step": "sim.step(10**8)",
    "sweep": "simloop.sweep(timesteps=[0.02, 0.04], duration=10000.0, threads=2)",
    "run_scenario": "simloop.run_scenario(simloop.Scenario.chapter(), steps=10**8, record_every=10**6)",
    "run_scenario_batch": "simloop.run_scenario_batch(simloop.Scenario.chapter(), seeds=range(4), steps=10**8, "
    "record_every=10**6, threads=2)",
}

# The child: signals it is about to call, calls, and reports when the
# KeyboardInterrupt reached Python, and that the interpreter is still fine.
CHILD = """
import sys, time
import simloop
sim = simloop.Sim()
simloop.run(steps=10)  # the scene compiled, everything imported
print("calling", flush=True)
try:
    {call}
except KeyboardInterrupt:
    raised = time.monotonic()
    print("KeyboardInterrupt", repr(raised), sim.steps_taken, simloop.run(steps=10).rows, flush=True)
    sys.exit(0)
print("finished without an interrupt", flush=True)
sys.exit(3)
"""

# The budget is 0.2 s; the machines that run the tests are shared,
# so the test allows more for the process to exit, and reports the latency.
RAISE_BUDGET_S = 0.2
EXIT_BUDGET_S = 1.0


def interrupt(code: str):
    """Runs CODE, which prints "calling" before its long call; sends SIGINT
    0.5 s later. Returns the words of the line the child printed next, the
    seconds from the signal to that KeyboardInterrupt and to the exit."""
    with subprocess.Popen(
        [sys.executable, "-c", textwrap.dedent(code)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    ) as child:
        try:
            assert child.stdout.readline() == "calling\n"
            time.sleep(0.5)
            sent = time.monotonic()
            child.send_signal(signal.SIGINT)
            ready, _, _ = select.select([child.stdout], [], [], 10)
            line = child.stdout.readline() if ready else "(nothing within 10 s)"
            child.wait(timeout=10)
            exited = time.monotonic()
        finally:
            if child.poll() is None:
                child.kill()
            _, stderr = child.communicate()
    words = line.split()
    assert words[:1] == ["KeyboardInterrupt"], f"{line!r} {stderr[-2000:]}"
    assert child.returncode == 0
    return words, float(words[1]) - sent, exited - sent


@pytest.mark.parametrize("name", list(LONG_CALLS))
def test_ctrl_c_raises_keyboard_interrupt_promptly(name):
    words, latency, exit_after = interrupt(CHILD.format(call=LONG_CALLS[name]))
    print(f"{name}: KeyboardInterrupt {latency * 1e3:.1f} ms after SIGINT, exit after {exit_after * 1e3:.1f} ms")
    assert latency < RAISE_BUDGET_S
    assert exit_after < EXIT_BUDGET_S
    if name == "Sim.step":
        assert 0 < int(words[2]) < 10**8  # the steps taken stay taken
    assert words[3] == "11"  # and the next call works


def test_progress_reports_to_the_end():
    calls = []
    result = simloop.run(steps=60_000, record_every=1000, progress=lambda done, total: calls.append((done, total)))
    assert result.rows == 61
    assert calls[-1] == (60_000, 60_000)
    assert all(total == 60_000 for _, total in calls)
    assert [done for done, _ in calls] == sorted(done for done, _ in calls)
    batch = []
    simloop.run_batch(seeds=[0, 1, 2], steps=500, threads=2, progress=lambda d, t: batch.append((d, t)))
    assert batch[-1] == (1500, 1500)
    sim = simloop.Sim()
    stepped = []
    sim.step(100, progress=lambda d, t: stepped.append((d, t)))
    assert stepped[-1] == (100, 100)
    swept = []
    simloop.sweep(timesteps=[0.25, 0.125], duration=1.0, threads=1, progress=lambda d, t: swept.append((d, t)))
    assert swept[-1] == (12, 12)  # 4 + 8 steps


class Stop(Exception):
    pass


@pytest.mark.parametrize(
    "call",
    [
        lambda progress: simloop.run(steps=10**8, record_every=10**6, progress=progress),
        lambda progress: simloop.run_batch(seeds=[0, 1], steps=10**8, record_every=10**6, threads=2, progress=progress),
        lambda progress: simloop.Sim().step(10**8, progress=progress),
        lambda progress: simloop.run_scenario_batch(
            simloop.Scenario.chapter(), seeds=[0, 1], steps=10**8, record_every=10**6, threads=2, progress=progress
        ),
    ],
    ids=["run", "run_batch", "Sim.step", "run_scenario_batch"],
)
def test_an_exception_from_progress_stops_the_work_and_reaches_the_caller(call):
    def progress(done, total):
        if done > 0:
            raise Stop(f"stopped at {done} of {total}")

    started = time.monotonic()
    with pytest.raises(Stop, match="stopped at"):
        call(progress)
    assert time.monotonic() - started < 5  # not the 10**8 steps


def test_ctrl_c_reaches_a_thread_waiting_for_a_sim_another_thread_steps():
    # A daemon thread steps the Sim for minutes; the main thread asks it the
    # time, waits for its turn, and must still hear Ctrl-C.
    code = """
        import os, sys, threading, time
        import simloop
        sim = simloop.Sim()
        threading.Thread(target=sim.step, args=(10**8,), daemon=True).start()
        time.sleep(0.1)
        print("calling", flush=True)
        try:
            sim.time
        except KeyboardInterrupt:
            print("KeyboardInterrupt", repr(time.monotonic()), flush=True)
            os._exit(0)  # the daemon thread is still stepping
        print("finished without an interrupt", flush=True)
        os._exit(3)
    """
    _, latency, _ = interrupt(code)
    print(f"waiting for a Sim: KeyboardInterrupt {latency * 1e3:.1f} ms after SIGINT")
    assert latency < RAISE_BUDGET_S


# Calls a policy (or a vector environment) makes long, each with a daemon
# thread present that runs Python code now and then (a logger, a watchdog):
# Ctrl-C still acts within the budget, whatever the thread count.
POLICY_CALLS = {
    "run_scenario policy": "simloop.run_scenario(simloop.Scenario.chapter(), steps=10**8, record_every=10**6, "
    "policy=lambda obs: [1.0], control_every=10)",
    "policy batch, 1 thread": "simloop.run_scenario_batch(simloop.Scenario.chapter(), seeds=range(2), steps=10**8, "
    "record_every=10**6, threads=1, policy=lambda obs: [1.0], control_every=10)",
    "policy batch, 2 threads": "simloop.run_scenario_batch(simloop.Scenario.chapter(), seeds=range(2), "
    "steps=10**8, record_every=10**6, threads=2, policy=lambda obs: [1.0], "
    "control_every=10)",
    "vector env, 2 threads": "env = simloop.gym.ScenarioVectorEnv(simloop.Scenario.chapter(), num_envs=4, "
    "threads=2, control_every=10**7, steps=10**8); env.reset(seed=0); "
    "env.step(__import__('numpy').ones((4, 1)))",
}
DAEMON = """
import threading
def _busy():
    while True:
        sum(range(1000))
        time.sleep(0.001)
threading.Thread(target=_busy, daemon=True).start()
"""


@pytest.mark.parametrize("daemon", [False, True], ids=["alone", "with a daemon thread"])
@pytest.mark.parametrize("name", list(POLICY_CALLS))
def test_ctrl_c_stops_policy_batches_and_vector_envs_promptly(name, daemon):
    call = POLICY_CALLS[name]
    if name.startswith("vector env"):
        call = "import simloop.gym; " + call
    code = CHILD.replace("import simloop\n", "import simloop\n" + (DAEMON if daemon else ""), 1)
    words, latency, exit_after = interrupt(
        code.format(call=call).replace("sys.exit(0)", "os._exit(0)").replace("import sys, time", "import os, sys, time")
    )
    print(
        f"{name} ({'with' if daemon else 'without'} a daemon thread): KeyboardInterrupt {latency * 1e3:.1f} ms "
        f"after SIGINT"
    )
    assert latency < RAISE_BUDGET_S
    assert exit_after < EXIT_BUDGET_S


@pytest.mark.parametrize("delay", [0.0, 0.01, 0.03])
def test_ctrl_c_while_the_command_loads_its_modules_is_one_line_not_a_traceback(tmp_path, delay):
    # 7 of 20 Ctrl-Cs in the first ~0.2 s printed a KeyboardInterrupt traceback. Sent once the package is
    # importing (its extension module mapped), and a little later, while the command's modules load.
    child = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "simloop",
            "--steps",
            "100000000",
            "--record-every",
            "1000000",
            "--no-rerun",
            "--out",
            "out",
        ],
        cwd=tmp_path,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL) and None,
    )
    deadline = time.monotonic() + 60
    while "simloop/_core" not in Path(f"/proc/{child.pid}/maps").read_text():
        assert child.poll() is None and time.monotonic() < deadline
        time.sleep(0.001)
    time.sleep(delay)
    child.send_signal(signal.SIGINT)
    _, err = child.communicate(timeout=60)
    assert child.returncode == 130, err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    assert err.startswith("sim-loop: interrupted (SIGINT)"), err
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())


# A signal that a library turns into an error of its own: numpy's import, hit by
# SIGUSR1 inside, said "ImportError: ... PyCapsule_Import could not import module
# datetime" and the command exited 1 (once, on a fresh Debian). Here the drawing
# is made to do the same.
SWALLOWED = """
import os, signal, sys, time
import simloop.recording
from simloop.__main__ import main

class Swallowing:
    def __init__(self, *args, **kwargs):
        try:
            os.kill(os.getpid(), getattr(signal, sys.argv[1]))
            time.sleep(5)
        except BaseException:
            raise ImportError("PyCapsule_Import could not import module datetime") from None

simloop.recording.Recording = Swallowing
sys.exit(main(["--steps", "50", "--out", "out"]))
"""


@pytest.mark.parametrize("name", ["SIGUSR1", "SIGINT", "SIGTERM"])
def test_a_signal_a_library_turned_into_its_own_error_is_reported_as_the_signal(tmp_path, name):
    child = subprocess.run(
        [sys.executable, "-c", SWALLOWED, name], cwd=tmp_path, capture_output=True, text=True, timeout=60
    )
    assert child.returncode == 128 + getattr(signal, name), child.stderr
    assert child.stderr == f"sim-loop: interrupted ({name}); the earlier outputs were left as they were\n"
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())
