"""One run at a time in an output folder, whichever command runs it: a second
run is refused (exit 2, one line naming the folder and the other process),
and the pair in the folder is always one run's."""

import json
import subprocess
import sys
import time
from pathlib import Path

import pytest
import simloop
from conftest import sim_loop_exe
from expected import stepping_error_scene


def command(which: str):
    return [str(sim_loop_exe())] if which == "sim_loop" else [sys.executable, "-m", "simloop", "--no-rerun"]


def wait_for_temporary_file(out: Path, proc: subprocess.Popen) -> None:
    """Until the run is writing (its trajectory's temporary file exists): it holds the lock by then."""
    limit = time.monotonic() + 60
    while not any(p.name.startswith(".trajectory.csv.tmp.") for p in out.glob(".*")):
        assert proc.poll() is None, "the first run ended early"
        assert time.monotonic() < limit, "the first run never began writing"
        time.sleep(0.01)


@pytest.mark.parametrize("first, second", [("sim_loop", "python"), ("python", "sim_loop"), ("sim_loop", "sim_loop")])
def test_a_second_run_on_the_same_folder_is_refused_naming_the_first(tmp_path, first, second):
    out = tmp_path / "out"
    with subprocess.Popen(
        command(first) + ["--steps", "100000000", "--record-every", "100000", "--out", str(out)],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    ) as holder:
        try:
            wait_for_temporary_file(out, holder)
            refused = subprocess.run(
                command(second) + ["--smoke", "--out", str(out)],
                capture_output=True,
                text=True,
                timeout=120,
                stdin=subprocess.DEVNULL,
            )
        finally:
            holder.terminate()
            holder.wait(timeout=30)
    prefix = "sim_loop: " if second == "sim_loop" else "sim-loop: "
    assert refused.returncode == 2, refused.stderr
    assert refused.stderr == (
        f"{prefix}--out: {out}: another simloop run (pid {holder.pid}) is writing in this "
        "folder; wait for it to end, or choose another folder\n"
    )
    assert holder.returncode == 143
    assert not out.exists(), "the stopped run removed the folder it made, and the refused one wrote nothing"


def test_the_lock_is_released_on_every_exit_path(tmp_path):
    out = tmp_path / "out"
    # A failed run (a MuJoCo error while stepping), a stopped one, a killed one:
    # each time the next run gets the folder.
    scene, says = stepping_error_scene()
    broken = tmp_path / "falls.xml"
    broken.write_text(scene)
    for which in ("sim_loop", "python"):
        failed = subprocess.run(
            command(which) + ["--model", str(broken), "--body", "b1", "--out", str(out)],
            capture_output=True,
            text=True,
            timeout=120,
        )
        assert failed.returncode == 1 and says in failed.stderr, failed.stderr
        proc = subprocess.Popen(
            command(which) + ["--steps", "100000000", "--record-every", "100000", "--out", str(out)],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        wait_for_temporary_file(out, proc)
        proc.kill()  # SIGKILL: the kernel releases the lock
        proc.wait()
        for leftover in out.glob(".trajectory.csv.tmp.*"):  # what only SIGKILL leaves
            leftover.unlink()
        after = subprocess.run(
            command(which) + ["--smoke", "--out", str(out)], capture_output=True, text=True, timeout=120
        )
        assert after.returncode == 0, after.stderr


def test_runs_started_together_never_mix_their_pair(tmp_path):
    out = tmp_path / "out"
    outcomes = {0: 0, 2: 0}
    for attempt in range(12):
        which = ("sim_loop", "sim_loop") if attempt % 3 else ("sim_loop", "python")
        procs = [
            subprocess.Popen(
                command(w) + ["--steps", str(2000 + i), "--out", str(out)],
                stdout=subprocess.DEVNULL,
                stderr=subprocess.PIPE,
                text=True,
            )
            for i, w in enumerate(which)
        ]
        codes = [p.wait(timeout=120) for p in procs]
        for p in procs:
            p.stderr.close()
        assert set(codes) <= {0, 2} and 0 in codes, codes
        for code in codes:
            outcomes[code] += 1
        steps = json.loads((out / "metrics.json").read_text())["steps"]
        rows = (out / "trajectory.csv").read_text().count("\n") - 1
        assert rows == steps + 1, f"attempt {attempt}: metrics.json of {steps} steps beside {rows} rows"
    print(f"runs that got the folder: {outcomes[0]}, refused: {outcomes[2]}")


def test_within_one_process_the_lock_is_shared(tmp_path):
    with simloop._core.OutputLock(tmp_path):
        # RunResult.write takes the folder's lock too: this process holds it already.
        simloop.run(smoke=True).write(tmp_path)
    assert {p.name for p in tmp_path.iterdir()} == {"metrics.json", "trajectory.csv"}
