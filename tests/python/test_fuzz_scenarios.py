"""Attacks on scenario files kept in the repository: a seeded, bounded campaign of mutated scenario files through
sim_loop, under the rules of test_fuzz.py (exit 0, 1 or 2, never a signal or the time limit; a failure is one
stderr line; nothing left behind, no MUJOCO_LOG.TXT).

What it mutates is what found issue 38's crashes: deep and long dotted keys and table headers (50,000 parts
overflowed toml++'s stack), nested arrays and inline tables, and paths inside the file (`scene`, `csv`) that name
devices, FIFOs, folders, NUL bytes, huge or endless files. FUZZ_SEED=N picks another campaign.
"""

from __future__ import annotations

import os
import random
import shutil

from conftest import ROOT
from test_fuzz import SEED, check_outcome

SCENARIOS = 150
SCENES = ROOT / "tests" / "scenes"

BASES = [
    (SCENES / "walker.toml").read_text(),
    (SCENES / "pusht.toml").read_text(),
    'steps = 40\n[[control]]\nactuator = "push_motor"\ncsv = "u.csv"\n[[disturbance]]\nbody = "box"\n'
    'force = [0.0, 8.0, 0.0]\nstart = 0.01\nduration = 0.02\n[record]\nbodies = ["box"]\n[reset]\n'
    "qpos_noise = 0.01\n",
]

HOSTILE_PATHS = [
    "/dev/zero",
    "/dev/null",
    "/dev/urandom",
    "fifo",
    "folder",
    "huge.csv",
    "u.csv\\u0000x",
    "../../../../../../etc/passwd",
    "",
    "missing.xml",
    "\\u001b]0;t\\u0007",
    "long.csv",
    "/proc/self/mem",
]


def dotted(rng: random.Random) -> str:
    parts = rng.choice([2, 3, 63, 64, 65, 100, 5000, 50000])
    part = rng.choice(["a", '"q.q"', "'x'", "b-c", "1"])
    return ".".join([part] * parts)


def mutate(rng: random.Random, text: str) -> str:
    lines = text.splitlines(keepends=True) or [""]
    for _ in range(rng.randint(1, 3)):
        kind = rng.randrange(8)
        at = rng.randrange(len(lines) + 1)
        if kind == 0:  # a deep dotted table header
            lines.insert(at, f"[{dotted(rng)}]\nb = 1\n")
        elif kind == 1:  # a deep dotted key
            lines.insert(at, f"{dotted(rng)} = 1\n")
        elif kind == 2:  # a deep dotted key in an inline table, or nested arrays
            depth = rng.choice([10, 200, 5000, 100000])
            lines.insert(at, rng.choice([f"x = {{{dotted(rng)} = 1}}\n", "y = " + "[" * depth + "]" * depth + "\n"]))
        elif kind in (3, 4):  # a path inside the file names something hostile
            key = "scene" if kind == 3 else "csv"
            value = f'{key} = "{rng.choice(HOSTILE_PATHS)}"\n'
            if key == "scene":
                lines.insert(0, value)
            else:
                lines.insert(at, f'[[control]]\nactuator = "push_motor"\n{value}')
        elif kind == 5:  # a line goes
            if lines:
                del lines[rng.randrange(len(lines))]
        elif kind == 6:  # the text is cut short
            text = "".join(lines)
            lines = [text[: rng.randrange(len(text) + 1)]]
        else:  # a few bytes are flipped
            chars = list("".join(lines))
            for _ in range(rng.randint(1, 4)):
                if chars:
                    chars[rng.randrange(len(chars))] = rng.choice(["[", "]", ".", '"', "=", "\n", "\x00", "\x1b"])
            lines = ["".join(chars)]
    return "".join(lines)


def test_fuzz_scenario_files(tmp_path):
    rng = random.Random(SEED + 2)
    for name in ("walker.xml", "pusht.xml"):
        shutil.copy(SCENES / name, tmp_path / name)
    (tmp_path / "u.csv").write_text("u\n0.5\n1.0\n")
    (tmp_path / "long.csv").write_text("u" * (2 << 20) + "\n")
    (tmp_path / "folder").mkdir()
    os.mkfifo(tmp_path / "fifo")
    with open(tmp_path / "huge.csv", "wb") as f:
        f.truncate(1 << 30)  # sparse: a gigabyte of NULs on one line, and no disk
    codes = {0: 0, 1: 0, 2: 0}
    for i in range(SCENARIOS):
        scenario = tmp_path / f"s{i % 5}.toml"
        scenario.write_text(mutate(rng, rng.choice(BASES)), encoding="utf-8", errors="surrogateescape")
        args = ["--scenario", scenario.name, "--steps", "40", "--out", "out"]
        codes[check_outcome(args, tmp_path, tmp_path / "out")] += 1
    assert codes[2] >= 50 and codes[0] >= 5, codes  # most mutations are refused, by name; some run


def test_the_unmutated_scenarios_run(tmp_path):
    for name in ("walker.xml", "pusht.xml"):
        shutil.copy(SCENES / name, tmp_path / name)
    (tmp_path / "u.csv").write_text("u\n0.5\n1.0\n")
    for i, text in enumerate(BASES):
        (tmp_path / f"s{i}.toml").write_text(text)
        assert (
            check_outcome(["--scenario", f"s{i}.toml", "--steps", "40", "--out", "out"], tmp_path, tmp_path / "out")
            == 0
        )
