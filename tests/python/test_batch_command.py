"""`python -m simloop batch` into Parquet, locally and on a real Dask
scheduler with `dask worker` processes (one killed mid-batch): the bytes of
an uninterrupted local batch; an interrupted batch is resumed."""

from __future__ import annotations

import contextlib
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import conftest
import psutil
import pyarrow.parquet as pq
import pytest
import simloop
from conftest import NO_WORKER_PROCESSES, ROOT
from simloop import _core

PUSHT = ROOT / "tests" / "scenes" / "pusht.toml"


# ---- The command -----------------------------------------------------------


def batch(args, cwd, **kwargs) -> subprocess.CompletedProcess:
    return conftest.batch(args, cwd, timeout=180, **kwargs)


@contextlib.contextmanager
def running_batch(args, cwd):
    """`python -m simloop batch ARGS` started in the background; killed if still running at the end."""
    runner = subprocess.Popen(
        [sys.executable, "-m", "simloop", "batch", *args],
        cwd=cwd,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        yield runner
    finally:
        if runner.poll() is None:
            runner.kill()
            runner.wait()


def wait_for_chunks(runner: subprocess.Popen, parts: Path, count: int) -> None:
    """Until the running batch has `count` finished chunks in its parts folder."""
    deadline = time.monotonic() + 120
    while not (parts.is_dir() and len(list(parts.glob("chunk-*.parquet"))) >= count):
        assert runner.poll() is None and time.monotonic() < deadline, "the batch ended before it could be stopped"
        time.sleep(0.02)


GRID = [
    "--seeds",
    "0:6,40",
    "--timestep",
    "0.002,0.004",
    "--friction",
    "0.5,1.0",
    "--mass",
    "box=0.5,2",
    "--steps",
    "300",
    "--chunk-size",
    "5",
]


def test_the_batch_command_writes_one_row_per_run_of_the_grid(tmp_path):
    done = batch([*GRID, "--threads", "2", "--out", "grid.parquet"], tmp_path)
    assert done.returncode == 0, done.stderr
    assert done.stderr == ""  # no progress bar off a terminal
    assert sorted(p.name for p in tmp_path.iterdir()) == ["grid.parquet"]  # no temporary, no parts left
    table = pq.read_table(tmp_path / "grid.parquet").to_pydict()
    assert len(table["run"]) == 7 * 2 * 2 * 2
    # itertools.product(friction, mass, timesteps, seeds): the seed varies fastest.
    assert table["seed"][:8] == [0, 1, 2, 3, 4, 5, 40, 0]
    assert table["timestep"][:8] == [0.002] * 7 + [0.004]
    assert table["mass_box"][:14] == [0.5] * 14 and table["mass_box"][14] == 2.0
    assert table["friction"][27] == 0.5 and table["friction"][28] == 1.0
    # Each row is run_scenario with that model: the chapter's scenario, the scene with those parameters.
    chapter = simloop.Scenario.chapter()
    for row in (0, 9, 20, 55):
        model = _core.with_scene_params(
            chapter.model(), [("friction", "", table["friction"][row]), ("mass", "box", table["mass_box"][row])]
        )
        alone = simloop.run_scenario(
            chapter, seed=table["seed"][row], timestep=table["timestep"][row], steps=300, model=model
        )
        assert table["box_final_pos_x"][row] == alone.column("box_x")[-1]
        assert table["box_final_pos_y"][row] == alone.column("box_y")[-1]
    # Parameters equal to the scene's own (friction 1, the box's 0.5 kg) change no bit.
    plain = batch(
        ["--seeds", "0:6,40", "--timestep", "0.002,0.004", "--steps", "300", "--out", "plain.parquet"], tmp_path
    )
    assert plain.returncode == 0, plain.stderr
    plain_table = pq.read_table(tmp_path / "plain.parquet").to_pydict()
    for name in ("box_final_pos_x", "box_final_pos_y", "box_final_speed", "disturbance0_fy"):
        assert table[name][28:42] == plain_table[name]  # friction 1.0, mass 0.5


def test_a_progress_bar_on_a_terminal_only(tmp_path):
    import fcntl
    import pty
    import struct
    import termios

    leader, follower = pty.openpty()
    fcntl.ioctl(follower, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 100, 0, 0))  # a terminal 100 columns wide
    try:
        done = subprocess.run(
            [
                sys.executable,
                "-m",
                "simloop",
                "batch",
                "--seeds",
                "0:20",
                "--steps",
                "100",
                "--chunk-size",
                "5",
                "--out",
                "t.parquet",
            ],
            cwd=tmp_path,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=follower,
            timeout=120,
        )
        os.close(follower)
        follower = -1
        drawn = b""
        while True:
            try:
                chunk = os.read(leader, 65536)
            except OSError:  # the terminal's other end is closed: all read
                break
            if not chunk:
                break
            drawn += chunk
    finally:
        if follower >= 0:
            os.close(follower)
        os.close(leader)
    assert done.returncode == 0
    assert b"20/20" in drawn and b"run" in drawn


def test_bad_input_is_one_line_exit_2_and_nothing_written(tmp_path):
    for args, words in [
        (["--mass", "bx=1"], "no body named 'bx' (did you mean 'box'?)"),
        (["--friction", "-1"], "friction must be a finite number >= 0"),
        (["--damping", "pusher_slid=2"], "did you mean 'pusher_slide'?"),
        (["--seeds", "9:3"], "--seeds: '9:3' is an empty range"),
        (["--timestep", "0.002,x"], "--timestep: 'x' is not a number"),
        (["--timestep", "0.002,-1"], "batch: --timestep: timestep must be a positive, finite number of seconds"),
        (["--rng", "pcg"], "batch: --rng: rng must be 'mt19937_64' or 'numpy', got 'pcg'"),
        (["--scenario", "missing.toml"], "--scenario: missing.toml"),
        (["--threads", "0"], "--threads: '0' is not a whole number from 1"),
        (["--bogus"], "unknown argument '--bogus'"),
    ]:
        done = batch([*args, "--out", "sub/out.parquet"], tmp_path)
        assert done.returncode == 2, (args, done.stderr)
        assert done.stderr.count("\n") == 1 and words in done.stderr, done.stderr
    assert list(tmp_path.iterdir()) == []
    (tmp_path / "folder").mkdir()
    done = batch(["--out", "folder"], tmp_path)
    assert done.returncode == 2 and "--out: folder is a directory" in done.stderr
    assert [p.name for p in tmp_path.iterdir()] == ["folder"] and not list((tmp_path / "folder").iterdir())


def test_a_grid_of_a_parameter_the_scenario_draws_is_refused(tmp_path):
    """The scenario's [[reset.param]] is applied at each reset, over the grid's value: the table would show
    values no run used."""
    (tmp_path / "drawn.toml").write_text(
        'steps = 10\n[[reset.param]]\nkind = "mass"\nname = "box"\n'
        'uniform = [1.0, 2.0]\n[[reset.param]]\nkind = "friction"\n'
        'name = "box_geom"\nuniform = [0.5, 1.0]\n'
    )
    for args, words in [
        (
            ["--mass", "box=3,4"],
            "batch: --mass: the scenario's [[reset.param]] sets mass of 'box' "
            "at each run's reset, which would override the grid",
        ),
        (["--friction", "0.3"], "batch: --friction: the scenario's [[reset.param]] sets friction of 'box_geom'"),
    ]:
        done = batch(["--scenario", "drawn.toml", *args, "--out", "out.parquet"], tmp_path)
        assert done.returncode == 2 and done.stderr.count("\n") == 1 and words in done.stderr, done.stderr
    assert not (tmp_path / "out.parquet").exists()
    done = batch(["--scenario", "drawn.toml", "--mass", "pusher=3", "--seeds", "0:2", "--out", "out.parquet"], tmp_path)
    assert done.returncode == 0, done.stderr


def test_resume_after_ctrl_c_gives_the_bytes_of_an_uninterrupted_batch(tmp_path):
    args = ["--seeds", "0:800", "--steps", "500", "--chunk-size", "20", "--threads", "1"]
    whole = batch([*args, "--out", "whole.parquet"], tmp_path)
    assert whole.returncode == 0, whole.stderr
    parts = tmp_path / "cut.parquet.parts"
    with running_batch([*args, "--out", "cut.parquet"], tmp_path) as runner:
        wait_for_chunks(runner, parts, 3)
        runner.send_signal(signal.SIGINT)
        _, err = runner.communicate(timeout=60)
    assert runner.returncode == 130, err
    assert "cut.parquet not written" in err and "--resume" in err and err.count("\n") == 1
    assert not (tmp_path / "cut.parquet").exists()
    assert not list(tmp_path.glob(".cut.parquet.tmp.*"))  # the streaming file went with the stop
    kept = len(list(parts.glob("chunk-*.parquet")))
    assert 3 <= kept < 40

    again = batch([*args, "--out", "cut.parquet"], tmp_path)  # without --resume: refused, nothing touched
    assert again.returncode == 2 and "add --resume" in again.stderr
    other = batch([*args[:1], "0:801", *args[2:], "--out", "cut.parquet", "--resume"], tmp_path)
    assert other.returncode == 2 and "another batch" in other.stderr

    resumed = batch([*args, "--out", "cut.parquet", "--resume"], tmp_path)
    assert resumed.returncode == 0, resumed.stderr
    assert "from cut.parquet.parts/" in resumed.stdout
    ran_now = int(resumed.stdout.split("(")[1].split(" run now")[0])
    assert ran_now == 800 - 20 * kept  # what was written was not run again
    assert (tmp_path / "cut.parquet").read_bytes() == (tmp_path / "whole.parquet").read_bytes()
    assert not parts.exists()


# ---- A real scheduler and workers, as on a cluster --------------------------


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_for_port(port: int, process: subprocess.Popen, timeout: float = 60) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        assert process.poll() is None, f"the scheduler exited ({process.returncode})"
        with socket.socket() as s:
            if s.connect_ex(("127.0.0.1", port)) == 0:
                return
        time.sleep(0.1)
    raise AssertionError(f"nothing listens on 127.0.0.1:{port} after {timeout} s")


@pytest.fixture
def dask_cluster(tmp_path):
    if NO_WORKER_PROCESSES:
        pytest.skip(NO_WORKER_PROCESSES)
    """`dask scheduler` and two `dask worker` processes on 127.0.0.1, each in
    its own process group, all stopped (and their children) afterwards."""
    dask = Path(sys.executable).with_name("dask")
    port = free_port()
    address = f"tcp://127.0.0.1:{port}"
    processes = []

    def start(*args):
        log = open(tmp_path / f"dask-{len(processes)}.log", "w")
        processes.append(
            subprocess.Popen(
                [str(dask), *args],
                stdin=subprocess.DEVNULL,
                stdout=log,
                stderr=log,
                cwd=tmp_path,
                start_new_session=True,
            )
        )
        log.close()
        return processes[-1]

    descendants = []
    try:
        scheduler = start("scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard")
        wait_for_port(port, scheduler)
        workers = [
            start("worker", address, "--nthreads", "1", "--nworkers", "1", "--host", "127.0.0.1", "--no-dashboard")
            for _ in range(2)
        ]
        from distributed import Client

        with Client(address, timeout="30s") as c:
            c.wait_for_workers(2, timeout=60)
        yield address, workers
    finally:
        for p in processes:
            try:
                descendants.extend(psutil.Process(p.pid).children(recursive=True))
            except psutil.NoSuchProcess:
                pass
        for p in processes:
            if p.poll() is None:
                os.killpg(p.pid, signal.SIGTERM)
        for p in processes:
            try:
                p.wait(timeout=15)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
                p.wait()
        for p in processes:  # nothing of theirs outlives the test
            try:
                os.killpg(p.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
    gone, alive = psutil.wait_procs(descendants, timeout=15)
    assert not alive, f"left running: {alive}"


def test_a_real_scheduler_and_workers_with_one_killed_give_the_local_bytes(dask_cluster, tmp_path):
    address, workers = dask_cluster
    args = [
        "--scenario",
        str(PUSHT),
        "--seeds",
        "0:60",
        "--timestep",
        "0.002,0.004",
        "--damping",
        "0,2",
        "--chunk-size",
        "6",
    ]
    local = batch([*args, "--threads", "2", "--out", "local.parquet"], tmp_path)
    assert local.returncode == 0, local.stderr

    parts = tmp_path / "cluster.parquet.parts"
    with running_batch([*args, "--scheduler", address, "--out", "cluster.parquet"], tmp_path) as runner:
        wait_for_chunks(runner, parts, 1)
        # The worker process under the first `dask worker` (its nanny), mid-batch.
        victim = psutil.Process(workers[0].pid).children()[0]
        victim.send_signal(signal.SIGKILL)
        out, err = runner.communicate(timeout=180)
    assert runner.returncode == 0, err
    assert "batch: 240 runs" in out
    assert not parts.exists()
    assert (tmp_path / "cluster.parquet").read_bytes() == (tmp_path / "local.parquet").read_bytes()
    assert not victim.is_running() or victim.status() == psutil.STATUS_ZOMBIE
