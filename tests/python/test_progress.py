"""The commands' progress bar: on a terminal (a pseudo-terminal here) sim_loop
and python -m simloop draw one on stderr and erase it, so the screen then reads
as without it; without a terminal (or with TERM=dumb) there is none; stdout and
the output files are byte for byte the same either way; Ctrl-C during the bar
leaves a clean line and exit 130. And simloop.progress.progress_bar, the helper."""

from __future__ import annotations

import fcntl
import io
import os
import pty
import re
import signal
import struct
import subprocess
import sys
import termios
import threading
import time
from pathlib import Path

import pytest
from conftest import sim_loop_exe, snapshot, without_wall_clock
from simloop.progress import progress_bar, wants_bar

# Long enough that the bar (shown after 0.25 s of work) appears on a loaded machine too.
STEPS = "150000"
BAR = {"sim_loop": re.compile(r"sim_loop \[[#.]*\] +\d+% \d+/\d+ steps"), "python": re.compile(r"running: +\d+%\|")}


def _command(which: str, *args: str) -> list:
    if which == "sim_loop":
        return [str(sim_loop_exe()), *args]
    return [sys.executable, "-m", "simloop", "--no-rerun", *args]


def _env(term: str = "xterm") -> dict:
    env = dict(os.environ)
    env["TERM"] = term
    env.pop("COLUMNS", None)
    return env


class _Terminal:
    """A pseudo-terminal of 24 x 100 whose output is read as it comes (a thread)."""

    def __init__(self, columns: int = 100, lines: int = 24) -> None:
        self.master, self.slave = pty.openpty()
        fcntl.ioctl(self.slave, termios.TIOCSWINSZ, struct.pack("HHHH", lines, columns, 0, 0))
        self.data = bytearray()
        self._reader = threading.Thread(target=self._read, daemon=True)

    def _read(self) -> None:
        while True:
            try:
                chunk = os.read(self.master, 4096)
            except OSError:  # EIO: every writer closed the other end
                return
            if not chunk:
                return
            self.data += chunk

    def start(self, cmd: list, cwd: Path, env: dict, stdout_too: bool = False) -> subprocess.Popen:
        proc = subprocess.Popen(
            cmd,
            cwd=cwd,
            env=env,
            stdin=subprocess.DEVNULL,
            stdout=self.slave if stdout_too else subprocess.PIPE,
            stderr=self.slave,
        )
        os.close(self.slave)
        self._reader.start()
        return proc

    def finish(self, proc: subprocess.Popen, timeout: float = 120) -> bytes:
        stdout, _ = proc.communicate(timeout=timeout)
        self._reader.join(timeout=10)
        os.close(self.master)
        return stdout or b""


def _screen(data: bytes) -> list:
    """The lines a terminal shows after `data`: carriage returns, newlines and erase-to-end-of-line
    (ESC [ K) applied; any other control sequence is kept visible, so that a test sees it."""
    lines, row, col = [[]], 0, 0
    text = data.decode("utf-8", "replace")
    i = 0
    while i < len(text):
        c = text[i]
        if text.startswith("\x1b[K", i):
            del lines[row][col:]
            i += 3
            continue
        if c == "\r":
            col = 0
        elif c == "\n":
            row += 1
            if row == len(lines):
                lines.append([])
        else:
            line = lines[row]
            line.extend(" " * (col - len(line)))
            if col < len(line):
                line[col] = c
            else:
                line.append(c)
            col += 1
        i += 1
    return ["".join(line).rstrip() for line in lines]


# The run the tests draw a bar for; its outputs go to ./out, so that its report is the same in any folder.
RUN = ("--steps", STEPS, "--record-every", "1000", "--out", "out")


def _folder(tmp_path: Path, name: str) -> Path:
    (tmp_path / name).mkdir()
    return tmp_path / name


def _plain_run(which: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        _command(which, *RUN), cwd=cwd, env=_env(), capture_output=True, stdin=subprocess.DEVNULL, timeout=120
    )


@pytest.mark.parametrize("which", ["sim_loop", "python"])
def test_a_bar_on_a_terminal_then_erased_and_the_same_outputs(which, tmp_path):
    plain = _plain_run(which, _folder(tmp_path, "plain"))
    assert plain.returncode == 0, plain.stderr
    assert plain.stderr == b"", "no terminal, no bar: stderr stays empty"

    terminal = _Terminal()
    proc = terminal.start(_command(which, *RUN), _folder(tmp_path, "tty"), _env())
    stdout = terminal.finish(proc)
    assert proc.returncode == 0, bytes(terminal.data)
    drawn = bytes(terminal.data).decode()
    assert BAR[which].search(drawn), f"no progress bar on the terminal: {drawn!r}"
    assert _screen(terminal.data) == [""], f"the bar was not erased: {_screen(terminal.data)}"
    assert without_wall_clock(stdout.decode()) == without_wall_clock(plain.stdout.decode())
    files = {p.relative_to(tmp_path / "tty"): data for p, (data, _) in snapshot(tmp_path / "tty").items()}
    plain_files = {p.relative_to(tmp_path / "plain"): data for p, (data, _) in snapshot(tmp_path / "plain").items()}
    assert Path("out/metrics.json") in files
    assert files == plain_files and len(files) == 2


@pytest.mark.parametrize("which", ["sim_loop", "python"])
def test_on_a_terminal_the_screen_reads_as_the_report_without_a_bar(which, tmp_path):
    """stdout and stderr both on the terminal, as a user runs it: the bar drawn, then erased, then the report."""
    plain = _plain_run(which, _folder(tmp_path, "plain"))
    terminal = _Terminal()
    proc = terminal.start(_command(which, *RUN), _folder(tmp_path, "tty"), _env(), stdout_too=True)
    terminal.finish(proc)
    assert proc.returncode == 0
    assert BAR[which].search(bytes(terminal.data).decode())
    screen = [line for line in _screen(terminal.data) if not line.startswith("wall-clock:")]
    assert screen == without_wall_clock(plain.stdout.decode()).splitlines() + [""]


@pytest.mark.parametrize("which", ["sim_loop", "python"])
@pytest.mark.parametrize("lines", [24, 0])
def test_a_terminal_that_gives_no_size_gets_an_80_column_bar(which, lines, tmp_path):
    terminal = _Terminal(columns=0, lines=lines)
    proc = terminal.start(_command(which, *RUN), tmp_path, _env())
    terminal.finish(proc)
    assert proc.returncode == 0
    drawn = [line for line in bytes(terminal.data).decode().replace("\x1b[K", "").split("\r") if line.strip()]
    assert drawn and all(BAR[which].search(line) for line in drawn), drawn
    assert max(len(line) for line in drawn) <= 80, drawn


@pytest.mark.parametrize("which", ["sim_loop", "python"])
def test_no_bar_when_TERM_is_dumb(which, tmp_path):
    terminal = _Terminal()
    proc = terminal.start(_command(which, *RUN), tmp_path, _env("dumb"))
    terminal.finish(proc)
    assert proc.returncode == 0
    assert bytes(terminal.data) == b""


@pytest.mark.parametrize("which", ["sim_loop", "python"])
def test_ctrl_c_during_the_bar_leaves_a_clean_line_and_exit_130(which, tmp_path):
    terminal = _Terminal()
    proc = terminal.start(
        _command(which, "--steps", "100000000", "--record-every", "100000", "--out", str(tmp_path)), tmp_path, _env()
    )
    deadline = time.monotonic() + 60
    # After a second of work the bar says how long is left (tqdm's "<" in Python).
    time_left = {"sim_loop": re.compile(r" steps, \d+:\d\d:\d\d left"), "python": re.compile(r"<\d+:\d\d")}[which]
    while not (BAR[which].search(drawn := bytes(terminal.data).decode("utf-8", "replace")) and time_left.search(drawn)):
        assert proc.poll() is None and time.monotonic() < deadline, bytes(terminal.data)
        time.sleep(0.02)
    proc.send_signal(signal.SIGINT)
    stdout = terminal.finish(proc)
    assert proc.returncode == 130
    program = "sim_loop" if which == "sim_loop" else "sim-loop"
    assert _screen(terminal.data) == [
        f"{program}: interrupted (SIGINT); the earlier outputs were left as they were",
        "",
    ]
    assert stdout.decode().startswith("ch0.1-sim-loop | tier: cpu |") and stdout.count(b"\n") == 1
    assert not any(tmp_path.iterdir())


# ---- the helper ---------------------------------------------------------------


class _FakeTerminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_the_helper_draws_on_a_terminal_and_erases_its_line(monkeypatch):
    monkeypatch.setenv("TERM", "xterm")
    stream = _FakeTerminal()
    with progress_bar("batch", unit="run", stream=stream, unit_scale=False) as progress:
        progress(0, 10)
        time.sleep(0.3)  # past the delay
        progress(4, 10)
    text = stream.getvalue()
    assert re.search(r"batch: +40%\|.*\| 4/10", text), text
    assert _screen(text.encode()) == [""]


def test_the_helper_draws_nothing_when_not_a_terminal_or_TERM_is_dumb(monkeypatch):
    monkeypatch.setenv("TERM", "xterm")
    stream = io.StringIO()
    assert not wants_bar(stream) and not wants_bar(None)
    with progress_bar("batch", stream=stream) as progress:
        time.sleep(0.3)
        progress(5, 10)
    assert stream.getvalue() == ""
    monkeypatch.setenv("TERM", "dumb")
    assert not wants_bar(_FakeTerminal())


def test_the_helper_erases_its_line_when_the_work_raises(monkeypatch):
    monkeypatch.setenv("TERM", "xterm")
    stream = _FakeTerminal()
    with pytest.raises(KeyboardInterrupt):
        with progress_bar("running", stream=stream) as progress:
            time.sleep(0.3)
            progress(1, 2)
            raise KeyboardInterrupt
    assert "50%" in stream.getvalue() and _screen(stream.getvalue().encode()) == [""]
