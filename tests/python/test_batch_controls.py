"""Runs and batches of the caller's own controls and initial states, as
mujoco.rollout takes them: the same bits as the scenario's own per-step
controls, as each run alone at 1 and 2 threads, and as one longer run; bad
shapes and values refused by name before any step."""

import numpy as np
import pytest
import simloop
from conftest import ROOT

SCENES = ROOT / "tests" / "scenes"
PUSHT = SCENES / "pusht.toml"


def controls(seed, steps, nu=2, runs=None):
    shape = (steps, nu) if runs is None else (runs, steps, nu)
    return np.random.default_rng(seed).uniform(-0.9, 0.9, shape)


def same(a, b):
    return (
        a.column_names == b.column_names
        and a.trajectory.tobytes() == b.trajectory.tobytes()
        and a.final_state.tobytes() == b.final_state.tobytes()
        and a.metrics_json() == b.metrics_json()
    )


def test_own_controls_are_the_scenarios_per_step_controls_bit_for_bit(tmp_path):
    # The scenario's own way to give a value per step (a CSV file per
    # actuator) against the array: the same loop, so the same bits.
    u = controls(0, 120)
    for a, name in enumerate(("push_x", "push_y")):
        (tmp_path / f"{name}.csv").write_text(name + "\n" + "".join(f"{float(v)!r}\n" for v in u[:, a]))
    from_files = simloop.Scenario(
        scene=SCENES / "pusht.xml",
        steps=120,
        record={"bodies": ["tblock", "pusher"], "actuators": ["push_x", "push_y"]},
        controls={n: tmp_path / f"{n}.csv" for n in ("push_x", "push_y")},
    )
    bare = simloop.Scenario(
        scene=SCENES / "pusht.xml",
        steps=120,
        record={"bodies": ["tblock", "pusher"], "actuators": ["push_x", "push_y"]},
    )
    expected = simloop.run_scenario(from_files)
    got = simloop.run_scenario(bare, controls=u)
    assert same(got, expected)
    np.testing.assert_array_equal(got.column("push_y_ctrl")[:-1], u[:, 1])
    # And they replace a scenario's own controls (push_x at 0.8 in pusht.toml).
    replaced = simloop.run_scenario(PUSHT, steps=120, perturb=False, controls=u)
    np.testing.assert_array_equal(replaced.column("push_x_ctrl")[:-1], u[:, 0])


def test_the_disturbances_still_apply_with_own_controls():
    u = controls(1, 1000)
    pushed = simloop.run_scenario(PUSHT, steps=1000, seed=4, controls=u)
    calm = simloop.run_scenario(PUSHT, steps=1000, seed=4, controls=u, perturb=False)
    assert len(pushed.disturbances) == 1 and calm.disturbances == []
    assert pushed.final_state.tobytes() != calm.final_state.tobytes()


@pytest.mark.parametrize("threads", [1, 2])
def test_a_batch_of_own_controls_and_states_is_each_run_alone(threads):
    seeds, steps = [0, 1, 2], 200
    u = controls(2, steps, runs=6)
    start = simloop.run_scenario(PUSHT, steps=50, perturb=False).final_state
    starts = np.stack([start] * 6)
    starts[1::2, 0] += 0.25  # some runs start later in time (the state carries the time)
    alone = [
        simloop.run_scenario(PUSHT, seed=s, timestep=t, steps=steps, controls=u[i], initial_state=starts[i])
        for i, (s, t) in enumerate((s, t) for s in seeds for t in (0.002, 0.004))
    ]
    batch = simloop.run_scenario_batch(
        PUSHT, seeds=seeds, timesteps=[0.002, 0.004], steps=steps, controls=u, initial_state=starts, threads=threads
    )
    assert len(batch) == 6
    for i, (a, b) in enumerate(zip(batch.results, alone)):
        assert same(a, b), f"run {i}"
    assert batch.results[0].final_state.tobytes() != batch.results[2].final_state.tobytes()
    # One (steps, nu) array and one state for every run: broadcast.
    shared = simloop.run_scenario_batch(
        PUSHT, seeds=seeds, steps=steps, controls=u[0], initial_state=start, threads=threads
    )
    for s, r in zip(seeds, shared.results):
        assert same(r, simloop.run_scenario(PUSHT, seed=s, steps=steps, controls=u[0], initial_state=start))


@pytest.mark.parametrize("threads", [1, 2])
def test_a_metrics_only_batch_from_states_gives_the_kept_batchs_bits(threads):
    # A run from a whole state that nothing reads at t = 0 (metrics only) is neither reset nor derived first, and
    # records only its final row: the same bits as runs that record every row, whatever ran before in the same
    # Data (here runs from the scene's reset pose and from states alternate, the odd ones later in time).
    u = controls(5, 100, runs=6)
    start = simloop.run_scenario(PUSHT, steps=50, perturb=False).final_state
    starts = np.stack([start] * 6)
    starts[1::2, 0] += 0.25
    seeds = [0, 1, 2]
    for initial_state in (starts, None):
        asked = dict(seeds=seeds, timesteps=[0.002, 0.004], steps=100, controls=u, threads=threads)
        kept = simloop.run_scenario_batch(PUSHT, initial_state=initial_state, **asked).to_pandas()
        only = simloop.run_scenario_batch(PUSHT, initial_state=initial_state, metrics_only=True, **asked).to_pandas()
        assert kept.equals(only)
        assert len(set(kept["pusher_final_pos_x"])) == 6  # six runs, six places


def test_a_run_continued_from_its_final_state_is_one_longer_run():
    u = controls(3, 400)
    whole = simloop.run_scenario(PUSHT, steps=400, perturb=False, controls=u)
    half = simloop.run_scenario(PUSHT, steps=200, perturb=False, controls=u[:200])
    rest = simloop.run_scenario(PUSHT, steps=200, perturb=False, controls=u[200:], initial_state=half.final_state)
    assert rest.final_state.tobytes() == whole.final_state.tobytes()
    assert rest.trajectory[:, 1:].tobytes() == whole.trajectory[200:, 1:].tobytes()  # all but the step column
    assert rest.sim_time == whole.sim_time


def test_the_controls_array_is_read_in_place_and_left_unchanged():
    u = controls(4, 100)
    before = u.copy()
    simloop.run_scenario(PUSHT, steps=100, controls=u)
    assert u.tobytes() == before.tobytes()
    # Other layouts and integer arrays are converted, with the same result.
    assert same(
        simloop.run_scenario(PUSHT, steps=100, controls=np.asfortranarray(u)),
        simloop.run_scenario(PUSHT, steps=100, controls=u),
    )
    ints = np.zeros((100, 2), dtype=np.int32)
    assert same(
        simloop.run_scenario(PUSHT, steps=100, controls=ints),
        simloop.run_scenario(PUSHT, steps=100, controls=ints.astype(float)),
    )


@pytest.mark.parametrize(
    "kwargs, error, words",
    [
        (
            dict(controls=np.zeros((99, 2))),
            ValueError,
            "controls must have one row per step and one column per actuator, (100, 2) for this run, got (99, 2)",
        ),
        (dict(controls=np.zeros((100, 3))), ValueError, "got (100, 3)"),
        (dict(controls=np.zeros(100)), ValueError, "controls must be shaped (steps, nu), got shape (100,)"),
        (dict(controls="fast"), TypeError, "controls must be an array of numbers shaped (steps, nu), got 'fast'"),
        (dict(controls=[[1, 2], [3]]), TypeError, "controls must be an array of numbers"),
        (dict(controls=np.zeros((100, 2), dtype=bool)), TypeError, "got an array of dtype bool"),
        (
            dict(controls=np.where(np.arange(200).reshape(100, 2) == 75, np.nan, 0.0)),
            ValueError,
            "controls must be finite, got nan at step 37, actuator 1",
        ),
        (dict(initial_state=np.zeros(3)), ValueError, "initial_state must hold "),
        (
            dict(initial_state=np.zeros((1, 3))),
            ValueError,
            "initial_state must be shaped (state_size,), got shape (1, 3)",
        ),
    ],
)
def test_bad_inputs_are_refused_by_name(kwargs, error, words):
    with pytest.raises(error) as raised:
        simloop.run_scenario(PUSHT, steps=100, **kwargs)
    assert words in str(raised.value)


def test_a_non_finite_initial_state_is_refused():
    state = simloop.run_scenario(PUSHT, steps=10).final_state
    state[5] = np.inf
    with pytest.raises(ValueError, match=r"initial_state must be finite, got inf at index 5"):
        simloop.run_scenario(PUSHT, steps=10, initial_state=state)


def test_batch_inputs_must_have_one_entry_per_run():
    with pytest.raises(ValueError, match=r"controls: 2 runs' controls for 3 runs"):
        simloop.run_scenario_batch(PUSHT, seeds=[0, 1, 2], steps=100, controls=np.zeros((2, 100, 2)))
    with pytest.raises(ValueError, match=r"initial_state: 4 states for 3 runs"):
        simloop.run_scenario_batch(PUSHT, seeds=[0, 1, 2], steps=100, initial_state=np.zeros((4, 54)))
    # A bad run is named by its index, before any run starts.
    u = np.zeros((3, 100, 2))
    u[2, 7, 0] = np.nan
    with pytest.raises(ValueError, match=r"^run 2: controls must be finite, got nan at step 7, actuator 0$"):
        simloop.run_scenario_batch(PUSHT, seeds=[0, 1, 2], steps=100, controls=u)


def test_progress_counts_every_run_of_a_batch_with_inputs():
    seen = []
    table = simloop.run_scenario_batch(
        PUSHT,
        seeds=[0, 1, 2],
        steps=300,
        controls=controls(5, 300),
        metrics_only=True,
        progress=lambda done, total: seen.append((done, total)),
    )
    assert len(table) == 3
    assert seen[-1] == (900, 900) and all(total == 900 for _, total in seen)
    with pytest.raises(ZeroDivisionError):
        simloop.run_scenario(PUSHT, steps=300, controls=controls(5, 300), progress=lambda done, total: 1 / 0)


def test_the_chapters_scenario_with_its_own_control_as_an_array_is_the_same_run():
    chapter = simloop.Scenario.chapter()
    nu = simloop.Model.pusher_scene().nu
    ones = np.ones((2000, nu))
    assert same(simloop.run_scenario(chapter, controls=ones), simloop.run_scenario(chapter))
    assert not same(simloop.run_scenario(chapter, controls=ones * 0.5), simloop.run_scenario(chapter))
