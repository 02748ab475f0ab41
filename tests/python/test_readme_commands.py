"""The README's commands work as printed after scripts/test.sh, with nothing
set by hand: no SIMLOOP_PYTHON, the venv's bin off PATH, the system python3."""

import subprocess
import sys

from conftest import ROOT, sim_loop_exe

SYSTEM_PATH = "/usr/bin:/bin"  # as in a new shell: .venv/bin is not on it
VENV_PYTHON = ROOT / ".venv" / "bin" / "python"


def test_sim_loop_plot_finds_the_projects_venv(tmp_path):
    proc = subprocess.run([str(sim_loop_exe()), "--smoke", "--plot", "--out", "o"], cwd=tmp_path,
                          capture_output=True, text=True, env={"PATH": SYSTEM_PATH})
    if VENV_PYTHON.exists():  # scripts/test.sh made it
        assert proc.returncode == 0, proc.stderr
        assert (tmp_path / "o" / "trajectory.png").read_bytes()[:4] == b"\x89PNG"
    else:
        assert proc.returncode == 1
        assert proc.stderr.startswith(f"sim_loop: --plot: cannot start {VENV_PYTHON} (scripts/test.sh")
        assert len(proc.stderr.splitlines()) == 1


def test_sim_loop_plot_without_a_python_is_one_line(tmp_path):
    proc = subprocess.run([str(sim_loop_exe()), "--smoke", "--plot", "--out", "o"], cwd=tmp_path,
                          capture_output=True, text=True, env={"SIMLOOP_PYTHON": "/nonexistent/python"})
    assert proc.returncode == 1
    assert proc.stderr.splitlines() == [
        "sim_loop: --plot: cannot start /nonexistent/python (scripts/test.sh installs the simloop package into "
        "the project's .venv; or set SIMLOOP_PYTHON to a Python that has it)"]
