"""One Parquet file of a batch (python -m simloop batch --out FILE), streamed
chunk by chunk as they come back from distributed's executors, and
resumable: the chunks done are kept in FILE.parts/ until FILE is whole.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import json
import os
import shutil
import stat
from typing import Any, BinaryIO, Callable, Dict, List, Optional, Sequence

from . import input_files
from ._checks import MAX_CHUNK_RUNS
from .distributed import Run, chunk_ranges, iter_chunks


class ResumeError(ValueError):
    """The parts folder cannot be used: it belongs to another batch, or exists without --resume."""


class ParquetBatch:
    """A batch written to one Parquet file, a row per run in the order of `runs`.

    Each finished chunk is first written, atomically (a temporary file
    renamed), to OUT.parts/chunk-<index>.parquet; chunks are then appended
    in order, one row group each, to a temporary file beside OUT
    (.OUT.tmp.<pid>), which is renamed onto OUT once every chunk is in, after
    which OUT.parts/ is removed. OUT is therefore never half-written. If the
    batch stops (Ctrl-C, a failure), the temporary file is removed and
    OUT.parts/ kept with a manifest (manifest.json: the batch it belongs to);
    resume=True then reads the chunks found there and runs only the others.
    Each part file is stamped (its schema's metadata) with the batch's digest,
    its chunk's index and a checksum of what it holds; resuming refuses
    (ResumeError) a part file that is another batch's, cut short, damaged or
    edited, out of place, or not a regular file, rather than join it, and
    OUT carries no stamp.
    The finished file has the same bytes either way (the same chunks, read
    back from the same part files, in the same row groups); the chunk size
    of a resumed batch is the manifest's.
    """

    def __init__(
        self,
        out: "os.PathLike[str] | str",
        job: Dict[str, Any],
        runs: Sequence[Run],
        chunk_size: int,
        description: Dict[str, Any],
        inputs: Dict[str, str],
    ) -> None:
        self.out = os.fspath(out)
        self.parts = self.out + ".parts"
        self.job, self.runs = job, runs
        identity = {key: value for key, value in job.items() if key != "threads"}  # threads change no bit
        hasher = hashlib.sha256(json.dumps({**identity, "inputs": inputs}, sort_keys=True).encode())
        for run in runs:  # repr: floats exactly, without building one huge string
            hasher.update(repr(run).encode())
        digest = hasher.hexdigest()
        self.digest = digest  # stamped on every part file
        self.inputs = inputs  # {file: digest} of every file the batch reads (input_files)
        self.manifest = {
            "format": 1,
            "batch": digest,
            "runs": len(runs),
            "chunk_size": chunk_size,
            "description": description,
            "inputs": inputs,
        }
        self.chunk_size = chunk_size
        self.done: List[int] = []

    def _part(self, index: int) -> str:
        return os.path.join(self.parts, f"chunk-{index:09d}.parquet")

    def prepare(self, resume: bool) -> int:
        """Checks the parts folder against this batch; returns the runs already done. Writes nothing."""
        if not os.path.isdir(self.parts):
            return 0
        manifest_path = os.path.join(self.parts, "manifest.json")
        if not resume:
            raise ResumeError(
                f"{self.parts}/ holds an interrupted batch: add --resume to finish it, or remove the "
                "folder to start again"
            )
        try:
            theirs = json.loads(_read_regular_file(manifest_path, MAX_MANIFEST_BYTES))
        except (OSError, ValueError, RecursionError) as e:
            raise ResumeError(
                f"--resume: {manifest_path}: unreadable ({e}); remove {self.parts}/ to start again"
            ) from None
        size = theirs.get("chunk_size") if isinstance(theirs, dict) else None
        if isinstance(size, bool) or not isinstance(size, int) or not 1 <= size <= MAX_CHUNK_RUNS:
            raise ResumeError(
                f"--resume: {manifest_path}: not a batch's manifest (a JSON object whose chunk_size is a "
                f"whole number from 1 to {MAX_CHUNK_RUNS}); remove {self.parts}/ to start again"
            )
        recorded = theirs.get("inputs")  # a manifest without it is another batch's: its digest differs below
        differ = input_files.changed(recorded, self.inputs) if isinstance(recorded, dict) else []
        if differ:
            raise ResumeError(
                f"--resume: {differ[0]} is not the file it was when {self.parts}/ was written (edited, "
                f"replaced or removed): its chunks ran on the file as it was; restore it, or remove "
                f"{self.parts}/ to start again"
            )
        if theirs.get("batch") != self.manifest["batch"]:
            raise ResumeError(
                f"--resume: {self.parts}/ was written by another batch (other scenario, seeds, grid or "
                f"simloop version); remove it, or resume with that batch's arguments"
            )
        self.chunk_size = size
        self.manifest["chunk_size"] = self.chunk_size
        ranges = chunk_ranges(len(self.runs), self.chunk_size)
        # Every chunk found must be this batch's, whole: one copied from
        # another batch's folder, or cut short (a full disk, a copy that
        # stopped), would be joined into FILE otherwise.
        for name in sorted(os.listdir(self.parts)):
            if not (name.startswith("chunk-") and name.endswith(".parquet")):
                continue
            path = os.path.join(self.parts, name)
            index = name[len("chunk-") : -len(".parquet")]
            if not (index.isascii() and index.isdigit()) or int(index) >= len(ranges) or path != self._part(int(index)):
                raise ResumeError(
                    f"--resume: {path}: not a chunk of this batch (it has {len(ranges)} chunks); "
                    f"remove it, or {self.parts}/ to start again"
                )
            problem = self._chunk_problem(path, int(index), ranges[int(index)][1] - ranges[int(index)][0])
            if problem:
                raise ResumeError(
                    f"--resume: {path}: {problem}; remove it to run that chunk again, or {self.parts}/ to start again"
                )
        self.done = [k for k in range(len(ranges)) if os.path.isfile(self._part(k))]
        return sum(ranges[k][1] - ranges[k][0] for k in self.done)

    def _chunk_problem(self, path: str, index: int, rows: int) -> str:
        """'' if the part file is chunk `index` of this batch, whole; else what is wrong."""
        import pyarrow as pa
        import pyarrow.parquet as pq

        try:
            if not stat.S_ISREG(os.stat(path).st_mode):  # a FIFO would be waited on for ever
                return "not a regular file"
            meta = pq.read_metadata(path)
            stamp = meta.schema.to_arrow_schema().metadata or {}
        except (OSError, pa.ArrowException) as e:
            return f"truncated or damaged (pyarrow cannot read it: {e})"
        if stamp.get(_STAMP_BATCH) != self.digest.encode():
            return "written for another batch (other parameters, or another simloop or MuJoCo version)"
        if stamp.get(_STAMP_CHUNK) != str(index).encode() or meta.num_rows != rows:
            return (
                f"not chunk {index} of this batch (it holds {meta.num_rows} rows, stamped chunk "
                f"{stamp.get(_STAMP_CHUNK, b'?').decode(errors='replace')}; chunk {index} has {rows})"
            )
        try:  # what it holds, against the checksum it was written with (a flipped byte, an edited value)
            held = _content_digest(_unstamped(pq.read_table(path)))
        except (OSError, ValueError, pa.ArrowException) as e:
            return f"damaged (pyarrow cannot read it: {e})"
        if stamp.get(_STAMP_CONTENT) != held:
            return "damaged or edited (what it holds does not match its checksum)"
        return ""

    def run(self, executor: object, progress: Optional[Callable[[int, int], object]] = None) -> int:
        """Runs what is left and writes OUT; returns the runs computed now. The caller holds OUT's folder's
        lock (_core.OutputLock): the temporary files a killed batch left there are removed first."""
        import pyarrow.parquet as pq

        os.makedirs(self.parts, exist_ok=True)
        directory = os.path.dirname(os.path.abspath(self.out))
        _remove_temporaries(directory, lambda stem: stem == f".{os.path.basename(self.out)}")
        _remove_temporaries(self.parts, lambda stem: stem.startswith("chunk-") or stem == "manifest.json")
        manifest_path = os.path.join(self.parts, "manifest.json")
        if not os.path.isfile(manifest_path):
            _write_atomically(manifest_path, lambda out: out.write(json.dumps(self.manifest, indent=1).encode()))
        ranges = chunk_ranges(len(self.runs), self.chunk_size)
        ready = set(self.done)
        done_runs = sum(ranges[k][1] - ranges[k][0] for k in ready)
        computed = 0
        temporary = os.path.join(directory, f".{os.path.basename(self.out)}.tmp.{os.getpid()}")
        writer: Any = None  # a pyarrow.parquet.ParquetWriter once the first chunk is written
        written = 0  # chunks appended to the temporary file, in order
        file: Optional[BinaryIO] = None  # the temporary file the writer writes
        try:

            def flush() -> None:
                nonlocal writer, written, file
                while written in ready:
                    table = _unstamped(pq.read_table(self._part(written)))
                    if writer is None:
                        file = _open_new(temporary)
                        writer = pq.ParquetWriter(file, table.schema)
                    writer.write_table(table)
                    written += 1

            flush()
            if progress is not None and done_runs:
                progress(done_runs, len(self.runs))
            for index, chunk in iter_chunks(self.job, self.runs, executor, chunk_size=self.chunk_size, skip=ready):
                # Stamped with the batch and its place in it (checked by --resume,
                # taken off again in FILE).
                table = chunk.to_arrow()
                table = table.replace_schema_metadata(
                    {
                        **(table.schema.metadata or {}),
                        _STAMP_BATCH: self.digest.encode(),
                        _STAMP_CHUNK: str(index).encode(),
                        _STAMP_CONTENT: _content_digest(table),
                    }
                )
                _write_atomically(self._part(index), functools.partial(pq.write_table, table))
                ready.add(index)
                count = ranges[index][1] - ranges[index][0]
                done_runs += count
                computed += count
                flush()
                if progress is not None:
                    progress(done_runs, len(self.runs))
            writer.close()
            writer = None
            assert file is not None
            file.close()
            os.replace(temporary, self.out)
        except BaseException:
            try:
                with contextlib.suppress(Exception):  # (a full disk fails the close too: the cause is raised)
                    if writer is not None:
                        writer.close()
                with contextlib.suppress(Exception):
                    if file is not None:
                        file.close()
            finally:
                if file is not None and os.path.lexists(temporary):
                    os.unlink(temporary)
            raise
        shutil.rmtree(self.parts, ignore_errors=True)
        return computed

    def kept_runs(self) -> int:
        """Runs whose chunks are in the parts folder now (after a stop)."""
        ranges = chunk_ranges(len(self.runs), self.chunk_size)
        return sum(b - a for k, (a, b) in enumerate(ranges) if os.path.isfile(self._part(k)))


# The stamp a part file carries in its schema's metadata: its batch, its index, and a checksum of what it holds.
_STAMP_BATCH, _STAMP_CHUNK, _STAMP_CONTENT = b"simloop_batch", b"simloop_chunk", b"simloop_sha256"
# A manifest is a few lines, and one per file the batch reads.
MAX_MANIFEST_BYTES = 16 << 20


def _unstamped(table: Any) -> Any:
    """A part file's table without the stamp (FILE has the bytes it always had)."""
    kept = {
        k: v for k, v in (table.schema.metadata or {}).items() if k not in (_STAMP_BATCH, _STAMP_CHUNK, _STAMP_CONTENT)
    }
    return table.replace_schema_metadata(kept or None)


def _content_digest(table: Any) -> bytes:
    """sha256 of a table's column names, types and values (not of the file: the same whatever Parquet's layout)."""
    hasher = hashlib.sha256()
    for name, column in zip(table.column_names, table.columns):
        hasher.update(f"{len(name)}:{name}:{column.type}:{len(column)}:{column.null_count}:".encode())
        values = column.to_numpy(zero_copy_only=False)
        # An object array's bytes are its pointers: strings are hashed as their text.
        hasher.update(json.dumps(column.to_pylist()).encode() if values.dtype == object else values.tobytes())
    return hasher.hexdigest().encode()


def _read_regular_file(path: str, limit: int) -> bytes:
    """A regular file's bytes, at most `limit` of them; OSError for anything else (a FIFO is not waited on)."""
    fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            raise OSError("not a regular file")
        data = b""
        while len(data) <= limit:
            block = os.read(fd, 1 << 20)
            if not block:
                return data
            data += block
        raise OSError(f"larger than a manifest can be ({limit} bytes)")
    finally:
        os.close(fd)


def _remove_temporaries(folder: str, ours: Callable[[str], bool]) -> None:
    """Removes the files STEM.tmp.PID (_write_atomically's, OUT's temporary) from `folder` whose STEM is ours."""
    for name in os.listdir(folder):
        stem, dot_tmp, pid = name.rpartition(".tmp.")
        if dot_tmp and ours(stem) and pid.isascii() and pid.isdigit():
            with contextlib.suppress(FileNotFoundError):
                os.unlink(os.path.join(folder, name))


def _open_new(path: str) -> BinaryIO:
    """A new file at `path` to write: whatever is at that name (a killed batch's leftover, a link planted there) is
    removed, then the file is created exclusively, so that nothing is ever written through a link."""
    with contextlib.suppress(FileNotFoundError):
        os.unlink(path)
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_CLOEXEC", 0)
    return os.fdopen(os.open(path, flags, 0o644), "wb")


def _write_atomically(path: str, write: Callable[[BinaryIO], object]) -> None:
    """Writes `path` whole or not at all: into a new file beside it (_open_new), then renamed onto it."""
    temporary = f"{path}.tmp.{os.getpid()}"
    created = False
    try:
        with _open_new(temporary) as out:
            created = True
            write(out)
        os.replace(temporary, path)
    except BaseException:
        if created and os.path.lexists(temporary):
            os.unlink(temporary)
        raise
