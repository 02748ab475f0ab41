"""The recording is written and checked like the other outputs: a full disk
or a file-size limit under sim_loop.rrd is exit 1 with one line, the old
outputs kept whole (the recording is put in place with the pair, or none of
the three is), nothing hangs, and Ctrl-C and SIGTERM act while rerun
finishes writing."""

import os
import resource
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
WALKER = ROOT / "tests" / "scenes" / "walker.toml"  # its recording (780 kB) outgrows its trajectory (250 kB)


def run(args, **kwargs) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "simloop", *args],
        capture_output=True,
        text=True,
        stdin=subprocess.DEVNULL,
        timeout=120,
        **kwargs,
    )


def state(out: Path) -> dict:
    """Each file's bytes (and the recording's inode: its bytes differ between identical runs)."""
    return {p.name: (p.read_bytes() if p.suffix != ".rrd" else p.stat().st_ino) for p in sorted(out.iterdir())}


def test_a_file_size_limit_under_the_recording_fails_and_keeps_the_old_outputs(tmp_path):
    out = tmp_path / "out"
    assert run(["--scenario", str(WALKER), "--steps", "50", "--out", str(out)]).returncode == 0
    before = state(out)

    def limit_files():  # 500 KiB: the trajectory fits, the recording does not
        resource.setrlimit(resource.RLIMIT_FSIZE, (500 * 1024, resource.RLIM_INFINITY))

    proc = run(["--scenario", str(WALKER), "--out", str(out)], preexec_fn=limit_files)
    assert proc.returncode == 1, proc.stderr
    assert proc.stderr == f"sim-loop: {out / 'sim_loop.rrd'}: cannot write (File too large)\n"
    assert state(out) == before, "the old outputs changed, or a temporary file was left"


def mount_tmpfs(path: Path, kib: int) -> str:
    """Mounts a tmpfs of `kib` KiB on path: '' if done, else why not."""
    if os.geteuid() != 0:
        return "mounting a tmpfs needs root (run the tests as root to cover a full file system)"
    path.mkdir(exist_ok=True)
    proc = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", f"size={kib}k", "tmpfs", str(path)], capture_output=True, text=True
    )
    return "" if proc.returncode == 0 else f"mount -t tmpfs refused here: {proc.stderr.strip()}"


@pytest.mark.parametrize("kib", [600, 700, 1000, 1400, 2000])
def test_a_full_file_system_under_the_recording_fails_cleanly(tmp_path, kib):
    disk = tmp_path / "disk"
    why_not = mount_tmpfs(disk, kib)
    if why_not:
        pytest.skip(why_not)
    try:
        out = disk / "out"
        assert run(["--scenario", str(WALKER), "--steps", "50", "--out", str(out)]).returncode == 0
        before = state(out)
        started = time.monotonic()
        proc = run(["--scenario", str(WALKER), "--out", str(out)])
        took = time.monotonic() - started
        assert took < 60, "it hung"
        if proc.returncode == 0:  # it fitted: a complete recording, every row
            import rerun.chunk

            assert sorted(p.name for p in out.iterdir()) == ["metrics.json", "sim_loop.rrd", "trajectory.csv"]
            steps = set()
            for chunk in rerun.chunk.RrdReader(str(out / "sim_loop.rrd")).stream():
                if chunk.entity_path == "/plots/torso_z" and not chunk.is_static:
                    steps.update(chunk.to_record_batch().column("step").to_pylist())
            assert steps == set(range(751))
        else:
            assert proc.returncode == 1, proc.stderr
            assert proc.stderr.count("\n") == 1 and "cannot write (No space left on device)" in proc.stderr
            assert proc.stderr.startswith(f"sim-loop: {out}/"), proc.stderr
            assert state(out) == before, "the old outputs changed, or a temporary file was left"
            print(f"{kib} KiB: {proc.stderr.strip()}")
    finally:
        subprocess.run(["umount", str(disk)], check=True)


def test_a_write_error_is_kept_and_the_writer_never_blocks(tmp_path):
    # Through a pipe, past a 64 KiB file-size limit: the writer's writes all
    # succeed (the pipe is drained, discarding), and finish() says what failed.
    proc = subprocess.run(
        [
            sys.executable,
            "-c",
            textwrap.dedent("""
        import os, resource
        from simloop import _core
        resource.setrlimit(resource.RLIMIT_FSIZE, (64 * 1024, resource.RLIM_INFINITY))
        piped = _core.PipedFile("out.bin")
        writer = os.open(piped.writer_path, os.O_WRONLY)
        piped.close_writer()
        for _ in range(64):
            assert os.write(writer, b"x" * 16384) == 16384
        os.close(writer)
        assert piped.wait(30)
        try:
            piped.finish()
        except OSError as e:
            print("OSError", e)
        del piped
        print(sorted(os.listdir(".")))
    """),
        ],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        stdin=subprocess.DEVNULL,
        timeout=120,
    )
    assert proc.returncode == 0, proc.stderr
    first, second = proc.stdout.splitlines()
    assert first.startswith("OSError ") and first.endswith("out.bin: cannot write (File too large)"), first
    assert second == "[]", "the temporary file went"


WAITING = textwrap.dedent("""
    import os, signal, sys, time
    from simloop import _core
    import simloop.__main__ as command
    command._catch_terminating_signals()
    piped = _core.PipedFile("out.bin")
    writer = os.open(piped.writer_path, os.O_WRONLY)  # never closed: the stream never ends
    piped.close_writer()
    started = time.monotonic()
    assert piped.wait(0.3) is False
    print("bounded", round(time.monotonic() - started, 1), flush=True)
    try:
        piped.wait(60)
    except KeyboardInterrupt as e:
        print(type(e).__name__, time.monotonic(), flush=True)
""")


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_waiting_for_the_recording_has_a_bound_and_hears_signals(tmp_path, sig):
    with subprocess.Popen(
        [sys.executable, "-c", WAITING],
        cwd=tmp_path,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    ) as proc:
        assert proc.stdout.readline() == "bounded 0.3\n"
        time.sleep(0.3)
        sent = time.monotonic()
        proc.send_signal(sig)
        line = proc.stdout.readline().split()
        proc.wait(timeout=10)
        err = proc.stderr.read()
    assert line[:1] == ["KeyboardInterrupt" if sig == signal.SIGINT else "_Terminated"], err
    assert float(line[1]) - sent < 0.2


def test_no_file_is_none():
    # (The command's commit and commit_files share the conversion: a None
    # among the files is refused, where the command's dereferenced it.)
    from simloop import _core

    with pytest.raises(ValueError, match=r"^also: None is not a PipedFile$"):
        _core.commit_files([None])
    with pytest.raises(ValueError, match=r"^also: None is not a PipedFile$"):
        _core.Orchestration(["--smoke"]).commit([None])
