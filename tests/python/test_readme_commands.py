"""The commands README.md and docs/ print work as printed after scripts/test.sh, with nothing
set by hand: no SIMLOOP_PYTHON, the venv's bin off PATH, the system python3."""

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import ROOT, sim_loop_exe
from simloop import _build

SYSTEM_PATH = "/usr/bin:/bin"  # as in a new shell: .venv/bin is not on it
# The venv scripts/test.sh makes for the build under test (sim_loop's --plot default).
VENV_PYTHON = ROOT / (".venv-pypi" if _build.MUJOCO_BUILD == "pypi" else ".venv") / "bin" / "python"


def test_sim_loop_plot_finds_the_projects_venv(tmp_path):
    proc = subprocess.run(
        [str(sim_loop_exe()), "--smoke", "--plot", "--out", "o"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        env={"PATH": SYSTEM_PATH},
    )
    if VENV_PYTHON.exists():  # scripts/test.sh made it
        assert proc.returncode == 0, proc.stderr
        assert (tmp_path / "o" / "trajectory.png").read_bytes()[:4] == b"\x89PNG"
    else:
        assert proc.returncode == 1
        assert proc.stderr.startswith("sim_loop: --plot: no Python with the simloop package was found (tried python3")
        assert len(proc.stderr.splitlines()) == 1


def _sim_loop_elsewhere(tmp_path: Path) -> Path:
    """build/sim_loop copied into a tree with no venv beside it."""
    exe = tmp_path / "elsewhere" / "build" / "sim_loop"
    exe.parent.mkdir(parents=True)
    shutil.copy2(sim_loop_exe(), exe)
    return exe


def test_sim_loop_plot_finds_python3_on_path_at_run_time(tmp_path):
    """No interpreter path is built in: the python3 on PATH, when it has simloop, draws."""
    proc = subprocess.run(
        [str(_sim_loop_elsewhere(tmp_path)), "--smoke", "--plot", "--out", "o"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        env={"PATH": f"{Path(sys.executable).parent}:{SYSTEM_PATH}"},
    )
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.splitlines()[-2] == "plot: o/trajectory.png"
    assert (tmp_path / "o" / "trajectory.png").read_bytes()[:4] == b"\x89PNG"


def test_sim_loop_plot_with_no_python_that_has_simloop_is_one_line_and_keeps_the_run(tmp_path):
    bin_dir = tmp_path / "bin"  # a python3 without the simloop package, first on PATH
    bin_dir.mkdir()
    (bin_dir / "python3").symlink_to(shutil.which("python3", path=SYSTEM_PATH) or "/usr/bin/python3")
    proc = subprocess.run(
        [str(_sim_loop_elsewhere(tmp_path)), "--smoke", "--plot", "--out", "o"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        env={"PATH": f"{bin_dir}:{SYSTEM_PATH}"},
    )
    if subprocess.run([str(bin_dir / "python3"), "-c", "import simloop"], capture_output=True).returncode == 0:
        pytest.skip("this machine's python3 has simloop itself: nothing to miss")
    assert proc.returncode == 1
    assert proc.stderr.splitlines() == [
        "sim_loop: --plot: no Python with the simloop package was found (tried python3; the outputs above were "
        "written): install it with scripts/setup.sh --package (or pip install . in a venv), or set SIMLOOP_PYTHON "
        "to a Python that has it"
    ]
    assert "trajectory: o/trajectory.csv (301 rows)" in proc.stdout
    assert sorted(p.name for p in (tmp_path / "o").iterdir()) == ["metrics.json", "trajectory.csv"]


def test_sim_loop_plot_without_a_python_is_one_line(tmp_path):
    proc = subprocess.run(
        [str(sim_loop_exe()), "--smoke", "--plot", "--out", "o"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        env={"SIMLOOP_PYTHON": "/nonexistent/python"},
    )
    assert proc.returncode == 1
    assert proc.stderr.splitlines() == [
        "sim_loop: --plot: cannot start /nonexistent/python (scripts/test.sh installs the simloop package into "
        "the project's .venv; or set SIMLOOP_PYTHON to a Python that has it)"
    ]


def test_viewer_line_names_a_rerun_that_exists(tmp_path):
    """`open it with: VIEWER PATH` works as typed where the command ran, also
    when rerun is only in the venv's bin, off PATH."""
    proc = subprocess.run(
        [sys.executable, "-m", "simloop", "--smoke", "--out", "o"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        env={"PATH": SYSTEM_PATH},
    )
    assert proc.returncode == 0, proc.stderr
    line = next(line for line in proc.stdout.splitlines() if line.startswith("recording: "))
    viewer, rrd = line.split(" -- open it with: ")[1].rsplit(" ", 1)
    assert rrd == os.path.join("o", "sim_loop.rrd")
    exe = tmp_path / viewer if os.sep in viewer else shutil.which(viewer, path=SYSTEM_PATH)
    assert exe and os.access(exe, os.X_OK), f"{viewer!r} in {line!r} is not a command there"
    assert os.path.samefile(exe, Path(sys.executable).with_name("rerun"))  # the viewer of this rerun-sdk


def test_check_py_runs_as_a_command(tmp_path):
    """`exercises/check.py N`: executable, and under the system python3 it
    re-runs itself with the project's .venv, which has simloop."""
    answer = tmp_path / "answer.txt"
    answer.write_text("# nothing yet\n")
    proc = subprocess.run(
        [str(ROOT / "exercises" / "check.py"), "1", "--answer", str(answer)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        env={"PATH": SYSTEM_PATH},
        timeout=120,
    )
    if VENV_PYTHON.exists():
        assert proc.returncode == 2, proc.stderr  # got as far as reading the (blank) answer
        assert "needs the simloop package" not in proc.stderr and "Traceback" not in proc.stderr
    else:
        assert proc.returncode == 2
        assert proc.stderr.startswith("check.py: needs the simloop package")


def test_callgrind_without_valgrind_is_one_line(tmp_path):
    proc = subprocess.run(
        [
            sys.executable,
            str(ROOT / "bench" / "bench_command.py"),
            "--callgrind",
            "--build",
            str(sim_loop_exe().parent),
        ],
        capture_output=True,
        text=True,
        env={"PATH": str(tmp_path)},
        timeout=60,
    )
    assert proc.returncode == 1
    assert proc.stderr.splitlines() == ["--callgrind: valgrind is not installed (apt-get install valgrind)"]
    assert proc.stdout == ""  # refused before measuring anything
