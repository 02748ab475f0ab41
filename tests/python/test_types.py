"""The type stub of simloop._core (python/simloop/_core.pyi) against the module.

Three checks, each failing with what to change in the stub:
- mypy's stubtest: names the module has and the stub lacks (and the reverse);
- pybind11's own signatures (the docstrings it writes, which stubtest cannot
  read) against the stub's: parameters, defaults, argument and return types,
  writable properties, constructors; each difference comes with the stub line
  the module's signature suggests (stub_signatures.py);
- mypy --strict on the package and on an example of the public API
  (typing_example.py), which also runs, and on misuse that must be a type
  error (typing_misuse.py).
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path
from typing import Dict, List

import pytest
import simloop
from stub_signatures import _compare, _Stub

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
STUB = ROOT / "python" / "simloop" / "_core.pyi"
ALLOWLIST = HERE / "stubtest_allowlist.txt"
FIX = (
    "update python/simloop/_core.pyi, then reinstall the package "
    "(.venv/bin/pip install --no-deps .) so that the installed stub is the new one"
)


@pytest.fixture(scope="module")
def mypy_cache(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """One mypy cache for this file's runs: the later runs reuse what the first one read (numpy's stubs)."""
    return tmp_path_factory.mktemp("mypy_cache")


def _mypy(*args: str, cache: Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "mypy", "--cache-dir", str(cache), *args],
        cwd=ROOT,
        capture_output=True,
        text=True,
        stdin=subprocess.DEVNULL,
        timeout=300,
    )


def test_the_installed_package_ships_this_stub_and_py_typed():
    installed = Path(simloop.__file__).parent
    assert (installed / "py.typed").is_file(), f"{installed} has no py.typed: type checkers would ignore the stub"
    stub = installed / "_core.pyi"
    assert stub.is_file(), f"{installed} has no _core.pyi: the wheel does not ship the stub"
    assert stub.read_text() == STUB.read_text(), (
        f"the installed {stub} is not python/simloop/_core.pyi: reinstall (.venv/bin/pip install --no-deps .)"
    )


# stubtest's report, one error per paragraph: "error: NAME WHAT\nStub: ...\nRuntime: ...".
def _stubtest_errors(output: str) -> List[str]:
    errors = []
    for block in re.split(r"\n(?=error: )", output.strip()):
        if not block.startswith("error: "):
            continue
        lines = [line for line in block.splitlines() if not line.startswith("Stub: in file")]
        errors.append("\n    ".join(lines))
    return errors


HINTS = {
    "is not present in stub": "the module has it and the stub does not: add it",
    "is not present at runtime": "the stub has it and the module does not: remove it (or bind it)",
    "metaclass differs": "a pybind11 class: declare it as `class Name(metaclass=_Pybind11Type):`",
}


def test_stubtest_finds_no_difference():
    """stubtest on the installed simloop._core (as the package leaves it after import)."""
    proc = subprocess.run(
        [sys.executable, "-m", "mypy.stubtest", "simloop._core", "--allowlist", str(ALLOWLIST)],
        capture_output=True,
        text=True,
        stdin=subprocess.DEVNULL,
        timeout=300,
        cwd=HERE,
    )
    if proc.returncode == 0:
        return
    errors = _stubtest_errors(proc.stdout)
    lines = []
    for error in errors:
        hint = next((h for key, h in HINTS.items() if key in error.splitlines()[0]), "")
        lines.append(f"- {error}" + (f"\n    -> {hint}" if hint else ""))
    pytest.fail(
        f"mypy.stubtest: python/simloop/_core.pyi and simloop._core disagree ({len(errors)}); {FIX}\n"
        + ("\n".join(lines) if lines else proc.stdout + proc.stderr),
        pytrace=False,
    )


def test_pybind11_signatures_match_the_stub():
    problems = _compare(_Stub(STUB))
    if problems:
        pytest.fail(
            f"python/simloop/_core.pyi and pybind11's signatures of simloop._core disagree "
            f"({len(problems)}): update the stub (numpy.ndarray is written _Float64Array; check its dtype)\n"
            + "\n".join(f"- {p}" for p in problems),
            pytrace=False,
        )


def test_the_comparison_sees_a_missing_parameter_and_a_wrong_type(tmp_path):
    """The check above can fail: a stub with one parameter dropped and one return type changed."""
    text = STUB.read_text()
    broken = text.replace(
        "def run(model: Model, config: RunConfig, progress: _Progress = None) -> RunResult: ...",
        "def run(model: Model, config: RunConfig) -> RunResult: ...",
    )
    broken = broken.replace("    def ctrl(self) -> float: ...", "    def ctrl(self) -> int: ...")
    assert broken.count("\n") == text.count("\n") and broken != text
    (tmp_path / "_core.pyi").write_text(broken)
    new = sorted(set(_compare(_Stub(tmp_path / "_core.pyi"))) - set(_compare(_Stub(STUB))))
    assert len(new) == 2, new
    assert new[0].startswith(
        "Sim.ctrl: returns float in the module, int in the stub; the module has: @property def ctrl(self) -> float: ..."
    ), new
    assert new[1].startswith(
        "run: parameters (model, config, progress) in the module, (model, config) in the stub; "
        "the module has: def run(model: Model, config: RunConfig, progress: object = None)"
    ), new


# ---- mypy --strict ------------------------------------------------------------


def test_the_package_passes_mypy_strict(mypy_cache):
    """python/simloop with the stub, under pyproject.toml's [tool.mypy] (strict)."""
    proc = _mypy(cache=mypy_cache)
    assert proc.returncode == 0, (
        f"mypy (pyproject.toml's [tool.mypy], strict) on python/simloop:\n{proc.stdout}{proc.stderr}"
    )


def test_an_example_of_the_public_api_type_checks_and_runs(mypy_cache):
    """typing_example.py asserts the types mypy infers (assert_type) and runs, so they are the runtime's too."""
    example = HERE / "typing_example.py"
    proc = _mypy("--strict", str(example), cache=mypy_cache)
    assert proc.returncode == 0, f"mypy --strict {example.name}:\n{proc.stdout}{proc.stderr}"
    ran = subprocess.run(
        [sys.executable, str(example)], capture_output=True, text=True, stdin=subprocess.DEVNULL, timeout=120, cwd=HERE
    )
    assert ran.returncode == 0, ran.stderr


def test_misuse_of_the_api_is_a_type_error(mypy_cache):
    """Each line of typing_misuse.py marked `# error: CODE` is a mypy error with that code, and no other line
    is: the stub's types are precise, not Any."""
    misuse = HERE / "typing_misuse.py"
    expected = {
        i: m.group(1)
        for i, line in enumerate(misuse.read_text().splitlines(), 1)
        if (m := re.search(r"# error: ([\w-]+)", line))
    }
    assert len(expected) >= 8
    proc = _mypy("--strict", "--show-error-codes", "--no-pretty", str(misuse), cache=mypy_cache)
    found: Dict[int, List[str]] = {}
    for line in proc.stdout.splitlines():
        m = re.match(rf"^.*{misuse.name}:(\d+): error: .*\[([\w-]+)\]$", line)
        if m:
            found.setdefault(int(m.group(1)), []).append(m.group(2))
    missed = {n: code for n, code in expected.items() if code not in found.get(n, [])}
    extra = {n: codes for n, codes in found.items() if n not in expected}
    assert not missed and not extra, (
        f"lines mypy did not flag as expected: {missed}; unexpected errors: {extra}\n{proc.stdout}"
    )
