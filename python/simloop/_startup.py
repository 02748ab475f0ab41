"""Ctrl-C while `python -m simloop` (or `sim-loop`) loads its modules: the command's one line and exit 130, as a
moment later, not a KeyboardInterrupt traceback. Imported first by the package, and only acts when this process
is that command (a program of the user's that imports simloop keeps its own Ctrl-C)."""

from __future__ import annotations

import os
import signal
import sys
from types import FrameType
from typing import Optional


def _is_the_command() -> bool:
    argv = list(getattr(sys, "orig_argv", []))  # the interpreter's own command line (Python 3.10+)
    for i, arg in enumerate(argv[1:], 1):
        if arg == "-m":
            return argv[i + 1 : i + 2] == ["simloop"]
        if arg == "-msimloop":
            return True
        if arg in ("-c",) or not arg.startswith("-"):
            break
    return os.path.basename(sys.argv[0]) == "sim-loop" if sys.argv else False


def _interrupted_while_starting(signum: int, frame: Optional[FrameType]) -> None:
    os.write(2, b"sim-loop: interrupted (SIGINT) while starting; nothing was run\n")
    os._exit(128 + signum)


def quiet_interrupt_while_starting() -> None:
    """Until the command installs its own handlers (main); a SIGINT the process was started ignoring stays so."""
    if _is_the_command() and signal.getsignal(signal.SIGINT) is signal.default_int_handler:
        signal.signal(signal.SIGINT, _interrupted_while_starting)


def started() -> None:
    """The command's own handling from here (main): Ctrl-C is Python's KeyboardInterrupt again."""
    if signal.getsignal(signal.SIGINT) is _interrupted_while_starting:
        signal.signal(signal.SIGINT, signal.default_int_handler)
