"""`python -m simloop batch` checks every value before the first run (one
line, exit 2, nothing written), refuses a parts folder it cannot trust (a
manifest that is not one, a part damaged or edited under its stamp, a part
that is not a regular file) naming the file, leaves no temporary file when
a write fails, and reports truthfully what it wrote."""

import json
import os
import resource
import subprocess
import sys
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from conftest import batch
from test_batch_resume import interrupted

ARGS = ["--seeds", "0:300", "--steps", "300", "--chunk-size", "10", "--threads", "1"]


@pytest.mark.parametrize(
    "args, words",
    [
        (["--seeds", "\u00b2"], "--seeds: '\u00b2' is not seeds"),
        (["--steps", "\u00b2"], "--steps: '\u00b2' is not a whole number from 1 to "),
        (["--chunk-size", "\u00b3"], "--chunk-size: '\u00b3' is not a whole number from 1 to "),
        (["--threads", "4611686018427387903"], "--threads: '4611686018427387903' is not a whole number from 1 to 4096"),
        (["--seeds", "0:10000000000"], "--seeds: '0:10000000000' is 10000000000 seeds; a batch runs at most 10000000"),
        (["--seeds", "0:100000", "--friction", ",".join(["1"] * 101)], "make 10100000 runs; a batch runs at most"),
    ],
)
def test_a_value_the_batch_cannot_run_is_refused_before_any_run(tmp_path, args, words):
    done = batch([*args, "--out", "out/b.parquet"], tmp_path)
    assert done.returncode == 2, done.stderr
    assert done.stderr.count("\n") == 1 and done.stderr.startswith("sim-loop: batch: "), done.stderr
    assert any(w in done.stderr for w in words.split(" | ")), done.stderr
    assert not (tmp_path / "out").exists()


@pytest.fixture(scope="module")
def stopped(tmp_path_factory):
    """A folder with a whole batch's file and the parts of the same batch stopped after 3 chunks."""
    folder = tmp_path_factory.mktemp("stopped")
    whole = batch([*ARGS, "--out", "whole.parquet"], folder)
    assert whole.returncode == 0, whole.stderr
    parts = interrupted(ARGS, folder, "cut.parquet", 3)
    return folder, parts


def refused(folder: Path, parts: Path, words: str) -> None:
    """The batch's --resume refuses the parts, in one line holding `words` (or one of "a | b"), changing nothing."""
    before = {p.name: p.read_bytes() for p in parts.iterdir() if p.is_file()}
    done = batch([*ARGS, "--out", "cut.parquet", "--resume"], folder)
    assert done.returncode == 2, done.stderr
    assert done.stderr.count("\n") == 1 and done.stderr.startswith("sim-loop: batch: --resume: "), done.stderr
    assert any(w in done.stderr for w in words.split(" | ")), done.stderr
    assert not (folder / "cut.parquet").exists()
    assert {p.name: p.read_bytes() for p in parts.iterdir() if p.is_file()} == before, "the parts folder changed"


@pytest.mark.parametrize("chunk_size", [0, "x", None, "missing", [10], True, 2**40])
def test_a_manifest_without_a_chunk_size_is_refused_in_one_line(stopped, chunk_size):
    folder, parts = stopped
    path = parts / "manifest.json"
    saved = path.read_bytes()
    manifest = json.loads(saved)
    if chunk_size == "missing":
        del manifest["chunk_size"]
    else:
        manifest["chunk_size"] = chunk_size
    try:
        path.write_text(json.dumps(manifest))
        refused(folder, parts, "manifest.json: not a batch's manifest")
        path.write_text(json.dumps([manifest]))
        refused(folder, parts, "manifest.json: not a batch's manifest")
        path.write_text("[" * 100000 + "]" * 100000)
        refused(folder, parts, "manifest.json: unreadable")
    finally:
        path.write_bytes(saved)


def test_a_part_damaged_or_edited_under_its_stamp_or_not_a_file_is_refused(stopped):
    folder, parts = stopped
    first = parts / "chunk-000000000.parquet"
    saved = first.read_bytes()
    try:
        table = pq.read_table(first)
        column = table.column_names.index("seed") if "seed" in table.column_names else 1
        values = table.column(column).to_pylist()
        edited = table.set_column(
            column, table.field(column), pa.array([values[1]] + values[1:], table.field(column).type)
        )
        pq.write_table(edited, first)  # the stamp kept, a value changed
        refused(folder, parts, "chunk-000000000.parquet: damaged or edited")
        # A byte flipped a third of the way in: in the column data the checksum finds it; where a build's file
        # has a page header there (PyPI's pyarrow and MuJoCo), pyarrow does.
        flipped = bytearray(saved)
        flipped[len(flipped) // 3] ^= 0x10
        first.write_bytes(bytes(flipped))
        refused(folder, parts, "chunk-000000000.parquet: damaged | chunk-000000000.parquet: truncated or damaged")
    finally:
        first.write_bytes(saved)
    fifo = parts / "chunk-000000004.parquet"
    os.mkfifo(fifo)
    try:
        refused(folder, parts, "chunk-000000004.parquet: not a regular file")
    finally:
        fifo.unlink()


def test_a_full_file_leaves_no_temporary_and_resume_finishes_the_same_file(stopped):
    folder, parts = stopped
    size = (folder / "whole.parquet").stat().st_size

    def limit_files():  # the parts fit, the whole file does not
        resource.setrlimit(resource.RLIMIT_FSIZE, (size // 2, resource.RLIM_INFINITY))

    full = subprocess.run(
        [sys.executable, "-m", "simloop", "batch", *ARGS, "--out", "cut.parquet", "--resume"],
        cwd=folder,
        capture_output=True,
        text=True,
        stdin=subprocess.DEVNULL,
        timeout=300,
        preexec_fn=limit_files,
    )
    assert full.returncode == 1, full.stderr
    assert full.stderr.count("\n") == 1, full.stderr
    assert not [p.name for p in folder.iterdir() if ".tmp." in p.name]
    assert not [p.name for p in parts.iterdir() if ".tmp." in p.name]
    # What a killed batch leaves (no handler runs on SIGKILL) goes with the next batch on the folder.
    (folder / ".cut.parquet.tmp.999999").write_bytes(b"left")
    (parts / "chunk-000000007.parquet.tmp.999999").write_bytes(b"left")
    done = batch([*ARGS, "--out", "cut.parquet", "--resume"], folder)
    assert done.returncode == 0, done.stderr
    assert (folder / "cut.parquet").read_bytes() == (folder / "whole.parquet").read_bytes()
    assert sorted(p.name for p in folder.iterdir()) == ["cut.parquet", "whole.parquet"]


def test_a_report_that_cannot_be_written_says_the_file_was(tmp_path):
    with open("/dev/full", "w") as full:
        done = subprocess.run(
            [sys.executable, "-m", "simloop", "batch", "--seeds", "0:4", "--steps", "50", "--out", "b.parquet"],
            cwd=tmp_path,
            stdout=full,
            stderr=subprocess.PIPE,
            text=True,
            stdin=subprocess.DEVNULL,
            timeout=120,
        )
    assert done.returncode == 1, done.stderr
    assert done.stderr.count("\n") == 1, done.stderr
    assert "cannot write the report to standard output" in done.stderr and "b.parquet was written" in done.stderr
    assert (tmp_path / "b.parquet").is_file()


def test_a_run_whose_speed_squared_overflows_is_a_row_not_a_traceback(tmp_path):
    done = batch(["--gravity", "1e200", "--seeds", "0:2", "--steps", "300", "--out", "b.parquet"], tmp_path)
    assert done.returncode == 0, done.stderr
    table = pq.read_table(tmp_path / "b.parquet").to_pydict()
    assert all(table["diverged"]) and all(speed > 1e154 for speed in table["box_final_speed"]), table
