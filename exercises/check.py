#!/usr/bin/env python3
"""Checks an exercise answer by running the simulation: check.py N [--answer FILE].

Exit status: 0 the answer holds, 1 it does not, 2 there is no answer to check.
"""

import argparse
import importlib.util
import os
import sys
from pathlib import Path

try:
    import simloop
except ImportError:  # run as exercises/check.py by the system python3: use the project's .venv
    VENV_PYTHON = Path(__file__).resolve().parent.parent / ".venv" / "bin" / "python"
    if VENV_PYTHON.exists() and Path(sys.prefix).resolve() != VENV_PYTHON.parent.parent.resolve():
        os.execv(VENV_PYTHON, [str(VENV_PYTHON), *sys.argv])
    print("check.py: needs the simloop package: scripts/test.sh installs it into .venv", file=sys.stderr)
    sys.exit(2)

HERE = Path(__file__).resolve().parent
FOLDERS = {1: "01_timestep_edge", 2: "02_sticky_shove", 3: "03_predict_drift"}


class NoAnswer(Exception):
    pass


def answer_lines(path: Path) -> list:
    try:
        text = path.read_text()
    except OSError as e:
        raise NoAnswer(f"cannot read {path}: {e.strerror}")
    lines = [line.strip() for line in text.splitlines() if line.strip() and not line.strip().startswith("#")]
    if not lines:
        raise NoAnswer(f"{path} holds no answer yet: write it there first")
    return lines


def number(text: str, what: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise NoAnswer(f"{what} must be a number, got {text!r}")
    return value


def check_edge(path: Path) -> bool:
    predicted = number(answer_lines(path)[0], "the prediction")
    result = simloop.sweep()
    edge = result.edge
    print(result.summary(), end="")
    holds = edge / 1.5 <= predicted <= edge * 1.5
    print(f"\nyou predicted {predicted:g} s; the sweep's edge is {edge:g} s "
          f"(accepted: {edge / 1.5:.4g} to {edge * 1.5:.4g} s).")
    print("It holds." if holds else "It does not hold.")
    print("Why: below the edge the push lifts the box 2 to 5 mm through the contacts' softness, whatever the "
          "timestep; past it, each step extrapolates so far into the contact that the solver's correction throws "
          "the box up, and the contacts do positive work (the 'contacts +work' column) that no force explains.")
    return holds


def load_policy_loop():
    spec = importlib.util.spec_from_file_location("policy_loop", HERE / FOLDERS[2] / "policy_loop.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


class CountingSim(simloop.Sim):
    """A Sim that steps one step at a time and counts the steps with a force on the box."""

    shoved = 0

    def step(self, n=1, ctrl=None):
        for _ in range(n):
            self.shoved += bool(self.applied_force[1] != 0.0)
            super().step(1, ctrl)


def check_sticky(path: Path) -> bool:
    answer = number(answer_lines(path)[0], "the number of steps")
    module = load_policy_loop()
    sim = module.policy_loop(sim=CountingSim())
    actual = sim.shoved
    reference = simloop.run(seed=0)
    print(f"simloop.run:         box final y {reference.metrics['box_final_pos'][1]:.6f} m (shove for 50 steps)")
    print(f"policy_loop.py:      box final y {sim.box_position[1]:.6f} m")
    print(f"the buggy loop shoved for {actual} steps; you answered {answer:g}.")
    holds = answer == actual
    print("It holds." if holds else "It does not hold.")
    print(f"Why: the policy decides at steps 1000, 1020, 1040 and 1060. At 1040 the window is still open, so it "
          f"writes the shove, and xfrc_applied PERSISTS: MuJoCo keeps applying it on every one of the next "
          f"{module.DECIDE_EVERY} steps until the decision at 1060 clears it. The shove lasts until the next "
          f"decision, not until its window closes.")
    return holds


def slide(force: float) -> float:
    """Sideways distance (m) of a box at rest pushed with `force` N for 50 steps, then left for 500."""
    sim = simloop.Sim()
    sim.step(100)  # settle on the floor, motor off
    y0 = sim.box_position[1]
    sim.apply_force([0.0, force, 0.0])
    sim.step(50)
    sim.clear_force()
    sim.step(500)
    return sim.box_position[1] - y0


def check_drift(path: Path) -> bool:
    fields = {}
    for line in answer_lines(path):
        key, _, value = line.partition(":")
        if value.strip():
            fields[key.strip()] = value.strip()
    for key in ("stays_at_4N", "slide_at_9N_cm"):
        if key not in fields:
            raise NoAnswer(f"{path}: fill in {key}")
    stays = fields["stays_at_4N"].lower()
    if stays not in ("yes", "no"):
        raise NoAnswer(f"stays_at_4N must be yes or no, got {fields['stays_at_4N']!r}")
    predicted_cm = number(fields["slide_at_9N_cm"], "slide_at_9N_cm")
    at4, at9 = slide(4.0), slide(9.0)
    really_stays = abs(at4) < 0.002
    ok_stays = (stays == "yes") == really_stays
    ok_slide = at9 * 100 / 2 <= predicted_cm <= at9 * 100 * 2
    print(f"4 N: the box moved {at4 * 1000:.2f} mm ({'stays' if really_stays else 'moves'}); you said "
          f"{stays}: {'holds' if ok_stays else 'does not hold'}.")
    print(f"9 N: the box slid {at9 * 100:.2f} cm; you said {predicted_cm:g} cm (accepted: {at9 * 50:.2f} to "
          f"{at9 * 200:.2f}): {'holds' if ok_slide else 'does not hold'}.")
    friction = 0.5 * 9.81 * 1.0
    v = (9.0 - friction) / 0.5 * 0.1
    sum_cm = (0.5 * (9.0 - friction) / 0.5 * 0.1**2 + v * v / (2 * 9.81)) * 100
    print(f"The sum: 9 N - {friction:.2f} N friction = {9 - friction:.2f} N net on 0.5 kg for 0.1 s gives "
          f"{v:.2f} m/s and {sum_cm:.1f} cm in all. MuJoCo's contacts are soft: the box creeps even below "
          f"friction (about 1 mm at 4 N), and the friction cone is approximated, so the real slide differs.")
    return ok_stays and ok_slide


CHECKS = {1: check_edge, 2: check_sticky, 3: check_drift}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("exercise", type=int, choices=sorted(CHECKS))
    parser.add_argument("--answer", type=Path, help="the answer file (default: the exercise's answer.txt)")
    args = parser.parse_args(argv)
    path = args.answer or HERE / FOLDERS[args.exercise] / "answer.txt"
    try:
        return 0 if CHECKS[args.exercise](path) else 1
    except NoAnswer as e:
        print(f"check.py: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
