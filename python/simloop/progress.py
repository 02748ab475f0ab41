"""The commands' progress bar: tqdm on stderr when stderr is a terminal, nothing otherwise.

    with progress_bar("running") as progress:
        result = _core.run(model, config, progress)   # or any progress(done, total)

`progress(done, total)` is the callable the long calls take as `progress=`
(the C++ loop calls it at most every 20 ms). The bar appears only once the
work has taken a quarter of a second, so a short run's terminal output is
what it was, and it is erased when the block ends, however it ends (Ctrl-C
included), so that what the command prints next starts on a clean line.
Nothing is drawn, and progress does nothing, when stderr is not a terminal
(a pipe, a file, CI) or TERM is "dumb" (a terminal that cannot redraw a line).
"""

from __future__ import annotations

import contextlib
import os
import sys
from typing import Callable, Iterator, Optional, TextIO

Progress = Callable[[int, int], None]

# Seconds of work before the bar appears, and between two redraws.
DELAY = 0.25
REDRAW_INTERVAL = 0.1


def wants_bar(stream: Optional[TextIO]) -> bool:
    """Whether a bar drawn on `stream` would be seen: a terminal that can redraw a line."""
    if stream is None or os.environ.get("TERM") == "dumb":
        return False
    try:
        return stream.isatty()
    except (AttributeError, ValueError, OSError):  # no isatty, or closed
        return False


@contextlib.contextmanager
def progress_bar(
    description: str, unit: str = "step", stream: Optional[TextIO] = None, unit_scale: bool = True
) -> Iterator[Progress]:
    """A progress(done, total) callable drawing a bar on `stream` (sys.stderr by default) while the
    block runs, if wants_bar(stream); a callable that does nothing otherwise. `unit`: what done and
    total count ("step", "run"); unit_scale: counts as 1.20M rather than 1200000."""
    out = sys.stderr if stream is None else stream
    if not wants_bar(out):
        yield lambda done, total: None
        return
    from tqdm import tqdm  # only for a terminal: the import costs ~30 ms

    # A terminal that says it has no size (a fresh pseudo-terminal: 0 x 0) is
    # taken as 80 x 24; tqdm would draw nothing at all.
    try:
        size = os.get_terminal_size(out.fileno())
        sized = size.columns > 0 and size.lines > 0
    except (AttributeError, ValueError, OSError):
        sized = False
    bar = tqdm(
        desc=description,
        unit=unit,
        unit_scale=unit_scale,
        file=out,
        leave=False,
        delay=DELAY,
        mininterval=REDRAW_INTERVAL,
        dynamic_ncols=sized,
        ncols=None if sized else 80,
        nrows=None if sized else 24,
    )

    def progress(done: int, total: int) -> None:
        if total != bar.total:
            bar.total = total
        if done > bar.n:
            bar.update(done - bar.n)

    try:
        yield progress
    finally:
        bar.close()  # leave=False: the line is erased
