"""python -m simloop --video FILE: a run's pictures, drawn as its rows stream.

Each frame is the state of a recorded row (its qpos: the chapter's box and
pusher columns, or the positions every scenario's drawn row ends with),
posed in a Sim of the run's scene (mj_forward) and drawn by simloop.Renderer:
without multisampling, planes to the horizon, and for the chapter a camera
that follows the box along the floor, backing off as it rises (a hop shows
as the box rising in the frame, the floor beneath it still in view).
A frame every 1/25 s of simulated time (every row when rows are sparser):
the video plays in real time. FILE.mp4 is encoded by ffmpeg: imageio-ffmpeg's
bundled binary when that package is installed (simloop's `video` extra),
else the ffmpeg on PATH; without either, and for FILE.png, the frames go
into an animated PNG (APNG, which browsers play) beside it. Like the recording, the file is written
beside its target and put in place with the run's other outputs, or not at
all.
"""

from __future__ import annotations

import importlib
import os
import shutil
import struct
import subprocess
import tempfile
import zlib
from fractions import Fraction
from pathlib import Path
from typing import Any, BinaryIO, Dict, List, Optional, Sequence

from . import _core
from .render import Renderer
from .sim import Sim

FRAMES_PER_SECOND = 25
WIDTH, HEIGHT = 640, 480
# zlib's level for an APNG's frames: 3, filtered "Sub", took 2.8 ms a frame of the default run for 15.8 kB,
# where 6, filtered "Up", took 6.7 ms for 11.9 kB (a core of the two a frame's drawing uses).
COMPRESSION = 3
CHAPTER_DISTANCE = 1.5  # m from the box at rest, as simloop/Chapter-v0's pictures look at it
FINISH_TIMEOUT = 60.0


NO_FFMPEG = (
    "ffmpeg, which .mp4 needs, is neither installed with Python (pip install 'simloop[video]') "
    "nor on PATH (apt install ffmpeg)"
)


def find_ffmpeg() -> Optional[str]:
    """The ffmpeg to encode with: imageio-ffmpeg's (its bundled binary, or the
    one its IMAGEIO_FFMPEG_EXE names) when that package is installed, else
    the one on PATH; None without either."""
    try:
        imageio_ffmpeg = importlib.import_module("imageio_ffmpeg")
    except ImportError:
        return shutil.which("ffmpeg")
    try:
        return str(imageio_ffmpeg.get_ffmpeg_exe())
    except RuntimeError:  # installed without a binary for this machine
        return shutil.which("ffmpeg")


def _chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)


class _Apng:
    """Frames as an animated PNG: compressed as they come into a spool file,
    the whole written at the end (its header counts the frames)."""

    suffix = ".png"

    def __init__(self, width: int, height: int) -> None:
        from concurrent.futures import ThreadPoolExecutor

        self.width, self.height = width, height
        self.spool: BinaryIO = tempfile.TemporaryFile()
        self.frames = 0
        self.sequence = 0  # APNG numbers its fcTL and fdAT chunks in one sequence
        # zlib releases the GIL: a frame compresses on this thread while the next is drawn (the same bytes, in
        # order: at most one frame waits, so memory stays two frames).
        self.compressor = ThreadPoolExecutor(max_workers=1, thread_name_prefix="simloop-apng")
        self.pending: Any = None  # (future of the compressed rows, fcTL bytes) of the frame being compressed

    def add(self, picture: Any, delay: Fraction) -> None:
        import numpy as np

        # Each row filtered "Sub" (each byte's difference from the same colour's byte a pixel to its left): an
        # even floor or background compresses to runs of zeros.
        flat = picture.reshape(self.height, -1)
        rows = np.empty((self.height, 1 + flat.shape[1]), np.uint8)
        rows[:, 0] = 1  # the filter's type
        rows[:, 1:4] = flat[:, :3]
        np.subtract(flat[:, 3:], flat[:, :-3], out=rows[:, 4:])
        control = struct.pack(">IIIIIHHBB", 0, self.width, self.height, 0, 0, delay.numerator, delay.denominator, 0, 0)
        self._spool_pending()
        self.pending = (self.compressor.submit(zlib.compress, rows.tobytes(), COMPRESSION), control)

    def _spool_pending(self) -> None:
        """The frame compressed last, into the spool file, numbered in its place."""
        if self.pending is None:
            return
        future, control = self.pending
        self.pending = None
        data = future.result()
        self.spool.write(_chunk(b"fcTL", struct.pack(">I", self.sequence) + control[4:]))
        self.sequence += 1
        if self.frames == 0:
            self.spool.write(_chunk(b"IDAT", data))  # the first frame is the still image too
        else:
            self.spool.write(_chunk(b"fdAT", struct.pack(">I", self.sequence) + data))
            self.sequence += 1
        self.frames += 1

    def write(self, out: BinaryIO) -> None:
        self._spool_pending()
        out.write(b"\x89PNG\r\n\x1a\n")
        out.write(_chunk(b"IHDR", struct.pack(">IIBBBBB", self.width, self.height, 8, 2, 0, 0, 0)))
        out.write(_chunk(b"acTL", struct.pack(">II", self.frames, 0)))  # 0: play forever
        self.spool.seek(0)
        shutil.copyfileobj(self.spool, out)
        out.write(_chunk(b"IEND", b""))

    def close(self) -> None:
        self.compressor.shutdown(wait=True, cancel_futures=True)
        self.spool.close()


def _frame_delay(seconds: float) -> Fraction:
    """Seconds between frames as APNG's fcTL stores them (numerator and denominator each at most 65535),
    the closest such fraction; a frame shows at most 65535 s (an 18-hour timestep is still drawn)."""
    seconds = min(seconds, 65535.0)
    return Fraction(seconds).limit_denominator(max(1, min(10000, 65535 // (int(seconds) + 1))))


class VideoRecording:
    """A drawing of a run (columns, rows, finish, files, close: what the
    command's run calls) into a video; see the module's documentation.
    chapter: the rows are the chapter's columns (else a scenario's drawn
    rows, qpos last). RuntimeError when this machine cannot render; OSError
    when the file cannot be begun."""

    def __init__(self, model: _core.Model, path: str, chapter: bool) -> None:
        self.sim = Sim(model)
        self.nq = model.nq
        self.chapter = chapter
        self.view: Dict[str, Any] = {}
        # Frames without multisampling and with a 512-texel shadow map (each
        # about halves a frame's time on a software rasteriser: edges a little
        # jagged, shadows a little soft), and with the floor drawn to the
        # horizon: the box ends the run 4.9 m out, past the floor's drawn 2 m,
        # and Break It's hop peaks 11 m out, 1.3 m up.
        self.renderer = Renderer(
            self.sim, width=WIDTH, height=HEIGHT, multisample=False, endless_planes=True, shadow_size=512
        )
        self._box: List[int] = []  # the chapter's box_x, box_y, box_z columns
        self._lookat_z: Optional[float] = None  # the box's height at the first frame: the floor's, for the camera
        requested = Path(path)
        mp4 = requested.suffix.lower() == ".mp4"
        self.ffmpeg = find_ffmpeg() if mp4 else None
        self.target = requested if self.ffmpeg or requested.suffix.lower() == ".png" else requested.with_suffix(".png")
        suffix = requested.suffix.lower()
        if mp4 and not self.ffmpeg:
            self.note = f" (an animated PNG: {NO_FFMPEG})"
        elif suffix not in (".mp4", ".png"):  # asked for a GIF, say, or no format at all
            self.note = (
                f" (an animated PNG: {suffix or 'a name without a suffix'} is not a format --video writes; "
                "FILE.mp4 is an MP4, with ffmpeg)"
            )
        else:
            self.note = ""
        self.piped: Any = _core.PipedFile(self.target)
        self.apng: Optional[_Apng] = None if self.ffmpeg else _Apng(WIDTH, HEIGHT)
        self.encoder: "Optional[subprocess.Popen[bytes]]" = None  # ffmpeg, started once the frame rate is known
        self.spacing = 0.0  # seconds of simulated time between frames, from the first rows
        self.start = 0.0  # the first row's time
        self.due = 0  # the next frame's number: it is due at start + due * spacing
        self.frames = 0
        self._qpos_columns: List[int] = []
        self._time = 0

    # --- what the run calls

    def columns(self, names: Sequence[str]) -> None:
        names = list(names)
        self._time = names.index("time")
        if self.chapter:
            layout = self.sim.model.chapter_layout
            box = [names.index(c) for c in ("box_x", "box_y", "box_z", "box_qw", "box_qx", "box_qy", "box_qz")]
            self._qpos_columns = [-1] * self.nq  # -1: keeps qpos0 (a joint the chapter does not record)
            for i, c in enumerate(box):
                self._qpos_columns[layout["box_qposadr"] + i] = c
            self._box = box[:3]
            self._qpos_columns[layout["pusher_qposadr"]] = names.index("pusher_x")
        else:
            self._qpos_columns = list(range(len(names) - self.nq, len(names)))

    def rows(self, block: Any) -> None:
        import numpy as np

        times = block[:, self._time]
        if self.spacing == 0.0:
            row_spacing = float(times[1] - times[0]) if len(times) > 1 else 0.0
            self.spacing = max(1.0 / FRAMES_PER_SECOND, row_spacing)
            self.start = float(times[0])
        tolerance = 1e-6 * self.spacing
        for row, time in zip(block, times):
            if time < self.start + self.due * self.spacing - tolerance:
                continue
            self.due = int((time - self.start + tolerance) / self.spacing) + 1
            qpos = self.sim.qpos
            for i, c in enumerate(self._qpos_columns):
                if c >= 0:
                    qpos[i] = row[c]
            if not np.isfinite(qpos).all():
                continue  # a diverged state: nothing to draw
            self.sim.forward()
            if self._box:
                # The camera follows the box along the floor, looking half way
                # between it and where it started from in height, and backing
                # off as it rises: a hop shows as the box rising in the frame,
                # with the floor beneath it still in view.
                if self._lookat_z is None:
                    self._lookat_z = float(row[self._box[2]])
                rise = max(0.0, float(row[self._box[2]]) - self._lookat_z)
                self.view["lookat"] = (float(row[self._box[0]]), float(row[self._box[1]]), self._lookat_z + rise / 2)
                self.view["distance"] = CHAPTER_DISTANCE + 1.2 * rise
            self._add(self.renderer.render(self.sim, **self.view))

    def finish(self, result: Any) -> None:
        """The file, whole and checked, ready to be put in place; OSError if not."""
        if self.frames == 0:
            raise OSError(f"{self.target}: no state of the run could be drawn (every row diverged)")
        if self.apng is not None:
            with open(self.piped.writer_path, "wb") as out:
                self.piped.close_writer()
                self.apng.write(out)
        elif self.encoder is not None:
            assert self.encoder.stdin is not None and self.encoder.stderr is not None
            self.encoder.stdin.close()
            try:
                code = self.encoder.wait(FINISH_TIMEOUT)
            except subprocess.TimeoutExpired:
                raise OSError(f"{self.target}: ffmpeg did not finish within {FINISH_TIMEOUT:g} s") from None
            if code != 0:
                error = self.encoder.stderr.read().decode(errors="replace").strip().splitlines()
                raise OSError(f"{self.target}: ffmpeg failed: {error[-1] if error else 'no message'}")
        if not self.piped.wait(FINISH_TIMEOUT):
            raise OSError(f"{self.target}: the video was not written within {FINISH_TIMEOUT:g} s")
        self.piped.finish()

    @property
    def files(self) -> List[Any]:
        """The file to put in place with the run's outputs, until it is closed."""
        return [] if self.piped is None else [self.piped]

    def close(self) -> None:
        """Abandons the file if it was not finished."""
        if self.encoder is not None and self.encoder.poll() is None:
            self.encoder.kill()
            self.encoder.wait()
        if self.apng is not None:
            self.apng.close()
        self.piped = None
        self.renderer.close()

    @property
    def line(self) -> str:
        """The report's line for the video."""
        return f"video: {self.target}{self.note}"

    # --- the frames

    def _add(self, picture: Any) -> None:
        delay = _frame_delay(self.spacing)
        if self.apng is not None:
            self.apng.add(picture, delay)
        else:
            if self.encoder is None:
                self.encoder = self._start_ffmpeg(1 / delay)
            assert self.encoder.stdin is not None
            self.encoder.stdin.write(picture.tobytes())
        self.frames += 1

    def _start_ffmpeg(self, rate: Fraction) -> "subprocess.Popen[bytes]":
        """ffmpeg writing a fragmented MP4 (no seeking back) into the file's pipe."""
        assert self.ffmpeg is not None
        writer = os.open(self.piped.writer_path, os.O_WRONLY)
        try:
            encoder = subprocess.Popen(
                [
                    self.ffmpeg,
                    "-nostdin",
                    "-loglevel",
                    "error",
                    "-f",
                    "rawvideo",
                    "-pix_fmt",
                    "rgb24",
                    "-s",
                    f"{WIDTH}x{HEIGHT}",
                    "-framerate",
                    f"{rate.numerator}/{rate.denominator}",
                    "-i",
                    "pipe:0",
                    "-pix_fmt",
                    "yuv420p",
                    "-movflags",
                    "frag_keyframe+empty_moov",
                    "-f",
                    "mp4",
                    "pipe:1",
                ],
                stdin=subprocess.PIPE,
                stdout=writer,
                stderr=subprocess.PIPE,
            )
        finally:
            os.close(writer)
            self.piped.close_writer()  # ffmpeg holds the only write end now: its exit ends the stream
        return encoder
