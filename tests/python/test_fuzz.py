"""Attacks kept in the repository: seeded, bounded fuzzing of sim_loop.

Two campaigns, each a few hundred runs of the real command in a fresh
directory, with a memory cap and a time limit per run:

* command lines built from the command's flags and hostile values (spaces,
  signs, hex, huge and tiny numbers, quotes, control characters, unknown
  flags, missing values, the sweep's points);
* MJCF files: the chapter's scene and a few others, mutated (numbers swapped
  for hostile ones, elements dropped or duplicated, text cut short, sizes
  blown up).

Every run must end by itself with exit code 0, 1 or 2 (never a signal, never
the time limit); a failure must be exactly one stderr line "sim_loop: ...";
and nothing may be left behind: no MUJOCO_LOG.TXT, no temporary files, no
files but the ones a successful run writes. The seeds are fixed, so a failure
reproduces; FUZZ_SEED=N picks another campaign.
"""

from __future__ import annotations

import os
import random
import re
import resource
import subprocess
from pathlib import Path

import pytest
import simloop
from conftest import sim_loop_exe

SEED = int(os.environ.get("FUZZ_SEED", "8"))
COMMAND_LINES = 300
MUTATIONS = 300
# Bytes of address space per run; FUZZ_MEMORY_CAP=0 lifts it (needed to fuzz
# an ASan build: SIMLOOP_SIM_LOOP=build-asan/sim_loop FUZZ_MEMORY_CAP=0).
MEMORY_CAP = int(os.environ.get("FUZZ_MEMORY_CAP", str(2 << 30)))
TIME_LIMIT = 60  # seconds per run: a hang fails the test

OUTPUT_FILES = {"metrics.json", "trajectory.csv", "sweep.csv"}

HOSTILE_NUMBERS = [
    "",
    " ",
    " 5",
    "5 ",
    "+5",
    "-5",
    "0",
    "-0",
    "0x10",
    "0x1p-3",
    "1e",
    ".",
    "-",
    "1e-300",
    "1e300",
    "1e309",
    "nan",
    "NaN",
    "inf",
    "-inf",
    "4611686018427387903",
    "4611686018427387904",
    "9223372036854775807",
    "18446744073709551615",
    "18446744073709551616",
    "99999999999999999999999",
    "1.5",
    "1,5",
    "5.",
    ".5",
    "1E+2",
    "00012",
    "'",
    '"',
    "a'b",
    "x\ny",
    "tab\there",
    "\x7f",
    "é",
    "\\",
    "--steps",
    "=",
]
SMALL_TIMESTEPS = ["0.002", "0.001", "0.05", "0.01", "2e-3", ".004", "1", "5"]
SMALL_STEPS = ["1", "2", "10", "64", "65", "300"]


def _limits() -> None:
    if MEMORY_CAP > 0:
        resource.setrlimit(resource.RLIMIT_AS, (MEMORY_CAP, MEMORY_CAP))
    resource.setrlimit(resource.RLIMIT_CORE, (0, 0))


def run_sim_loop(args: list[str], cwd: Path) -> subprocess.CompletedProcess:
    env = dict(os.environ, SIMLOOP_PYTHON=str(cwd / "no-such-python"))
    try:
        return subprocess.run(
            [str(sim_loop_exe()), *args],
            cwd=cwd,
            capture_output=True,
            stdin=subprocess.DEVNULL,
            timeout=TIME_LIMIT,
            preexec_fn=_limits,
            env=env,
        )
    except subprocess.TimeoutExpired:
        pytest.fail(f"sim_loop {args!r} ran past {TIME_LIMIT} s")


def check_outcome(args: list[str], cwd: Path, out: Path) -> int:
    """Runs sim_loop in cwd and checks the rules; returns its exit code."""
    before = {p for p in cwd.rglob("*")}
    result = run_sim_loop(args, cwd)
    what = f"sim_loop {args!r}: exit {result.returncode}, stderr {result.stderr!r}"
    assert result.returncode in (0, 1, 2), what
    if result.returncode != 0:
        assert result.stderr.startswith(b"sim_loop: "), what
        assert result.stderr.count(b"\n") == 1 and result.stderr.endswith(b"\n"), what
    else:
        assert result.stderr == b"", what
    assert not list(cwd.rglob("MUJOCO_LOG.TXT")), what
    new = {p for p in cwd.rglob("*")} - before
    for path in new:
        if path.is_dir():
            assert path == out or out in path.parents or path in out.parents, f"{what}: left {path}"
        else:
            assert path.parent == out and path.name in OUTPUT_FILES, f"{what}: left {path.relative_to(cwd)}"
    return result.returncode


def random_command_line(rng: random.Random) -> list[str]:
    sweep = rng.random() < 0.3
    args = ["sweep"] if sweep else []
    flags = [
        "--seed",
        "--steps",
        "--timestep",
        "--record-every",
        "--smoke",
        "--energy-audit",
        "--no-perturb",
        "--rerun",
        "--no-rerun",
        "--model",
        "--out",
        "--help",
        "--version",
        "--plot",
        "--threads",
        "--timesteps",
        "--range",
        "--duration",
        "--bogus",
        "-h",
        "-x",
        "stray",
    ]
    for _ in range(rng.randint(0, 5)):
        flag = rng.choice(flags)
        r = rng.random()
        if flag in (
            "--smoke",
            "--energy-audit",
            "--no-perturb",
            "--rerun",
            "--no-rerun",
            "--help",
            "--version",
            "--plot",
            "-h",
            "-x",
            "stray",
            "--bogus",
        ):
            value = rng.choice(HOSTILE_NUMBERS) if r < 0.15 else None
        elif flag == "--steps":
            value = rng.choice(SMALL_STEPS) if r < 0.6 else rng.choice(HOSTILE_NUMBERS)
        elif flag in ("--timestep",):
            value = rng.choice(SMALL_TIMESTEPS) if r < 0.6 else rng.choice(HOSTILE_NUMBERS)
        elif flag == "--timesteps":
            value = ",".join(rng.choice(SMALL_TIMESTEPS + HOSTILE_NUMBERS[:20]) for _ in range(rng.randint(1, 3)))
        elif flag == "--range":
            count = rng.choice(["1", "2", "3", "0", "x", "10001"])
            value = f"{rng.choice(SMALL_TIMESTEPS)}:{rng.choice(SMALL_TIMESTEPS)}:{count}"
            if r < 0.3:
                value = rng.choice(HOSTILE_NUMBERS)
        elif flag == "--duration":
            value = (
                rng.choice(["0.05", "0.2", "1e-3", "1e300", "9e18", "0"]) if r < 0.7 else rng.choice(HOSTILE_NUMBERS)
            )
        elif flag == "--model":
            value = rng.choice(["scene.xml", "missing.xml", "broken.xml", ".", "", "out"])
        elif flag == "--out":
            value = rng.choice(["out", "file.txt", "", "out/../out", "/proc/self/x", "file.txt/sub"])
        else:
            value = rng.choice(HOSTILE_NUMBERS + SMALL_STEPS)
        if value is None:
            args.append(flag)
        elif r < 0.5 and flag.startswith("--"):
            args.append(f"{flag}={value}")
        else:
            args += [flag, value]
    if sweep and not any(a.startswith(("--timesteps", "--range")) for a in args):
        args += ["--timesteps", "0.002,0.05"]  # keeps each sweep short
    if sweep and not any(a.startswith("--duration") for a in args):
        args += ["--duration", "0.2"]
    if not any(a.startswith("--out") for a in args):
        args += ["--out", "out"]
    if not sweep and not any(a.startswith("--steps") for a in args):
        args += ["--steps", "200"]
    return args


def test_fuzz_command_lines(tmp_path):
    rng = random.Random(SEED)
    (tmp_path / "scene.xml").write_text(CHAPTER_SCENE)
    (tmp_path / "broken.xml").write_text("<mujoco><worldbody><body></mujoco>")
    (tmp_path / "file.txt").write_text("precious")
    codes = {0: 0, 1: 0, 2: 0}
    for _ in range(COMMAND_LINES):
        args = random_command_line(rng)
        out = tmp_path / "out"
        codes[check_outcome(args, tmp_path, out)] += 1
        assert (tmp_path / "file.txt").read_text() == "precious"
    # The campaign reaches both sides: runs that succeed and ones refused.
    assert codes[0] >= 20 and codes[2] >= 50, codes


# ---- MJCF mutations ----

CHAPTER_SCENE = simloop._core.PUSHER_SCENE_XML  # the chapter's scene, as sim_loop embeds it

# A hinged paddle that swats the box, with options set.
PADDLE_SCENE = """<mujoco model="paddle">
  <compiler autolimits="true" angle="radian"/>
  <option timestep="0.001" gravity="0 0 -9.81" integrator="RK4"/>
  <size nkey="2"/>
  <worldbody>
    <geom type="plane" size="3 3 0.1"/>
    <body name="box" pos="0.5 0 0.1">
      <freejoint/>
      <geom type="box" size="0.1 0.1 0.1" mass="1"/>
    </body>
    <body name="paddle" pos="0 0 0.1">
      <joint name="swing" type="hinge" axis="0 0 1" damping="0.5" range="-3 3"/>
      <geom type="capsule" fromto="0 0 0 0.4 0 0" size="0.03"/>
    </body>
  </worldbody>
  <actuator>
    <position joint="swing" kp="20" ctrlrange="-2 2"/>
  </actuator>
</mujoco>
"""

# A stack: the box sits on a second free body, with a sphere and a mesh-less
# composite of geoms; defaults and a tendon-free equality.
STACK_SCENE = """<mujoco model="stack">
  <compiler autolimits="true"/>
  <default><geom friction="0.8 0.01 0.001" condim="4"/></default>
  <worldbody>
    <geom type="plane" size="2 2 0.1" pos="0 0 0"/>
    <body name="base" pos="0.4 0 0.1">
      <freejoint/>
      <geom type="box" size="0.1 0.1 0.1" mass="2"/>
    </body>
    <body name="box" pos="0.4 0 0.26">
      <freejoint/>
      <geom type="box" size="0.05 0.05 0.05" mass="0.5"/>
      <geom type="sphere" pos="0 0 0.06" size="0.02" mass="0.05"/>
    </body>
    <body name="pusher" pos="0 0 0.1">
      <joint name="slide" type="slide" axis="1 0 0" damping="4" range="-1 1"/>
      <geom type="box" size="0.04 0.12 0.1" mass="1"/>
    </body>
  </worldbody>
  <actuator>
    <motor joint="slide" gear="10" ctrlrange="-1 1"/>
  </actuator>
</mujoco>
"""

SCENES = [CHAPTER_SCENE, PADDLE_SCENE, STACK_SCENE]
NUMBER = re.compile(r"-?\d+(?:\.\d+)?(?:e-?\d+)?")
MUTANT_NUMBERS = [
    "0",
    "-1",
    "1e308",
    "-1e308",
    "1e-308",
    "nan",
    "inf",
    "-inf",
    "2147483648",
    "99999999999",
    "1e9",
    "3",
    "0.0000001",
    "",
    "x",
    "1 2 3 4 5 6 7",
]
MUTANT_ELEMENTS = [
    '<size nkey="100000000"/>',
    '<size nconmax="2000000000"/>',
    '<size njmax="-5"/>',
    '<option timestep="0"/>',
    '<option timestep="1e300"/>',
    '<option integrator="bogus"/>',
    '<include file="/etc/passwd"/>',
    '<include file="missing.xml"/>',
    "<body><freejoint/></body>",
    '<geom type="mesh" mesh="none"/>',
    "<!--",
    "<![CDATA[",
    '<compiler meshdir="/nonexistent"/>',
    "<worldbody/>",
    "<actuator/>",
    "\x00",
    "&bogus;",
]


def mutate(rng: random.Random, xml: str) -> str:
    for _ in range(rng.randint(1, 3)):
        kind = rng.randrange(7)
        if kind == 0:  # a number becomes a hostile one
            spans = [m.span() for m in NUMBER.finditer(xml)]
            if spans:
                a, b = rng.choice(spans)
                xml = xml[:a] + rng.choice(MUTANT_NUMBERS) + xml[b:]
        elif kind == 1:  # a line goes
            lines = xml.splitlines(keepends=True)
            del lines[rng.randrange(len(lines))]
            xml = "".join(lines)
        elif kind == 2:  # a line doubles
            lines = xml.splitlines(keepends=True)
            i = rng.randrange(len(lines))
            lines.insert(i, lines[i])
            xml = "".join(lines)
        elif kind == 3:  # the text is cut short
            xml = xml[: rng.randrange(len(xml) + 1)]
        elif kind == 4:  # an element appears somewhere
            lines = xml.splitlines(keepends=True)
            lines.insert(rng.randrange(1, len(lines) + 1), rng.choice(MUTANT_ELEMENTS) + "\n")
            xml = "".join(lines)
        elif kind == 6:  # a size blown up, where <size> belongs
            lines = xml.splitlines(keepends=True)
            # Not nkey in the hundred thousands: MuJoCo 2.2's compiler takes time
            # quadratic in nkey (a minute at 100000) before it allocates enough
            # to hit the memory cap; from ten million on, the cap stops it.
            attribute = rng.choice(["nkey", "nconmax", "njmax", "nstack", "nuserdata", "nuser_body"])
            values = ["0", "-1", "10000000", "2147483647"] + ([] if attribute == "nkey" else ["100000"])
            lines.insert(1, f'<size {attribute}="{rng.choice(values)}"/>\n')
            xml = "".join(lines)
        else:  # a few bytes are flipped
            chars = list(xml)
            for _ in range(rng.randint(1, 4)):
                if chars:
                    chars[rng.randrange(len(chars))] = chr(rng.choice([0x3C, 0x3E, 0x22, 0x2F, 0x20, 0x41, 0xE9]))
            xml = "".join(chars)
    return xml


def test_fuzz_mjcf_mutations(tmp_path):
    rng = random.Random(SEED + 1)
    codes = {0: 0, 1: 0, 2: 0}
    for i in range(MUTATIONS):
        xml = mutate(rng, rng.choice(SCENES))
        model = tmp_path / f"mutant{i % 7}.xml"
        model.write_text(xml, encoding="utf-8", errors="surrogateescape")
        args = ["--model", model.name, "--steps", "100", "--out", "out"]
        if rng.random() < 0.2:
            args = ["sweep", "--model", model.name, "--timesteps", "0.002,0.02", "--duration", "0.1", "--out", "out"]
        codes[check_outcome(args, tmp_path, tmp_path / "out")] += 1
    # Both outcomes are reached: models that load and run, models refused.
    assert codes[0] >= 20 and codes[2] >= 50, codes


def test_the_unmutated_scenes_run(tmp_path):
    # The campaign's starting points are good models: what fails is the mutation.
    for i, xml in enumerate(SCENES):
        (tmp_path / f"scene{i}.xml").write_text(xml)
        assert (
            check_outcome(["--model", f"scene{i}.xml", "--steps", "100", "--out", "out"], tmp_path, tmp_path / "out")
            == 0
        )
