"""Every terminating signal, at random moments, in both commands: the run
ends as Ctrl-C ends it (exit 128 + the signal, one line), and the folder
holds all the old outputs or all the new ones, never a temporary file."""

import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from conftest import sim_loop_exe

OUTPUTS = {"metrics.json", "trajectory.csv"}
# sim_loop's: Python ignores SIGPIPE (a closed pipe is an EPIPE error there).
SIGNALS = [signal.SIGHUP, signal.SIGINT, signal.SIGQUIT, signal.SIGTERM, signal.SIGPIPE, signal.SIGUSR1]
MOMENTS = 3  # per signal and command: a handful, seeded


def command(which: str):
    if which == "sim_loop":
        return [str(sim_loop_exe())]
    return [sys.executable, "-m", "simloop"]  # with its recording


def _defaults():
    """Every signal at its default action in the child, as a terminal's shell
    starts it (a background job's SIGINT and SIGQUIT are ignored otherwise)."""
    for sig in SIGNALS:
        signal.signal(sig, signal.SIG_DFL)


def state(out: Path) -> tuple:
    """What a test compares: the pair's bytes and the recording's inode (its
    bytes differ between identical runs: rerun stamps time-based ids)."""
    names = {p.name for p in out.iterdir()}
    rrd = out / "sim_loop.rrd"
    return (
        names,
        (out / "metrics.json").read_bytes(),
        (out / "trajectory.csv").read_bytes(),
        rrd.stat().st_ino if rrd.exists() else None,
    )


@pytest.mark.parametrize("which", ["sim_loop", "python"])
def test_each_signal_at_random_moments_leaves_all_old_or_all_new(tmp_path, which):
    args = ["--steps", "20000"]
    new, old = tmp_path / "new", tmp_path / "old"
    started = time.perf_counter()
    assert (
        subprocess.run(
            command(which) + args + ["--seed", "2", "--out", str(new)], capture_output=True, timeout=120
        ).returncode
        == 0
    )
    seconds = time.perf_counter() - started
    assert (
        subprocess.run(
            command(which) + args + ["--seed", "1", "--out", str(old)], capture_output=True, timeout=120
        ).returncode
        == 0
    )
    expected = OUTPUTS | ({"sim_loop.rrd"} if which == "python" else set())
    random_moment = random.Random(20)  # the same moments every time
    tally = {"old": 0, "new": 0}
    for sig in SIGNALS if which == "sim_loop" else [s for s in SIGNALS if s != signal.SIGPIPE]:
        for _ in range(MOMENTS):
            out = tmp_path / "out"
            subprocess.run(["rm", "-rf", str(out)], check=True)
            subprocess.run(["cp", "-a", str(old), str(out)], check=True)
            before = state(out)
            moment = random_moment.uniform(0.0, seconds * 1.2)
            with subprocess.Popen(
                command(which) + args + ["--seed", "2", "--out", str(out)],
                stdin=subprocess.DEVNULL,
                stdout=subprocess.DEVNULL,
                stderr=subprocess.PIPE,
                text=True,
                preexec_fn=_defaults,
            ) as proc:
                time.sleep(moment)
                proc.send_signal(sig)
                try:
                    _, err = proc.communicate(timeout=30)
                except subprocess.TimeoutExpired:
                    proc.kill()
                    pytest.fail(f"{which}: {sig.name} at {moment:.2f} s: still running 30 s later")
            what = f"{which}: {sig.name} at {moment:.2f} s: exit {proc.returncode}, {err!r}"
            after = state(out)
            if proc.returncode == -sig:
                # Killed by the default action before the command could catch
                # anything (the interpreter still starting): nothing touched.
                assert after == before, what
                tally["old"] += 1
                continue
            assert proc.returncode in (0, 128 + sig), what
            if proc.returncode:
                assert err.count("\n") == 1 and f"interrupted ({sig.name})" in err, what
            assert after[0] == expected, f"{what}: left {sorted(after[0] - expected)}"
            all_old = after == before
            all_new = (
                after[1] == (new / "metrics.json").read_bytes()
                and after[2] == (new / "trajectory.csv").read_bytes()
                and (which == "sim_loop" or after[3] != before[3])
            )
            assert all_old or all_new, f"{what}: a mix of old and new outputs"
            tally["old" if all_old else "new"] += 1
    print(f"{which}: {tally['old']} runs kept the old outputs, {tally['new']} wrote the new")


@pytest.mark.parametrize("which", ["sim_loop", "python"])
def test_a_signal_the_command_was_started_ignoring_stays_ignored(tmp_path, which):
    # nohup: SIGHUP ignored from the start; the run goes on to the end.
    def ignoring_hup():
        _defaults()
        signal.signal(signal.SIGHUP, signal.SIG_IGN)

    with subprocess.Popen(
        command(which) + ["--steps", "3000", "--no-rerun", "--out", str(tmp_path / "o")],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=ignoring_hup,
    ) as proc:
        proc.stdout.readline()  # the banner
        proc.send_signal(signal.SIGHUP)
        _, err = proc.communicate(timeout=120)
    assert proc.returncode == 0, err
    assert {p.name for p in (tmp_path / "o").iterdir()} == OUTPUTS


# A signal landing inside rerun: rerun's objects stopped half-way print under
# the command's line (a half-made RecordingStream's __del__ prints a traceback;
# a blueprint dropped between its MemorySink and the send warns). The random
# moments above hit these rarely; here the signal is raised at exactly those
# points, from inside rerun's own calls.
INSIDE_RERUN = {
    "making the RecordingStream": """
import rerun as rr
real = rr.RecordingStream.__init__
def init(self, *args, **kwargs):
    signal.raise_signal(SIG)
    real(self, *args, **kwargs)
rr.RecordingStream.__init__ = init
""",
    "sending the blueprint": """
import rerun.sinks as sinks
real = sinks.create_in_memory_blueprint
def create(*args, **kwargs):
    made = real(*args, **kwargs)
    signal.raise_signal(SIG)
    return made
sinks.create_in_memory_blueprint = create
""",
}


@pytest.mark.parametrize("where", sorted(INSIDE_RERUN))
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_inside_rerun_ends_the_run_with_one_line(tmp_path, where, sig):
    pytest.importorskip("rerun")
    script = (
        f"import runpy, signal, sys\nSIG = signal.{sig.name}\n{INSIDE_RERUN[where]}\n"
        f"sys.argv = ['simloop', '--steps', '50', '--out', {str(tmp_path / 'out')!r}]\n"
        "runpy.run_module('simloop', run_name='__main__')\n"
    )
    proc = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=120, preexec_fn=_defaults
    )
    assert proc.returncode == 128 + sig, (where, proc.returncode, proc.stderr)
    assert proc.stderr == f"sim-loop: interrupted ({sig.name}); the earlier outputs were left as they were\n", where
    assert not (tmp_path / "out").exists() or not list((tmp_path / "out").iterdir()), where


# A command whose work raises Ctrl-C inside code whose exceptions Python only
# reports (a __del__, or importlib's module-lock callback, where CI once lost a
# batch's Ctrl-C): `then` says what the work does after that.
SWALLOWED = """
import signal, sys
import simloop.__main__ as command
from simloop import batch_command

class Swallows:
    def __del__(self):
        signal.raise_signal(signal.{name})

def work(argv):
    Swallows()
    {then}

command._main = work
sys.exit(command.main([]))
"""


@pytest.mark.parametrize("name", ["SIGINT", "SIGTERM"])
def test_a_signal_python_only_reported_still_stops_the_command(name):
    done = subprocess.run(
        [sys.executable, "-c", SWALLOWED.format(name=name, then="return 0")],
        capture_output=True,
        text=True,
        timeout=60,
        preexec_fn=_defaults,
    )
    assert done.returncode == 128 + signal.Signals[name], done.stderr
    assert done.stderr == f"sim-loop: interrupted ({name}); the earlier outputs were left as they were\n"


def test_a_signal_python_only_reported_stops_a_batch_at_its_next_chunk(tmp_path):
    then = "return batch_command._run_batch(Batch(), None, 0, 0.0)"
    script = SWALLOWED.replace("command._main = work", BATCH + "command._main = work")
    done = subprocess.run(
        [sys.executable, "-c", script.format(name="SIGINT", then=then)],
        capture_output=True,
        text=True,
        timeout=60,
        preexec_fn=_defaults,
        cwd=tmp_path,
    )
    assert done.returncode == 130, done.stderr
    kept = "b.parquet not written; 1 of 3 runs kept in b.parts/ (add --resume to finish)"
    assert done.stderr == f"sim-loop: interrupted (SIGINT); {kept}\n"


# A batch of three runs in one-run chunks, the signal already taken: its first chunk is its last.
BATCH = """
class Batch:
    out, parts, runs = "b.parquet", "b.parts", [0, 1, 2]
    kept = 0
    def run(self, executor, progress):
        for self.kept in (1, 2, 3):
            progress(self.kept, 3)
        return 3
    def kept_runs(self):
        return self.kept

"""
