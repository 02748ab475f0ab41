"""What python -m simloop's commands share (the run, plot and batch): the
program's name, exit codes, one-line failures, the terminating signals
raised as KeyboardInterrupt, and the peak memory they report.
"""

from __future__ import annotations

import contextlib
import signal
import sys
import threading
from types import FrameType
from typing import Any, Dict, Iterator, List, NoReturn, Optional, TextIO

from . import _core

PROGRAM = "sim-loop"
EXIT_RUN_FAILED = 1
EXIT_USAGE = 2
# Ctrl-C, SIGTERM and the other terminating signals stop the work: 128 + the
# signal's number, as for sim_loop.
EXIT_SIGINT = 128 + signal.SIGINT
EXIT_SIGTERM = 128 + signal.SIGTERM


class _Terminated(KeyboardInterrupt):
    """A terminating signal other than Ctrl-C (SIGTERM, SIGHUP, SIGQUIT, ...:
    _core.TERMINATING_SIGNALS), raised like Ctrl-C's KeyboardInterrupt so
    that each stops the work the same way (the C++ calls check for signals
    between chunks, and every temporary file goes with the stack)."""

    def __init__(self, signum: int = signal.SIGTERM) -> None:
        super().__init__(signum)
        self.signum = signum


# The terminating signals raised here as KeyboardInterrupt, Ctrl-C's among
# them. A library may turn that exception into an error of its own (a C
# extension's import: numpy's ImportError "PyCapsule_Import could not import
# module datetime"); the command then reports the signal, not that error.
_raised: List[int] = []


def _interruption(signum: int) -> KeyboardInterrupt:
    """What a terminating signal raises: Ctrl-C's own KeyboardInterrupt, or _Terminated."""
    return KeyboardInterrupt() if signum == signal.SIGINT else _Terminated(signum)


def _on_signal(signum: int, frame: Optional[FrameType]) -> NoReturn:
    _raised.append(signum)
    raise _interruption(signum)


def raise_swallowed_signal() -> None:
    """Raises a terminating signal's interruption again when its handler ran
    but the exception went nowhere: raised inside code whose exceptions
    Python only reports (importlib's module-lock callback, a __del__), it
    would be lost and the work go on. Called between pieces of work and as
    the command ends."""
    if _raised:
        raise _interruption(_raised.pop(0))


def _unraisable(previous: Any) -> Any:
    """sys.unraisablehook while the command runs: an interruption that Python
    could only report is not printed (raise_swallowed_signal raises it again);
    everything else goes to `previous`."""

    def hook(unraisable: Any) -> None:
        if not (isinstance(unraisable.exc_value, KeyboardInterrupt) and _raised):
            previous(unraisable)

    return hook


def _stopped_by(e: KeyboardInterrupt) -> "tuple[str, int]":
    """The signal's name and the exit code for a stop."""
    signum = e.signum if isinstance(e, _Terminated) else int(signal.SIGINT)
    return signal.Signals(signum).name, 128 + signum


def _catch_terminating_signals() -> Dict[int, Any]:
    """Installs _on_signal for every terminating signal whose action is still
    the default (one the command was started ignoring stays ignored, as
    nohup wants; SIGINT keeps Python's KeyboardInterrupt, noted in _raised;
    Python ignores SIGPIPE itself). Returns what to restore."""
    _raised.clear()
    previous = {}
    for signum in _core.TERMINATING_SIGNALS:
        if signal.getsignal(signum) == signal.SIG_DFL:
            previous[signum] = signal.signal(signum, _on_signal)
        elif signum == signal.SIGINT and signal.getsignal(signum) is signal.default_int_handler:
            previous[signum] = signal.signal(signum, _on_signal)  # the same KeyboardInterrupt, noted
    return previous


@contextlib.contextmanager
def signals_wait() -> Iterator[None]:
    """Ctrl-C and the terminating signals wait for the block to end, then act
    as they would have (the signal is raised again). For work that a
    KeyboardInterrupt raised inside would leave saying something else: rerun
    objects stopped half-way print under the command's one line (a
    RecordingStream stopped inside its constructor prints a traceback from
    its __del__, a blueprint stopped between its MemorySink and the send
    warns "Dropping data"), and a C extension's import turns it into an
    error of its own (numpy's ImportError: "PyCapsule_Import could not import
    module datetime"). Python runs signal handlers on the main thread only:
    elsewhere, nothing to do."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    caught: List[int] = []
    previous = {}
    for signum in _core.TERMINATING_SIGNALS:  # Ctrl-C among them
        if signal.getsignal(signum) not in (signal.SIG_IGN, None):
            previous[signum] = signal.signal(signum, lambda number, frame: caught.append(number))
    try:
        yield
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)
        if caught:
            signal.raise_signal(caught[0])


class _ReportLost(Exception):
    """Writing to stdout failed (a full disk, /dev/full): not an OSError, so
    that the handlers for the outputs' errors do not take it for theirs."""


class _Report:
    """sys.stdout while the command runs: the same stream, but a failed write
    raises _ReportLost."""

    def __init__(self, stream: TextIO) -> None:
        self._stream = stream

    def write(self, text: str) -> int:
        try:
            return self._stream.write(text)
        except OSError as e:
            raise _ReportLost(e.strerror or str(e)) from None

    def flush(self) -> None:
        try:
            self._stream.flush()
        except OSError as e:
            raise _ReportLost(e.strerror or str(e)) from None

    def __getattr__(self, name: str) -> Any:
        return getattr(self._stream, name)


def _fail(code: int, message: str, *, signal_first: bool = True) -> int:
    """Says `message` on one line and returns `code`; but when a terminating
    signal was raised and a library turned it into the failure being
    reported (_raised), raises the signal's KeyboardInterrupt again instead,
    for the command to report (signal_first=False: the command's own report
    of a stop or a lost report)."""
    if signal_first and _raised and code in (EXIT_RUN_FAILED, EXIT_USAGE):
        signum = _raised[0]
        _raised.clear()
        raise _interruption(signum)
    # As bytes: a path's undecodable bytes (surrogate escapes) go through and come back.
    line = _core._one_line(str(message).encode("utf-8", "surrogateescape")).decode("utf-8", "surrogateescape")
    if sys.stderr is not None:  # (print(file=None) would write to stdout)
        print(f"{PROGRAM}: {line}", file=sys.stderr)
    return code


# VmHWM of this process, MiB (-1 if unknown): the one reading both commands report.
_peak_memory_mib = _core._peak_memory_mib
