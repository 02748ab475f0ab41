"""Goldens: what users can observe, byte for byte as tests/golden/ pins it.

Both commands (build/sim_loop and python -m simloop) and the Python API must
give the outputs scripts/make_goldens.py recorded: the smoke runs' files
whole, the other runs' files, stdouts and arrays by sha256 (the runs and
cases: golden_cases.py). The goldens are one MuJoCo build's bytes: a build
on a MuJoCo without a tests/golden/mujoco-X.Y.Z/ folder is skipped, naming
its version. A failure here means observable output changed; regenerate the
goldens only when that change is intended (see scripts/make_goldens.py).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Dict, Tuple

import golden_cases as g
import pytest
import simloop
from conftest import sim_loop_exe

PROGRAMS = ("sim_loop", "python -m simloop")


def _goldens(version: str, who: str) -> Tuple[Path, Dict[str, Any]]:
    directory = g.golden_dir(version)
    if not (directory / "manifest.json").is_file():
        pinned = sorted(p.name for p in g.GOLDEN_ROOT.glob("mujoco-*")) or ["none"]
        pytest.skip(
            f"{who} runs on {version}; the goldens are one MuJoCo build's bytes and tests/golden/ "
            f"holds them for {', '.join(pinned)} only"
        )
    return directory, g.load_manifest(directory)


@pytest.fixture(scope="module")
def sim_loop_goldens() -> Tuple[Path, Dict[str, Any]]:
    return _goldens(g.sim_loop_mujoco(sim_loop_exe()), str(sim_loop_exe()))


@pytest.fixture(scope="module")
def python_goldens() -> Tuple[Path, Dict[str, Any]]:
    return _goldens(simloop.MUJOCO_VERSION, f"simloop {simloop.__version__} (its _core)")


def first_difference(golden: bytes, got: bytes) -> str:
    """Where two texts part: the first differing line, numbered from 1."""
    a, b = golden.decode(errors="replace").splitlines(), got.decode(errors="replace").splitlines()
    for i, (x, y) in enumerate(zip(a, b)):
        if x != y:
            return f"first difference at line {i + 1}:\n  golden: {x}\n  got:    {y}"
    if len(a) != len(b):
        return f"the same first {min(len(a), len(b))} lines, then golden has {len(a)} lines, got {len(b)}"
    return "the same lines; the bytes differ in line endings or a final newline"


def check_output(who: str, name: str, data: bytes, golden: Dict[str, Any], directory: Path) -> None:
    """data against a golden entry: the kept file when there is one, else sha256 and size."""
    kept = golden.get("file") or golden.get("text")
    if kept:
        expected = (directory / kept).read_bytes()
        if data != expected:
            pytest.fail(
                f"{who}: {name} differs from {directory.relative_to(g.ROOT) / kept}: "
                f"{first_difference(expected, data)}",
                pytrace=False,
            )
        return
    got = g.file_entry(data)
    if got != {"sha256": golden["sha256"], "bytes": golden["bytes"]}:
        shown = f"; got:\n{data.decode(errors='replace')}" if len(data) <= 2000 else ""
        pytest.fail(
            f"{who}: {name} is {got['bytes']} bytes, sha256 {got['sha256']}; the golden "
            f"{golden['bytes']} bytes, sha256 {golden['sha256']}{shown}",
            pytrace=False,
        )


def golden_entry(manifest: Dict[str, Any], section: str, name: str) -> Dict[str, Any]:
    entry = manifest[section].get(name)
    if entry is None:
        pytest.fail(
            f"tests/golden has no {section} entry {name!r}: golden_cases.py lists it; if the new run is "
            "intended, regenerate with scripts/make_goldens.py",
            pytrace=False,
        )
    return entry


@pytest.mark.parametrize("program", PROGRAMS)
@pytest.mark.parametrize("run", g.COMMAND_RUNS, ids=[run.name for run in g.COMMAND_RUNS])
def test_command_writes_the_golden_files_and_stdout(run, program, tmp_path, request):
    python = program != "sim_loop"
    directory, manifest = request.getfixturevalue("python_goldens" if python else "sim_loop_goldens")
    entry = golden_entry(manifest, "commands", run.name)
    if entry["command"] != run.command():
        pytest.fail(
            f"{run.name}: the golden is of `{entry['command']}`, the test runs `{run.command()}`: "
            "regenerate the goldens if the new command line is intended",
            pytrace=False,
        )
    who = run.command(python=python)
    try:
        stdout, files = g.run_command(
            run, g.python_program() if python else [str(sim_loop_exe())], g.scratch(tmp_path), python=python
        )
    except RuntimeError as e:
        pytest.fail(str(e), pytrace=False)
    for name, data in files.items():
        check_output(who, name, data, entry["files"][name], directory)
    # The recording is not byte-reproducible (rerun's time-based ids): only whether it is written is pinned.
    recorded = (tmp_path / g.OUT / "sim_loop.rrd").is_file()
    assert recorded == (python and run.python_records()), f"{who}: sim_loop.rrd {'written' if recorded else 'missing'}"
    got = g.pinned_stdout(stdout, python=python).encode()
    golden = entry["python -m simloop stdout" if python else "stdout"]
    if python and "text" in entry["stdout"]:  # sim_loop's kept text, less its recording line
        expected = g.pinned_stdout((directory / entry["stdout"]["text"]).read_text(), python=True).encode()
        if got != expected:
            pytest.fail(
                f"{who}: stdout differs from {directory.relative_to(g.ROOT) / entry['stdout']['text']} "
                "(less its recording line): "
                f"{first_difference(expected, got)}",
                pytrace=False,
            )
    check_output(who, "stdout (filtered)", got, golden, directory)


API_RUNS = [run for run in g.COMMAND_RUNS if run.api is not None]


@pytest.mark.parametrize("run", API_RUNS, ids=[run.name for run in API_RUNS])
def test_api_writes_the_commands_golden_files(run, python_goldens, tmp_path):
    directory, manifest = python_goldens
    entry = golden_entry(manifest, "commands", run.name)
    for name, data in g.run_api(run, tmp_path / "out").items():
        check_output(f"{run.api_call()} (as `{run.command()}`)", name, data, entry["files"][name], directory)


@pytest.mark.parametrize("case", g.API_CASES, ids=[case.name for case in g.API_CASES])
def test_api_results_hash_as_the_goldens(case, python_goldens):
    if case.name.startswith("gym"):
        pytest.importorskip("gymnasium")
    _, manifest = python_goldens
    golden = golden_entry(manifest, "api", case.name)
    if golden["call"] != case.call:
        pytest.fail(f"{case.name}: the golden is of {golden['call']}, the test runs {case.call}", pytrace=False)
    got = {name: g.part_entry(value) for name, value in case.parts().items()}
    differ = [
        f"  {name}: golden {golden['parts'].get(name)}, got {got.get(name)}"
        for name in sorted(set(got) | set(golden["parts"]))
        if got.get(name) != golden["parts"].get(name)
    ]
    if differ:
        pytest.fail(f"{case.call}: {len(differ)} part(s) differ from the golden:\n" + "\n".join(differ), pytrace=False)


GOLDEN_DIRS = sorted(g.GOLDEN_ROOT.glob("mujoco-*"))


@pytest.mark.parametrize("directory", GOLDEN_DIRS, ids=[d.name for d in GOLDEN_DIRS])
def test_the_golden_folder_is_what_its_manifest_says(directory):
    """Each kept file hashes as listed, and nothing else lies in the folder
    (a stale file would pin nothing and mislead). Any MuJoCo's folder: no build is run."""
    manifest = g.load_manifest(directory)
    assert g.golden_dir(manifest["mujoco"]) == directory, f"{directory.name} holds {manifest['mujoco']}'s goldens"
    listed = {"manifest.json"}
    for entry in manifest["commands"].values():
        for golden in [*entry["files"].values(), entry["stdout"]]:
            kept = golden.get("file") or golden.get("text")
            if kept:
                listed.add(kept)
                data = (directory / kept).read_bytes()
                assert g.file_entry(data) == {"sha256": golden["sha256"], "bytes": golden["bytes"]}, (
                    f"{directory.name}/{kept}: not the sha256 and size the manifest lists"
                )
    present = {p.relative_to(directory).as_posix() for p in directory.rglob("*") if p.is_file()}
    assert present == listed, (
        f"files not in the manifest: {sorted(present - listed)}; missing: {sorted(listed - present)}"
    )
