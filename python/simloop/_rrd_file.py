"""The .rrd file a recording writes: rerun's file sink, drained through a pipe
into a file simloop checks and puts in place (recording.py's Recording)."""

from __future__ import annotations

from pathlib import Path
from typing import Any, List

from . import _core
from ._command import signals_wait


class RrdFile:
    """A RecordingStream whose file simloop writes. rerun's file sink writes
    to a pipe (_core.PipedFile); a thread of simloop's appends every byte,
    each write checked, to a temporary file beside `target`, which is put in
    place together with the run's other outputs (its `files`) once finish()
    has checked it whole. A full disk or
    a file-size limit is an OSError naming the file, and rerun itself never
    sees it (the pipe is drained whatever happens), so nothing hangs in
    rerun and nothing half-written is put in place. Waiting for rerun takes
    at most FINISH_TIMEOUT seconds, and Ctrl-C and SIGTERM act during it."""

    FINISH_TIMEOUT = 60.0

    def __init__(self, rr: Any, application_id: str, recording_id: str, target: Path) -> None:
        self.target = Path(target)
        self.piped: Any = _core.PipedFile(self.target)
        self.rec: Any = None
        try:
            with signals_wait():
                self.rec = rr.RecordingStream(application_id, recording_id=recording_id, send_properties=False)
                self.rec.save(self.piped.writer_path)
        except BaseException:
            self.close()
            raise
        finally:
            if self.piped is not None:
                self.piped.close_writer()  # rerun holds its own end now

    @property
    def files(self) -> List[Any]:
        """The file to put in place with the run's outputs, until it is closed."""
        return [] if self.piped is None else [self.piped]

    def flush(self) -> None:
        """Waits for rerun to have written what was sent (keeps its queue short)."""
        try:
            self.rec.flush(timeout_sec=self.FINISH_TIMEOUT)
        except RuntimeError as e:
            raise OSError(f"{self.target}: rerun could not write the recording ({e})") from None

    def finish(self) -> None:
        """Every byte rerun wrote is in the temporary file, checked; OSError if not."""
        self.flush()
        self.rec.disconnect()  # rerun closes its end: the end of the stream
        self.rec = None
        if not self.piped.wait(self.FINISH_TIMEOUT):
            raise OSError(f"{self.target}: rerun did not finish writing the recording within {self.FINISH_TIMEOUT:g} s")
        self.piped.finish()

    def close(self) -> None:
        """Abandons the file if it was not finished: the temporary file goes at
        once, and what rerun still writes is drained and dropped."""
        rec, self.rec = self.rec, None
        self.piped = None
        if rec is not None:
            rec.disconnect()
