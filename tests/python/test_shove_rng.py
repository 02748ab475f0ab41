"""--rng numpy draws the chapter's shove exactly as numpy does, without numpy.

numpy is the independent source here: np.random.default_rng(seed) is the
chapter's generator, and simloop's C++ reimplementation of PCG64 and
SeedSequence must give the very same doubles for every seed.
"""

import numpy as np
import pytest
import simloop
from conftest import run_command
from simloop import _core

U64_MAX = 2**64 - 1


def numpy_shove(seed):
    """The chapter's two lines, as it runs them."""
    rng = np.random.default_rng(seed)
    push_newtons = rng.uniform(6.0, 12.0)
    push_sign = rng.choice([-1.0, 1.0])
    return float(push_newtons), float(push_sign)


def seeds_to_check():
    # Small seeds (one 32-bit word of entropy), the word boundary, two-word
    # seeds up to 2**64 - 1, and a spread of random 64-bit seeds.
    edges = [2**32 - 1, 2**32, 2**32 + 1, 2**48 + 12345, 2**63 - 1, 2**63, U64_MAX - 1, U64_MAX]
    spread = np.random.default_rng(20240601).integers(0, U64_MAX, size=2000, dtype=np.uint64, endpoint=True)
    return list(range(3000)) + edges + [int(s) for s in spread]


def test_numpy_rng_matches_numpy_over_many_seeds():
    mismatches = []
    for seed in seeds_to_check():
        shove = _core.draw_shove(seed, 2000, "numpy")
        if (shove.newtons, shove.sign) != numpy_shove(seed):
            mismatches.append((seed, (shove.newtons, shove.sign), numpy_shove(seed)))
    assert not mismatches, mismatches[:5]


def test_the_issues_figures():
    # Quoted in issue 12 from numpy: seed 0 -> +9.821770123928726; 1, 2, 3.
    expected = {0: 9.821770123928726, 1: 9.07092974820154, 2: -7.569672805495898, 3: -6.513895002861746}
    for seed, force_y in expected.items():
        assert simloop.run(seed=seed, steps=10, rng="numpy").shove.force_y == force_y


def test_a_run_applies_the_numpy_shove():
    result = simloop.run(seed=0, rng="numpy")
    newtons, sign = numpy_shove(0)
    assert result.shove.rng == "numpy" and result.config.rng == "numpy"
    shove_y = result.column("shove_y")
    acting = np.flatnonzero(np.nan_to_num(shove_y) != 0.0)
    assert acting[0] == 1000 and len(acting) == 50
    assert np.all(shove_y[acting] == sign * newtons)


def test_the_default_is_still_mt19937_64():
    default = simloop.run(seed=0, steps=10)
    assert default.shove.rng == "mt19937_64" and default.config.rng == "mt19937_64"
    assert default.shove.newtons != numpy_shove(0)[0]
    # Explicitly naming it changes nothing.
    named = simloop.run(seed=0, steps=300, rng="mt19937_64")
    assert named.metrics_json() == simloop.run(seed=0, steps=300).metrics_json()
    assert named.trajectory_csv() == simloop.run(seed=0, steps=300).trajectory_csv()


def test_batch_takes_the_generator_too():
    batch = simloop.run_batch(seeds=[0, 1, 2], steps=20, rng="numpy", threads=2)
    assert [r.shove.force_y for r in batch.results] == [numpy_shove(s)[0] * numpy_shove(s)[1] for s in (0, 1, 2)]


@pytest.mark.parametrize("python", [True, False])
def test_both_commands_say_which_generator_drew_the_shove(tmp_path, python):
    proc = run_command(["--seed", "0", "--rng", "numpy", "--no-rerun", "--out", "o"], tmp_path, python=python)
    assert proc.returncode == 0, proc.stderr
    line = next(line for line in proc.stdout.splitlines() if line.startswith("shove:"))
    assert line.startswith("shove: +9.8 N in y for 50 steps -> ")
    assert line.endswith(" of sideways drift (drawn by numpy default_rng (PCG64) from seed 0)")
    default = run_command(["--smoke", "--no-rerun", "--out", "d"], tmp_path, python=python)
    assert "(drawn by std::mt19937_64 from seed 0)" in default.stdout


@pytest.mark.parametrize("python", [True, False])
def test_chapter_is_the_books_run_the_numpy_shove_and_the_same_bytes(tmp_path, python):
    """--chapter, named in the README's first screen: the book's +9.8 N, and
    exactly the files --rng numpy writes."""
    chapter = run_command(["--chapter", "--no-rerun", "--out", "c"], tmp_path, python=python)
    numpy_run = run_command(["--rng", "numpy", "--no-rerun", "--out", "n"], tmp_path, python=python)
    assert chapter.returncode == 0 and numpy_run.returncode == 0, chapter.stderr + numpy_run.stderr
    assert "shove: +9.8 N in y for 50 steps" in chapter.stdout
    for name in ("metrics.json", "trajectory.csv"):
        assert (tmp_path / "c" / name).read_bytes() == (tmp_path / "n" / name).read_bytes(), name
    refused = run_command(["--chapter", "--rng", "mt19937_64", "--out", "o"], tmp_path, python=python)
    assert refused.returncode == 2 and refused.stderr.count("\n") == 1, refused.stderr
    assert "--chapter draws the shove as the chapter does (--rng numpy)" in refused.stderr
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("python", [True, False])
def test_a_bad_generator_is_refused_by_name(tmp_path, python):
    proc = run_command(["--rng", "pcg64", "--out", "o"], tmp_path, python=python)
    assert proc.returncode == 2
    assert "--rng must be mt19937_64 or numpy, got 'pcg64'" in proc.stderr
    assert not (tmp_path / "o").exists()


def test_draw_shove_is_the_runs_shove_without_the_run():
    for rng in ("mt19937_64", "numpy"):
        drawn = simloop.draw_shove(seed=7, steps=600, rng=rng)
        ran = simloop.run(seed=7, steps=600, rng=rng).shove
        assert (drawn.newtons, drawn.sign, drawn.start_step, drawn.steps, drawn.rng) == (
            ran.newtons,
            ran.sign,
            ran.start_step,
            ran.steps,
            ran.rng,
        )
    with pytest.raises(ValueError, match="rng must be 'mt19937_64' or 'numpy', got 'pcg'"):
        simloop.draw_shove(rng="pcg")
    # A run's steps, checked by the library (its words); Python checks the type.
    with pytest.raises(ValueError, match=r"^steps must be from 1 to 4611686018427387903, got 0$"):
        simloop.draw_shove(steps=0)
    with pytest.raises(ValueError, match=r"^steps must be from 1 to 4611686018427387903, got 4611686018427387904$"):
        simloop.draw_shove(steps=2**62)
    with pytest.raises(TypeError, match=r"^steps must be an int, got 2.5 \(float\)$"):
        simloop.draw_shove(steps=2.5)
