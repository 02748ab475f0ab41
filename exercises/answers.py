"""A learner's answers as check.py reads them: a number with its unit, the
answer file's lines, and the wrong answers given so far (kept beside the
answer file, so that a second wrong answer gets the solution)."""

import json
import re
from pathlib import Path

# Wrong answers so far, per exercise, kept beside the answer file: the first
# wrong answer gets a hint; a second, different one (or --reveal) the solution.
ATTEMPTS_FILE = ".check_attempts.json"

# unit: (dimension, factor to SI; for "steps", to steps)
UNITS = {
    "s": ("time", 1.0),
    "sec": ("time", 1.0),
    "secs": ("time", 1.0),
    "second": ("time", 1.0),
    "seconds": ("time", 1.0),
    "ms": ("time", 1e-3),
    "m": ("length", 1.0),
    "cm": ("length", 1e-2),
    "mm": ("length", 1e-3),
    "n": ("force", 1.0),
    "step": ("steps", 1.0),
    "steps": ("steps", 1.0),
}
DIMENSIONS = {
    "time": "a time (s or ms)",
    "length": "a distance (m, cm or mm)",
    "force": "a force (N)",
    "steps": "a number of steps",
}
NUMBER_WITH_UNIT = re.compile(r"\s*([-+]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][-+]?\d+)?)\s*([A-Za-z]*)\s*")


class NoAnswer(Exception):
    pass


class Verdict:
    """What a check found. `report` and `why` answer the answer given and never
    give the solution away; `hint` goes with a first wrong answer; `solution`
    with a right one, a second wrong one, or --reveal."""

    def __init__(self, holds, report, why, hint, solution):
        self.holds, self.report, self.why, self.hint, self.solution = holds, report, why, hint, solution


def answer_lines(path: Path) -> list:
    try:
        text = path.read_text()
    except OSError as e:
        raise NoAnswer(f"cannot read {path}: {e.strerror}") from None
    lines = [line.strip() for line in text.splitlines() if line.strip() and not line.strip().startswith("#")]
    if not lines:
        raise NoAnswer(f"{path} holds no answer yet: write it there first")
    return lines


def quantity(text: str, what: str, dimensions: tuple, default_unit: str) -> tuple:
    """(value, dimension) of an answer such as '0.002 s', '2ms', '6 cm' or '1000'.

    The value is in SI units (s, m, N), or in steps; a bare number is in
    `default_unit`. Refuses a unit of another dimension, naming what it wants.
    """
    match = NUMBER_WITH_UNIT.fullmatch(text)
    unit = match.group(2) if match else ""
    key = unit if unit in UNITS else unit.lower()
    if not match or (unit and key not in UNITS):
        raise NoAnswer(f"{what} must be a number with or without a unit (s, ms, m, cm, mm, N), got {text!r}")
    dimension, factor = UNITS[key or default_unit]
    if dimension not in dimensions:
        wanted = " or ".join(DIMENSIONS[d] for d in dimensions)
        raise NoAnswer(f"{what} is {wanted}, got {text!r} ({DIMENSIONS[dimension]})")
    return float(match.group(1)) * factor, dimension


def _attempts_path(answer: Path) -> Path:
    return answer.resolve().parent / ATTEMPTS_FILE


def wrong_answers(answer: Path, exercise: int) -> list:
    try:
        return json.loads(_attempts_path(answer).read_text()).get(str(exercise), [])
    except (OSError, ValueError):
        return []


def remember_wrong(answer: Path, exercise: int, text: str) -> int:
    """Records a wrong answer; returns how many different wrong answers there have been."""
    path = _attempts_path(answer)
    try:
        state = json.loads(path.read_text())
    except (OSError, ValueError):
        state = {}
    seen = state.setdefault(str(exercise), [])
    if text not in seen:
        seen.append(text)
    try:
        path.write_text(json.dumps(state, indent=2) + "\n")
    except OSError:
        pass  # a read-only folder: every wrong answer is then a first one
    return len(seen)
