#!/usr/bin/env python3
"""Checks an exercise answer by running the simulation: check.py N [--answer FILE].

Exit status: 0 the answer holds, 1 it does not, 2 there is no answer to check.
"""

import argparse
import importlib.util
import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
# The project's Python, which scripts/test.sh makes: .venv, or .venv-pypi
# where only the PyPI build was made (SIMLOOP_MUJOCO=pypi).
VENV_PYTHON = next(
    (
        python
        for python in (HERE.parent / venv / "bin" / "python" for venv in (".venv", ".venv-pypi"))
        if python.exists()
    ),
    HERE.parent / ".venv" / "bin" / "python",
)

try:
    import simloop
except ImportError:  # run as exercises/check.py by the system python3: use the project's venv
    if VENV_PYTHON.exists() and Path(sys.prefix).resolve() != VENV_PYTHON.parent.parent.resolve():
        os.execv(VENV_PYTHON, [str(VENV_PYTHON), *sys.argv])
    print("check.py: needs the simloop package: scripts/test.sh installs it into .venv", file=sys.stderr)
    sys.exit(2)

FOLDERS = {1: "01_timestep_edge", 2: "02_sticky_shove", 3: "03_predict_drift"}
# The questions as shipped: check.py grades these copies, never the files a
# learner edits (02_sticky_shove/loop.py is there to be fixed).
PRISTINE = HERE / "_pristine"

import re  # noqa: E402

from answers import NoAnswer, Verdict, answer_lines, quantity, remember_wrong  # noqa: E402
from drift import half_of_the_sum, rigid_sum, slide_phases, sum_beside_mujoco  # noqa: E402  (exercise 3's physics)

TIMESTEP = 0.002  # the chapter's, s


def _fmt(seconds: float) -> str:
    return f"{seconds:g} s"


def _shown(path: Path) -> str:
    """A path as a printed command gives it: relative when below the current folder."""
    try:
        return str(path.relative_to(Path.cwd()))
    except ValueError:
        return str(path)


def _python() -> str:
    """How to run this Python from here, as a hint prints it: the project's
    venv's python, else this one."""
    return _shown(VENV_PYTHON if VENV_PYTHON.exists() else Path(sys.executable))


# ---- 1. the timestep edge ---------------------------------------------------


def check_edge(path: Path) -> Verdict:
    predicted, _ = quantity(answer_lines(path)[0], "the prediction", ("time",), "s")
    if predicted <= 0:
        raise NoAnswer(f"the prediction must be a positive timestep, got {predicted:g} s")
    # The question as shipped: the default sweep (25 round timesteps, 0.0005 s
    # to 1 s, 4 s of sim time each) and the library's stability criterion.
    result = simloop.sweep(simloop._core.default_sweep_timesteps())
    points = result.points
    edge_index = next(i for i, p in enumerate(points) if p.timestep == result.edge)
    edge, first_unstable = result.edge, points[edge_index + 1].timestep
    low, high = edge / 1.5, first_unstable
    report = [f"you predicted {_fmt(predicted)}."]
    # What your own timestep does, by the same criterion and over the same 4 s.
    if predicted >= 2e-5:
        mine = simloop.sweep([predicted]).points[0]
        rise_mm = (mine.peak_box_z - simloop._core.BOX_REST_Z) * 1e3
        sink_mm = (simloop._core.BOX_REST_Z - mine.final_box_z) * 1e3
        verdict = "stable" if mine.stable else "unstable"
        detail = f"rose {rise_mm:.1f} mm above rest" + (
            f" and ended {sink_mm:.1f} mm into the floor" if sink_mm > 1.0 else ""
        )
        report.append(f"At {_fmt(predicted)} the box {detail}: {verdict} by the criterion.")
    else:
        mine = None
        report.append(f"({_fmt(predicted)} is too fine to run here: {4 / predicted:.0f} steps.)")
    # Right: in the band below the first unstable timestep, and stable itself
    # (an answer the same output calls unstable is never called right).
    holds = low <= predicted < high and (mine is None or mine.stable)
    if holds:
        # What the sweep measured up to the edge, not a figure from memory.
        rises = [(p.peak_box_z - simloop._core.BOX_REST_Z) * 1e3 for p in points[: edge_index + 1]]
        why = [
            f"Right. Below the edge the push lifts the box {min(rises):.1f} to {max(rises):.1f} mm through the "
            "contacts' softness (the sweep's timesteps up to the edge); past it each step extrapolates so far "
            "into the contact that the solver's correction "
            "throws the box up, and the contacts do positive work (the 'contacts +work' column) that no force "
            "explains. The chapter's 0.002 s has a factor of 2 to spare."
        ]
    elif predicted < high and mine is not None and not mine.stable:
        why = [
            f"Your {_fmt(predicted)} is unstable on its own, although the sweep's grid is stable up to "
            f"{_fmt(edge)}: near the edge the hop wavers around the 5 mm criterion, so the edge is a band rather "
            "than a line, and an answer must be stable itself. Try a little lower."
        ]
    elif predicted >= high or (mine is not None and not mine.stable):
        if mine is not None and mine.stable:
            why = [
                f"Your {_fmt(predicted)} is stable on its own, but it is past the edge: the edge is the largest "
                "timestep below which every timestep is stable, and some smaller ones are not."
            ]
        else:
            why = [f"Your {_fmt(predicted)} is already past the edge: the box hops or sinks there."]
        if predicted >= 0.05:
            why.append("At 0.05 s and beyond you are in Break It itself.")
    else:
        why = [
            f"Your {_fmt(predicted)} is stable, and so are timesteps well above it: the edge is higher. The "
            "chapter warns against 0.0002 s for the same reason: ten times the steps for nothing."
        ]
    python = _python()
    hint = [
        "Try a few timesteps before you predict again, each over the question's 4 s, and watch the box's height:",
        f"  {python} -m simloop --timestep T --steps N --no-perturb --plot    (N = 4 s / T: 2000 at 0.002 s; "
        "trajectory.png; stable: z stays under 0.055 m and ends above 0.049 m)",
    ]
    solution = [
        result.summary().rstrip("\n"),
        f"The edge is {_fmt(edge)}; the next timestep, {_fmt(first_unstable)}, is unstable. Accepted: "
        f"from {low:.2g} s up to, not including, {high:g} s, if stable itself. The edge is a band rather "
        "than a line: between 0.003 and 0.005 s the hop wavers around the 5 mm criterion "
        f"(`{python} -m simloop sweep --plot` draws the whole curve).",
    ]
    return Verdict(holds, report, why, hint, solution)


# ---- 2. the sticky shove ----------------------------------------------------


def load_module(path: Path, name: str):
    spec = importlib.util.spec_from_file_location(name, path)
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


# The chapter's own words for this answer ("Set it once and it pushes
# forever"): within a run, forever ends with the run's last step.
TO_THE_END = re.compile(
    r"(?:for ?ever|always|never stops|infinite(?:ly)?|(?:un)?til the end(?: of the run)?|"
    r"to the (?:end|last step)(?: of the run)?|(?:for )?(?:all )?the rest of the run|"
    r"every (?:remaining )?step(?: to the end)?)[.!]?",
    re.IGNORECASE,
)


def check_sticky(path: Path) -> Verdict:
    text = answer_lines(path)[0]
    # The question as shipped: the pristine loop, whatever the learner's copy now holds.
    shipped = load_module(PRISTINE / FOLDERS[2] / "loop.py", "shipped_loop")
    sim = shipped.chapter_loop(sim=CountingSim())
    actual, shove = sim.shoved, simloop.draw_shove(seed=0, steps=2000)
    after = 2000 - shove.start_step
    in_words = TO_THE_END.fullmatch(text.strip()) is not None
    if in_words:
        answer, said = actual, f"you answered {text.strip()!r}: in this run, to its last step, {actual} steps."
    else:
        value, dimension = quantity(text, "the number of steps", ("steps", "time"), "steps")
        answer = value / TIMESTEP if dimension == "time" else value
        answer = round(answer) if abs(answer - round(answer)) < 1e-6 else answer
        said = f"you answered {answer:g} step{'' if answer == 1 else 's'}" + (
            f" ({value:g} s at {TIMESTEP} s a step)." if dimension == "time" else "."
        )
    reference = simloop.run(seed=0)
    holds = answer == actual
    report = [
        f"simloop.run(seed=0): the box ends at y {reference.metrics['box_final_pos'][1]:.3f} m "
        f"(the shove pushed for {shove.steps} steps)",
        f"the shipped loop.py:  the box ends at y {sim.box_position[1]:.3f} m",
        said,
    ]
    if holds:
        why = [
            f"Right: written once at step {shove.start_step}, the force stayed in xfrc_applied and pushed on "
            f"every step to the end of the run, {actual} steps, {actual // shove.steps} times the chapter's "
            f"{shove.steps}. MuJoCo never clears it"
            + (": the chapter's 'forever', cut short by the run's end" if in_words else "")
            + ". The chapter's loop writes 0 explicitly on every step outside the shove's window for exactly "
            "this reason."
        ]
    elif abs(answer - actual) <= 2:
        why = [
            f"Off by {abs(answer - actual):g}: you have the idea. The force is written before step "
            f"{shove.start_step}'s mj_step, and the run's last step is step 1999: count the steps from one to "
            "the other, both included."
        ]
    elif answer == shove.steps:
        why = [
            f"{shove.steps} is how long the shove was meant to last (shove.steps), and it would be right if "
            "something stopped it after its window. Look for the line that does."
        ]
    elif answer == 1:
        why = [
            "1 would be right if MuJoCo cleared xfrc_applied after each step, as if a force were a kick. "
            "It does not: read what simloop.Sim.apply_force says about it."
        ]
    elif answer <= 0:
        why = ["Then the box would have stayed near its line, as it does in simloop.run: it did not."]
    elif answer > after:
        why = [
            f"The force is first written at step {shove.start_step} of 2000, so it cannot have pushed for "
            f"more than the {after} steps left."
        ]
    else:
        why = [
            f"Between {shove.steps} and the end of the run, yes, but not {answer:g}: ask what would ever "
            "change the force after it was written."
        ]
    hint = [
        "What does MuJoCo do with xfrc_applied between one mj_step and the next? Which line of loop.py would "
        "ever set it back to zero?"
    ]
    solution = [
        f"The shove pushed for {actual} steps, from step {shove.start_step} to the last step of the run: "
        "apply_force writes xfrc_applied once, and it persists until something writes it again. "
        f"{shove.force_y:+.1f} N for {actual * TIMESTEP:g} s instead of {shove.steps * TIMESTEP:g} s drives "
        f"the box {sim.box_position[1]:.1f} m off its line.",
        "The fix: clear the force when the window ends (sim.clear_force()), or write the force, zero "
        "outside the window, on every step, as the chapter's loop does. Then check the fix: "
        f"`{_python()} {_shown(HERE / 'check.py')} 2 --fix`.",
    ]
    return Verdict(holds, report, why, hint, solution)


def check_fix(loop_path: Path) -> bool:
    """Does the learner's loop.py now match simloop.run exactly? (Separate from the answer.)"""
    if not loop_path.is_file():
        raise NoAnswer(f"cannot read {loop_path}")
    if loop_path.read_bytes() == (PRISTINE / FOLDERS[2] / "loop.py").read_bytes():
        print(f"{loop_path.name} is still the shipped loop: the bug is still there. Fix it first.")
        return False
    module = load_module(loop_path, "learner_loop")
    ok = True
    for seed, steps in ((0, 2000), (2, 600), (1, 301)):
        sim = module.chapter_loop(seed=seed, steps=steps, sim=CountingSim())
        final = simloop.run(seed=seed, steps=steps).trajectory[-1]
        names = simloop.COLUMN_NAMES
        expected = {
            "box position": [final[names.index(c)] for c in ("box_x", "box_y", "box_z")],
            "box velocity": [final[names.index(c)] for c in ("box_vx", "box_vy", "box_vz")],
            "box orientation": [final[names.index(c)] for c in ("box_qw", "box_qx", "box_qy", "box_qz")],
            "pusher x": [final[names.index("pusher_x")]],
        }
        mine = {
            "box position": list(sim.box_position),
            "box velocity": list(sim.box_velocity),
            "box orientation": list(sim.box_quaternion),
            "pusher x": [sim.pusher_x],
        }
        differs = [k for k in expected if mine[k] != expected[k]]
        shove_steps = simloop.draw_shove(seed=seed, steps=steps).steps
        if differs:
            ok = False
            print(
                f"seed {seed}, {steps} steps: the shove pushed for {sim.shoved} steps (simloop.run: "
                f"{shove_steps}); differs from simloop.run in: {', '.join(differs)} "
                f"(box y {mine['box position'][1]:.6f} against {expected['box position'][1]:.6f} m)."
            )
        else:
            print(
                f"seed {seed}, {steps} steps: the same as simloop.run, bit for bit (the shove pushed for "
                f"{sim.shoved} steps)."
            )
    print("Your fix holds." if ok else "Your fix does not hold yet.")
    return ok


# ---- 3. below and above friction ---------------------------------------------


def check_drift(path: Path) -> Verdict:
    fields = {}
    for line in answer_lines(path):
        key, _, value = line.partition(":")
        if value.strip():
            fields[key.strip()] = value.strip()
    for key in ("stays_at_4N", "slide_at_9N_cm"):
        if key not in fields:
            raise NoAnswer(f"{path}: fill in {key}")
    stays = {"yes": "yes", "y": "yes", "no": "no", "n": "no"}.get(fields["stays_at_4N"].lower())
    if stays is None:
        raise NoAnswer(f"stays_at_4N must be yes or no, got {fields['stays_at_4N']!r}")
    predicted_m, _ = quantity(fields["slide_at_9N_cm"], "slide_at_9N_cm", ("length",), "cm")
    predicted_cm = predicted_m * 100
    # The question as shipped: a box at rest pushed for 0.1 s (drift.py).
    at4 = slide_phases(4.0)["end"]
    mujoco9 = slide_phases(9.0)
    at9 = mujoco9["end"]
    really_stays = abs(at4) < 0.002
    ok_stays = (stays == "yes") == really_stays
    low, high = at9 * 100 / 2, at9 * 100 * 2
    ok_slide = low <= predicted_cm <= high
    said = [f"4 N: you said it {'stays' if stays == 'yes' else 'moves'}.", f"9 N: you said {predicted_cm:g} cm."]
    sums = rigid_sum(9.0)
    friction = sums["friction"]
    # Why each part holds or not: said beside a right answer, or with the
    # solution. Before that, which part is wrong would give the yes/no half
    # away (a wrong yes is a no), so a first wrong answer hears neither.
    parts = []
    if ok_stays:
        parts.append(
            f"4 N: right. It is below what static friction can hold (m g mu = {friction:.2f} N); the box "
            f"only creeps {at4 * 1000:.2f} mm, through the contacts' softness."
        )
    else:
        parts.append(f"4 N: you expected it to {'stay' if stays == 'yes' else 'move more than 2 mm'}; it did not.")
    half = half_of_the_sum(predicted_cm, sums, at9 * 100, ok_slide)
    if half is not None:
        parts.append(half)
    elif ok_slide:
        parts.append(
            f"9 N: right: MuJoCo slid it {at9 * 100:.2f} cm; you said {predicted_cm:g} cm, within a factor of 2."
        )
    elif predicted_cm > high:
        parts.append(
            f"9 N: {predicted_cm:g} cm is more than twice what MuJoCo did. Friction acts during the push "
            "too, not only after it: only the force above friction accelerates the box."
        )
    else:
        parts.append(
            f"9 N: {predicted_cm:g} cm is less than half what MuJoCo did. The box does not stop when the "
            "push does: it coasts until friction has taken all its speed."
        )
    holds = ok_stays and ok_slide
    why = (
        parts
        if holds
        else [
            "One or both of your predictions do not hold. Which one stays unsaid for now: for the yes/no part, "
            "that alone would be the answer. The hint covers both."
        ]
    )
    hint = [
        "4 N: compare it with the largest force friction can hold on a 0.5 kg box (m g mu).",
        "9 N: the slide has two parts; add them. During the push only the force above friction accelerates "
        "the box (a = (9 N - friction) / m), so by the release, after 0.1 s, it has slid a t^2 / 2 and moves "
        "at v = a t; then it coasts until friction (a deceleration of mu g) has taken that speed, sliding "
        "v^2 / (2 mu g) more.",
    ]
    solution = (
        ([] if holds else parts)
        + [
            f"4 N: the box moved {at4 * 1000:.2f} mm (it stays). 9 N: it slid {at9 * 100:.2f} cm "
            f"(accepted: {low:.2f} to {high:.2f} cm)."
        ]
        + sum_beside_mujoco(9.0, sums, mujoco9)
    )
    return Verdict(holds, said, why, hint, solution)


# ---- grading ------------------------------------------------------------------

CHECKS = {1: check_edge, 2: check_sticky, 3: check_drift}


def grade(exercise: int, path: Path, reveal: bool) -> bool:
    verdict = CHECKS[exercise](path)
    print("\n".join(verdict.report))
    print("It holds." if verdict.holds else "It does not hold.")
    print("Why: " + "\n".join(verdict.why))
    if verdict.holds:
        print("\n".join(verdict.solution))
        return True
    tries = remember_wrong(path, exercise, " | ".join(answer_lines(path)))
    if reveal or tries >= 2:
        print("The solution:\n" + "\n".join(verdict.solution))
    else:
        print("Hint: " + "\n".join(verdict.hint))
        print("Change your answer and check again; a second, different wrong answer (or --reveal) shows the solution.")
    return False


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("exercise", type=int, choices=sorted(CHECKS))
    parser.add_argument("--answer", type=Path, help="the answer file (default: the exercise's answer.txt)")
    parser.add_argument("--reveal", action="store_true", help="show the solution even after a first wrong answer")
    parser.add_argument(
        "--fix",
        nargs="?",
        type=Path,
        const=HERE / FOLDERS[2] / "loop.py",
        default=None,
        metavar="LOOP",
        help="exercise 2 only: check your fixed loop.py (or LOOP) against simloop.run, instead of your answer",
    )
    args = parser.parse_args(argv)
    try:
        if args.fix is not None:
            if args.exercise != 2:
                raise NoAnswer("--fix is for exercise 2, the one with a loop to fix")
            return 0 if check_fix(args.fix) else 1
        path = args.answer or HERE / FOLDERS[args.exercise] / "answer.txt"
        return 0 if grade(args.exercise, path, args.reveal) else 1
    except NoAnswer as e:
        print(f"check.py: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
