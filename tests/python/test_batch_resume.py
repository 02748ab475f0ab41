"""`python -m simloop batch --resume` joins only this batch's chunks, whole:
a chunk from another batch (other parameters, another simloop or MuJoCo
version), one cut short, or one out of place is refused (exit 2, one line,
nothing written) instead of joined."""

import contextlib
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from conftest import batch

pytest.importorskip("pyarrow")

ARGS = ["--seeds", "0:300", "--steps", "300", "--chunk-size", "10", "--threads", "1"]


def interrupted(args, cwd: Path, out: str, chunks: int) -> Path:
    """Runs the batch into `out` until it has `chunks` finished chunks, then Ctrl-C: its parts folder."""
    parts = cwd / f"{out}.parts"
    with contextlib.ExitStack() as stack:
        # SIGINT at its default in the child, even when the tests run as a background job.
        runner = subprocess.Popen(
            [sys.executable, "-m", "simloop", "batch", *args, "--out", out],
            cwd=cwd,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
        )
        stack.callback(lambda: runner.poll() is None and (runner.kill(), runner.wait()))
        deadline = time.monotonic() + 120
        while not (parts.is_dir() and len(list(parts.glob("chunk-*.parquet"))) >= chunks):
            assert runner.poll() is None and time.monotonic() < deadline, "the batch ended before it could be stopped"
            time.sleep(0.02)
        runner.send_signal(signal.SIGINT)
        _, err = runner.communicate(timeout=60)
        assert runner.returncode == 130, err
    return parts


def test_resume_refuses_foreign_truncated_and_misplaced_chunks(tmp_path):
    whole = batch([*ARGS, "--out", "whole.parquet"], tmp_path)
    assert whole.returncode == 0, whole.stderr
    parts = interrupted(ARGS, tmp_path, "cut.parquet", 3)
    other = interrupted([*ARGS[:3], "301", *ARGS[4:]], tmp_path, "other.parquet", 1)  # --steps 301: another batch
    first = parts / "chunk-000000000.parquet"
    saved = first.read_bytes()
    last = parts / "chunk-000000029.parquet"
    named = {path: str(path.relative_to(tmp_path)) for path in (first, last)}  # as the command names them
    assert not last.exists()

    def refused(words: str) -> None:
        before = {p.name: p.read_bytes() for p in parts.iterdir()}
        done = batch([*ARGS, "--out", "cut.parquet", "--resume"], tmp_path)
        assert done.returncode == 2, done.stderr
        assert done.stderr.count("\n") == 1 and done.stderr.startswith("sim-loop: batch: --resume: "), done.stderr
        assert words in done.stderr, done.stderr
        assert not (tmp_path / "cut.parquet").exists()
        assert {p.name: p.read_bytes() for p in parts.iterdir()} == before, "the parts folder changed"

    shutil.copyfile(other / "chunk-000000000.parquet", first)  # another batch's chunk 0
    refused(f"{named[first]}: written for another batch (other parameters, or another simloop or MuJoCo version)")
    first.write_bytes(saved[: len(saved) // 2])  # cut short
    refused(f"{named[first]}: truncated or damaged")
    first.write_bytes(saved)
    shutil.copyfile(first, last)  # chunk 0 in chunk 29's place
    refused(f"{named[last]}: not chunk 29 of this batch (it holds 10 rows, stamped chunk 0; chunk 29 has 10)")
    last.unlink()
    shutil.copyfile(first, parts / "chunk-000000030.parquet")  # past the batch's 30 chunks
    refused("chunk-000000030.parquet: not a chunk of this batch (it has 30 chunks)")
    (parts / "chunk-000000030.parquet").unlink()

    resumed = batch([*ARGS, "--out", "cut.parquet", "--resume"], tmp_path)
    assert resumed.returncode == 0, resumed.stderr
    assert (tmp_path / "cut.parquet").read_bytes() == (tmp_path / "whole.parquet").read_bytes()
    assert not parts.exists()
