"""Each exercise's check accepts a right answer, rejects a wrong one, and asks for a missing one."""

import subprocess
import sys

import pytest

from conftest import ROOT

CHECK = ROOT / "exercises" / "check.py"


def check(exercise, answer_text, tmp_path):
    answer = tmp_path / "answer.txt"
    answer.write_text(answer_text)
    return subprocess.run([sys.executable, str(CHECK), str(exercise), "--answer", str(answer)],
                          capture_output=True, text=True, timeout=300)


@pytest.mark.parametrize("exercise, right, wrong", [
    (1, "# the edge\n0.003\n", "0.05\n"),                      # edge measured at 0.0033 s
    (2, "60\n", "50\n"),                                        # the shove persists to the next decision
    (3, "stays_at_4N: yes\nslide_at_9N_cm: 6\n",                # measured: 1.25 mm, 5.9 cm
     "stays_at_4N: no\nslide_at_9N_cm: 6\n"),
])
def test_check_accepts_right_and_rejects_wrong(exercise, right, wrong, tmp_path):
    accepted = check(exercise, right, tmp_path)
    assert accepted.returncode == 0, accepted.stdout + accepted.stderr
    assert "It holds." in accepted.stdout or "): holds." in accepted.stdout
    rejected = check(exercise, wrong, tmp_path)
    assert rejected.returncode == 1, rejected.stdout + rejected.stderr
    assert "not hold" in rejected.stdout


def test_a_wrong_slide_is_rejected(tmp_path):
    assert check(3, "stays_at_4N: yes\nslide_at_9N_cm: 40\n", tmp_path).returncode == 1


@pytest.mark.parametrize("exercise", [1, 2, 3])
def test_the_shipped_answer_files_are_blank(exercise, tmp_path):
    folder = {1: "01_timestep_edge", 2: "02_sticky_shove", 3: "03_predict_drift"}[exercise]
    blank = (ROOT / "exercises" / folder / "answer.txt").read_text()
    proc = check(exercise, blank, tmp_path)
    assert proc.returncode == 2
    assert "check.py:" in proc.stderr


def test_the_policy_loop_is_almost_right_and_wrong():
    sys.path.insert(0, str(ROOT / "exercises" / "02_sticky_shove"))
    try:
        import policy_loop
    finally:
        sys.path.pop(0)
    import simloop

    reference = simloop.run(seed=0).metrics["box_final_pos"][1]
    buggy = policy_loop.policy_loop().box_position[1]
    assert 0.01 < abs(buggy - reference) < 0.1  # close enough to look right, far enough to be wrong
