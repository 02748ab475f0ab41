"""The docs run as written: every ```python block and every command in a ```sh
or ```console block of README.md and docs/*.md, against the build under test.

Each page runs in a folder of its own, top to bottom, as a reader following
it would: the folder holds a link `tests` to the repository's tests/, so paths
read as from the repository's root, and what the examples write (outputs/...)
stays in the folder. A python block runs as a script there; a shell command
runs with its program mapped to the build under test (sim_loop ->
conftest's sim_loop_exe(), python -m simloop -> this Python's, the venv's
rerun -> the one beside this Python) and must exit 0, or the code its trailing
comment states (`# exit 2: ...`). A block that must not run says why in an
HTML comment on the line before it (MARKERS); every other block must run and
pass. Also: every relative link resolves, anchors included, and every name
in docs/developing.md's layout exists.
"""

from __future__ import annotations

import importlib.util
import os
import re
import shlex
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Dict, List, Optional, Tuple

import pytest
from conftest import NO_WORKER_PROCESSES, ROOT, sim_loop_exe
from simloop import _build

PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
RUNNABLE = ("python", "sh", "console")
# The HTML comments that keep a block from running, and when.
NOT_RUN = "not run by tests"
PYPI_ONLY = "run by tests only on the PyPI build"
WORKERS_ONLY = "run by tests only where worker processes can start"
# stable-baselines3 brings torch (gigabytes): not among the test extras.
SB3_ONLY = "run by tests only where stable-baselines3 is installed"
MARKER = re.compile(
    r"^<!--\s*(" + "|".join(map(re.escape, (NOT_RUN, PYPI_ONLY, WORKERS_ONLY, SB3_ONLY))) + r")\s*:\s*(\S.*?)\s*-->$"
)
SHELL_SYNTAX = {"&&", "||", "|", ";", ">", ">>", "<", "2>", "2>&1", "&"}
TIMEOUT = 120


@dataclass
class Block:
    page: Path
    line: int  # of the opening fence, 1-based
    lang: str
    text: str
    marker: Optional[Tuple[str, str]]  # (kind, reason)

    @property
    def where(self) -> str:
        return f"{self.page.relative_to(ROOT)}:{self.line}"


def fenced_blocks(page: Path) -> List[Block]:
    lines = page.read_text(encoding="utf-8").splitlines()
    blocks, i = [], 0
    while i < len(lines):
        if not lines[i].startswith("```"):
            i += 1
            continue
        lang = lines[i][3:].strip()
        end = next((j for j in range(i + 1, len(lines)) if lines[j].startswith("```")), None)
        assert end is not None, f"{page.relative_to(ROOT)}:{i + 1}: a ``` block that never closes"
        before = next((lines[j].strip() for j in range(i - 1, -1, -1) if lines[j].strip()), "")
        match = MARKER.match(before)
        blocks.append(
            Block(
                page,
                i + 1,
                lang,
                "\n".join(lines[i + 1 : end]) + "\n",
                (match.group(1), match.group(2)) if match else None,
            )
        )
        i = end + 1
    return blocks


ALL_BLOCKS = [b for page in PAGES for b in fenced_blocks(page)]
RUN_BLOCKS = [b for b in ALL_BLOCKS if b.lang in RUNNABLE]


def commands(block: Block) -> List[str]:
    """The command lines of a sh block (every line but comments), or of a
    console block (the lines after '$ '); a trailing backslash continues."""
    out: List[str] = []
    pending = ""
    for raw in block.text.splitlines():
        line = raw.strip()
        if block.lang == "console" and not pending:
            if not line.startswith("$ "):
                continue
            line = line[2:]
        if not pending and (not line or line.startswith("#")):
            continue
        if line.endswith("\\"):
            pending += line[:-1] + " "
            continue
        out.append(pending + line)
        pending = ""
    assert not pending, f"{block.where}: a command ends in a backslash"
    return out


def expected_exit(command: str) -> int:
    match = re.search(r"\s#\s*exit (\d+)\b", command)
    return int(match.group(1)) if match else 0


def argv(command: str, where: str) -> List[str]:
    """The command as the build under test runs it; fails the test, saying
    what to do, for a command this test cannot map."""
    try:
        words = shlex.split(command, comments=True)
    except ValueError as e:
        pytest.fail(f"{where}: cannot read {command!r} as a command ({e})")
    syntax = [w for w in words if w in SHELL_SYNTAX or "$(" in w or "`" in w]
    if syntax:
        pytest.fail(
            f"{where}: {command!r} uses the shell ({' '.join(syntax)}): write plain commands, or mark "
            f"the block '<!-- {NOT_RUN}: WHY -->'"
        )
    program, rest = words[0], words[1:]
    if program in ("sim_loop", "build/sim_loop", "build-pypi/sim_loop", "scripts/run.sh"):
        return [str(sim_loop_exe()), *rest]
    if program in ("python", "python3", ".venv/bin/python", ".venv-pypi/bin/python") and rest[:2] == ["-m", "simloop"]:
        return [sys.executable, "-m", "simloop", *rest[2:]]
    if program in ("sim-loop", ".venv/bin/sim-loop", ".venv-pypi/bin/sim-loop"):
        return [sys.executable, "-m", "simloop", *rest]
    if program in ("rerun", ".venv/bin/rerun", ".venv-pypi/bin/rerun"):
        return [str(Path(sys.executable).with_name("rerun")), *rest]
    pytest.fail(
        f"{where}: this test does not know how to run {program!r} (in {command!r}): use sim_loop, "
        f"python -m simloop or the venv's rerun, or mark the block '<!-- {NOT_RUN}: WHY -->'"
    )


@pytest.fixture(scope="session")
def page_folders(tmp_path_factory) -> Dict[Path, Path]:
    """One folder per page, made on first use, with a link `tests` to tests/."""
    return {}


def folder_for(page: Path, folders: Dict[Path, Path], tmp_path_factory) -> Path:
    if page not in folders:
        folder = tmp_path_factory.mktemp(page.stem)
        (folder / "tests").symlink_to(ROOT / "tests", target_is_directory=True)
        folders[page] = folder
    return folders[page]


def environment() -> Dict[str, str]:
    env = dict(os.environ)
    env["SIMLOOP_PYTHON"] = sys.executable  # sim_loop --plot draws with this Python's simloop
    env.pop("TERM", None)
    return env


def skip_reason(block: Block) -> Optional[str]:
    if block.marker is None:
        return None
    kind, reason = block.marker
    if kind == NOT_RUN:
        return f"{block.where}: {reason}"
    if kind == PYPI_ONLY and _build.MUJOCO_BUILD != "pypi":
        return f"{block.where}: on the PyPI build only: {reason}"
    if kind == WORKERS_ONLY and NO_WORKER_PROCESSES:
        return f"{block.where}: {NO_WORKER_PROCESSES}"
    if kind == SB3_ONLY and importlib.util.find_spec("stable_baselines3") is None:
        return f"{block.where}: stable-baselines3 is not installed ({reason})"
    return None


@pytest.mark.parametrize("block", RUN_BLOCKS, ids=[b.where for b in RUN_BLOCKS])
def test_the_block_runs(block: Block, page_folders, tmp_path_factory):
    reason = skip_reason(block)
    if reason:
        pytest.skip(reason)
    folder = folder_for(block.page, page_folders, tmp_path_factory)
    if block.lang == "python":
        script = tmp_path_factory.mktemp("blocks") / f"{block.page.stem}_{block.line}.py"
        script.write_text(block.text, encoding="utf-8")
        proc = subprocess.run(
            [sys.executable, str(script)],
            cwd=folder,
            capture_output=True,
            text=True,
            stdin=subprocess.DEVNULL,
            timeout=TIMEOUT,
            env=environment(),
        )
        assert proc.returncode == 0, f"{block.where}: the python block failed:\n{proc.stderr[-3000:]}"
        return
    lines = commands(block)
    assert lines, f"{block.where}: a {block.lang} block with no command in it"
    for command in lines:
        proc = subprocess.run(
            argv(command, block.where),
            cwd=folder,
            capture_output=True,
            text=True,
            stdin=subprocess.DEVNULL,
            timeout=TIMEOUT,
            env=environment(),
        )
        want = expected_exit(command)
        assert proc.returncode == want, (
            f"{block.where}: {command!r} exited {proc.returncode}, not {want}:\n{proc.stderr[-3000:]}"
        )


def test_every_marker_comes_right_before_a_block():
    for page in PAGES:
        lines = page.read_text(encoding="utf-8").splitlines()
        for i, line in enumerate(lines):
            if line.lstrip().startswith("<!--") and ("not run by tests" in line or "run by tests only" in line):
                assert MARKER.match(line.strip()), (
                    f"{page.relative_to(ROOT)}:{i + 1}: a marker that does not read '<!-- {NOT_RUN}: WHY -->': {line!r}"
                )
                following = next((lines[j] for j in range(i + 1, len(lines)) if lines[j].strip()), "")
                assert following.startswith("```") and following[3:].strip() in RUNNABLE, (
                    f"{page.relative_to(ROOT)}:{i + 1}: a marker not followed by a python, sh or console block"
                )


# ---- links ------------------------------------------------------------------

LINK = re.compile(r"\[[^\]]*\]\(([^)\s]+)\)")


def prose(page: Path) -> str:
    """The page without its fenced blocks and inline code, where a link is no link."""
    text = re.sub(r"^```.*?^```[^\n]*$", "", page.read_text(encoding="utf-8"), flags=re.S | re.M)
    return re.sub(r"(`+).+?\1", "", text, flags=re.S)


def anchors(page: Path) -> set:
    """GitHub's anchors for the page's headings."""
    seen: Dict[str, int] = {}
    out = set()
    for line in prose(page).splitlines():
        match = re.match(r"#{1,6}\s+(.*)", line)
        if not match:
            continue
        slug = re.sub(r"[^\w\- ]", "", match.group(1).strip().lower().replace("`", "")).replace(" ", "-")
        count = seen.get(slug, 0)
        seen[slug] = count + 1
        out.add(slug if count == 0 else f"{slug}-{count}")
    return out


def test_every_relative_link_resolves():
    broken = []
    for page in PAGES:
        for target in LINK.findall(prose(page)):
            if re.match(r"[a-z]+:", target):
                continue  # https:, mailto:
            path, _, anchor = target.partition("#")
            resolved = (page.parent / path).resolve() if path else page
            if not resolved.exists():
                broken.append(f"{page.relative_to(ROOT)}: {target}: no such file")
            elif anchor and resolved.suffix == ".md" and anchor not in anchors(resolved):
                broken.append(f"{page.relative_to(ROOT)}: {target}: no heading with that anchor")
    assert not broken, "\n".join(broken)


def test_readme_is_short():
    lines = (ROOT / "README.md").read_text(encoding="utf-8").count("\n")
    assert lines <= 200, f"README.md has {lines} lines: the rest belongs in docs/"


# ---- sizes (docs/developing.md, "Sizes") ----------------------------------------

SOURCE_SUFFIXES = {".c", ".cc", ".h", ".hpp", ".py", ".pyi", ".sh", ".cmake", ".md", ".in", ".toml"}
LONG_ALLOWED = {"python/simloop/_core.pyi"}  # stubtest checks only a stub's own classes: see "Sizes"


def test_no_source_file_is_over_450_lines_and_no_binding_over_350():
    too_long = []
    for path in tracked_files("", recursive=True):
        if Path(path).suffix not in SOURCE_SUFFIXES and Path(path).name != "CMakeLists.txt":
            continue
        if path.startswith("tests/golden/") or path in LONG_ALLOWED:
            continue
        limit = 350 if path.startswith("python/bindings") else 450
        lines = (ROOT / path).read_bytes().count(b"\n")
        if lines > limit:
            too_long.append(f"{path}: {lines} lines (at most {limit})")
    assert not too_long, "split these by topic (docs/developing.md, Sizes):\n" + "\n".join(too_long)


# ---- the layout ---------------------------------------------------------------


def layout() -> List[Tuple[str, List[str]]]:
    """docs/developing.md's layout: (top-level path, [names listed under it])."""
    text = (ROOT / "docs" / "developing.md").read_text(encoding="utf-8")
    block = text.split("## Layout\n", 1)[1].split("```text\n", 1)[1].split("```", 1)[0]
    entries: List[Tuple[str, List[str]]] = []
    for line in block.splitlines():
        if line and not line[0].isspace():
            entries.append((line.split()[0], []))
        elif line.startswith("  ") and not line.startswith("   "):
            entries[-1][1].append(line.split()[0])
    return entries


def tracked_files(folder: str, recursive: bool = False) -> List[str]:
    """The files directly in folder (or, recursive, anywhere under it, as paths from it) that git tracks (or,
    outside a clone, that exist)."""
    try:
        proc = subprocess.run(["git", "ls-files", "--", folder or "."], cwd=ROOT, capture_output=True, text=True)
    except FileNotFoundError:  # no git on this machine (a source tree copied or cloned elsewhere)
        proc = None
    if proc is not None and proc.returncode == 0 and proc.stdout:
        names = [p[len(folder) :] for p in proc.stdout.splitlines()]
    else:
        names = [] if recursive else [p.name for p in (ROOT / folder).iterdir() if p.is_file()]
        if recursive:
            for at, dirs, files in os.walk(ROOT / folder):
                dirs[:] = [d for d in dirs if not d.startswith((".", "build"))]  # no venvs, no build trees
                names += [(Path(at) / f).relative_to(ROOT / folder).as_posix() for f in files]
    return sorted(n for n in names if recursive or "/" not in n)


def test_the_layout_names_what_is_there():
    missing, unlisted = [], []
    for top, names in layout():
        if not list(ROOT.glob(top.rstrip("/"))):
            missing.append(top)
        for name in names:
            if not list((ROOT / top).glob(name.rstrip("/"))):
                missing.append(top + name)
        if names:  # a folder listed file by file: every file in it has its line
            listed = [p.name for name in names for p in (ROOT / top).glob(name.rstrip("/"))]
            unlisted += [top + f for f in tracked_files(top) if f not in listed]
    assert not missing, f"docs/developing.md's layout names what is not there: {missing}"
    assert not unlisted, f"docs/developing.md's layout lacks a line for: {unlisted}"
