"""`python -m simloop` at its edges: interrupted, a lost report, a failing plot.

Each failure is one line on stderr and a non-zero exit, and leaves the earlier
outputs as they were (or, after they were written, says so).
"""

import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest
import simloop.__main__ as command
from conftest import snapshot


@pytest.fixture
def earlier_outputs(tmp_path):
    """An output directory holding a finished smoke run's files."""
    out = tmp_path / "out"
    assert command.main(["--smoke", "--no-rerun", "--out", str(out)]) == 0
    return out


def test_ctrl_c_is_one_line_and_exit_130_and_keeps_the_earlier_outputs(earlier_outputs, monkeypatch, capsys):
    before = snapshot(earlier_outputs)
    capsys.readouterr()

    def interrupted_run(*args, **kwargs):
        raise KeyboardInterrupt

    # The progress bar begins the run: a Ctrl-C there stands for one during it.
    monkeypatch.setattr(command, "progress_bar", interrupted_run)
    try:
        code = command.main(["--seed", "3", "--no-rerun", "--out", str(earlier_outputs)])
    except KeyboardInterrupt:
        pytest.fail("KeyboardInterrupt escaped the command (a traceback for the user)")
    assert code == 130
    err = capsys.readouterr().err
    assert err == "sim-loop: interrupted (SIGINT); the earlier outputs were left as they were\n"
    assert snapshot(earlier_outputs) == before


# The long call a signal interrupts, stood in for by a sleep (which Python
# interrupts to run its signal handlers) where the progress bar begins
# the run: what is tested is the command's handling, not how promptly the
# bindings notice a signal.
SLEEPING_COMMAND = textwrap.dedent("""
    import sys, time
    import simloop.__main__
    simloop.__main__.progress_bar = lambda *args, **kwargs: time.sleep(60)
    sys.exit(simloop.__main__.main(sys.argv[1:]))
""")


def _as_from_a_terminal():
    """SIGINT, SIGQUIT and SIGHUP not ignored in the child, even when the tests
    run as a background job (which ignores the first two) or under nohup (the
    third), which the command would then leave ignored."""
    for sig in (signal.SIGINT, signal.SIGQUIT, signal.SIGHUP):
        signal.signal(sig, signal.SIG_DFL)


@pytest.mark.parametrize(
    "sig", [signal.SIGINT, signal.SIGTERM, signal.SIGHUP, signal.SIGQUIT, signal.SIGUSR1, signal.SIGALRM]
)
def test_a_signal_stops_the_command_at_once_with_one_line(earlier_outputs, sig):
    code = 128 + sig
    before = snapshot(earlier_outputs)
    with subprocess.Popen(
        [sys.executable, "-c", SLEEPING_COMMAND, "--no-rerun", "--out", str(earlier_outputs)],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=_as_from_a_terminal,
    ) as proc:
        try:
            # The banner says the command got as far as the run.
            assert proc.stdout.readline().startswith("ch0.1-sim-loop | tier: cpu")
            time.sleep(0.2)
            proc.send_signal(sig)
            sent = time.perf_counter()
            proc.wait(timeout=10)
            took = time.perf_counter() - sent
        finally:
            proc.kill()
            proc.wait()
        err = proc.stderr.read()
    assert proc.returncode == code, err
    assert took < 0.2
    assert err == f"sim-loop: interrupted ({sig.name}); the earlier outputs were left as they were\n"
    assert snapshot(earlier_outputs) == before


@pytest.mark.parametrize("args", [["--smoke", "--no-rerun"], ["--help"], ["--version"]])
def test_a_full_or_closed_stdout_exits_1_with_one_line(tmp_path, args):
    cmd = [sys.executable, "-m", "simloop", *args]
    if args[0] not in ("--help", "--version"):
        cmd += ["--out", str(tmp_path / "out")]
    for stdout in ("/dev/full", None):  # None: started with stdout closed
        with open(stdout or os.devnull, "w") as sink:
            proc = subprocess.run(
                cmd,
                cwd=tmp_path,
                stdin=subprocess.DEVNULL,
                stdout=sink,
                stderr=subprocess.PIPE,
                text=True,
                timeout=120,
                preexec_fn=None if stdout else (lambda: os.close(1)),
            )
        what = f"{args} > {stdout or 'closed'}"
        assert proc.returncode == 1, what
        assert proc.stderr.startswith("sim-loop: ") and "standard output" in proc.stderr, what
        assert proc.stderr.count("\n") == 1, proc.stderr
    assert not (tmp_path / "out").exists(), "nothing is written when the report cannot be"


def test_a_plot_failure_is_one_line_after_the_outputs(tmp_path):
    # A matplotlib that cannot be imported, ahead of any real one.
    fake = tmp_path / "fake"
    (fake / "matplotlib").mkdir(parents=True)
    (fake / "matplotlib" / "__init__.py").write_text("raise ImportError(\"No module named 'matplotlib' (test)\")\n")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(fake), os.environ.get("PYTHONPATH", "")]))
    run = subprocess.run(
        [sys.executable, "-m", "simloop", "--smoke", "--no-rerun", "--plot", "--out", "out"],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        stdin=subprocess.DEVNULL,
        timeout=120,
    )
    assert run.returncode == 1
    assert run.stderr == (
        "sim-loop: No module named 'matplotlib' (test) (metrics.json and trajectory.csv were written)\n"
    )
    assert (tmp_path / "out" / "metrics.json").is_file() and (tmp_path / "out" / "trajectory.csv").is_file()
    plot = subprocess.run(
        [sys.executable, "-m", "simloop", "plot", "trajectory", "--out", "out"],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        stdin=subprocess.DEVNULL,
        timeout=120,
    )
    assert plot.returncode == 1
    assert plot.stderr == "sim-loop: plot: out/trajectory.csv: No module named 'matplotlib' (test)\n"
