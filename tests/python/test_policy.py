"""A policy in the loop: run_scenario / run / run_scenario_batch(policy=f,
control_every=K). The policy sees the recorded quantities every K steps and
its ctrl is held in between; writing what the scenario would write gives the
open-loop run's bits."""

import threading

import numpy as np
import pytest
import simloop

PUSHT = "tests/scenes/pusht.xml"


def constant_pusht(steps=600):
    return simloop.Scenario(
        scene=PUSHT,
        steps=steps,
        controls={"push_x": 0.8, "push_y": 0.3},
        disturbances=[
            dict(body="tblock", newtons=[0.5, 1.5], direction=[0, 1, 0], random_sign=True, start_step=250, steps=40)
        ],
    )


def same_bits(a, b):
    return a.shape == b.shape and np.array_equal(a.view(np.uint64), b.view(np.uint64))


@pytest.mark.parametrize("every", [1, 50, 10_000])
def test_a_policy_writing_the_scenarios_ctrl_gives_the_open_loop_bits(every):
    scenario = constant_pusht()
    open_loop = simloop.run_scenario(scenario, seed=4)
    closed = simloop.run_scenario(scenario, seed=4, policy=lambda obs: [0.8, 0.3], control_every=every)
    assert same_bits(open_loop.trajectory, closed.trajectory)
    other = simloop.run_scenario(scenario, seed=4, policy=lambda obs: [0.8, 0.31], control_every=every)
    assert not same_bits(open_loop.trajectory, other.trajectory)


def test_the_policy_sees_the_recorded_row_every_k_steps_and_its_ctrl_is_held():
    seen = []

    def policy(obs):
        seen.append((obs.step, obs.time, obs.values.copy(), obs["tblock_x"]))
        return [np.clip(4.0 * (0.45 - obs["tblock_x"]), -1, 1), np.sin(5.0 * obs.time)]

    result = simloop.run_scenario(constant_pusht(230), seed=1, policy=policy, control_every=50)
    assert [s[0] for s in seen] == [0, 50, 100, 150, 200]
    names = result.column_names[2:]
    ctrl = result.column("push_x_ctrl")
    for k, (step, time, values, tblock_x) in enumerate(seen):
        row = result.trajectory[step]
        assert time == row[1] and tblock_x == result.column("tblock_x")[step]
        for name, value, recorded in zip(names, values, row[2:]):
            if name.endswith("_ctrl") or name.endswith("_force"):
                continue  # the observation's are the previous decision's
            assert same_bits(np.array([value]), np.array([recorded])), (name, step)
        decided = np.clip(4.0 * (0.45 - tblock_x), -1, 1)
        assert np.all(ctrl[step : min(step + 50, 230)] == decided)  # held, and the scenario's 0.8 never shows
        assert values[names.index("push_x_ctrl")] == (0.0 if k == 0 else ctrl[step - 1])


def test_observation_values_are_read_only_and_named():
    def policy(obs):
        assert obs.names == result_names
        assert not obs.values.flags.writeable
        with pytest.raises(KeyError):
            obs["nope"]
        return [0.0, 0.0]

    result_names = simloop.run_scenario(constant_pusht(10), seed=0).column_names[2:]
    simloop.run_scenario(constant_pusht(10), seed=0, policy=policy, control_every=5)


def test_run_with_a_policy_is_the_chapters_scenario_loop():
    chapter = simloop.run_scenario(simloop.Scenario.chapter(), seed=3, steps=400)
    result = simloop.run(seed=3, steps=400, policy=lambda obs: 1.0, control_every=50)
    assert isinstance(result, simloop.ScenarioResult)
    assert same_bits(result.trajectory, chapter.trajectory)
    half = simloop.run(seed=3, steps=400, policy=lambda obs: np.array([0.5]), control_every=50)
    assert np.all(half.column("push_motor_ctrl")[:-1] == 0.5)
    # Without a policy, the chapter's own result, as before.
    assert isinstance(simloop.run(seed=3, steps=400), simloop.RunResult)
    with pytest.raises(ValueError, match="audit_energy"):
        simloop.run(policy=lambda obs: 1.0, audit_energy=True)


def test_an_exception_in_the_policy_stops_the_run_and_names_the_decision_step():
    calls = []

    def policy(obs):
        calls.append(obs.step)
        if obs.step == 100:
            raise ZeroDivisionError("no idea")
        return [0.0, 0.0]

    with pytest.raises(ZeroDivisionError, match=r"no idea \(policy at decision step 100\)"):
        simloop.run_scenario(constant_pusht(), policy=policy, control_every=25)
    assert calls == [0, 25, 50, 75, 100]


@pytest.mark.parametrize(
    "answer, error, words",
    [
        ([0.0], ValueError, r"^the policy must return 2 ctrl values, got 1 at decision step 20$"),
        ([0.0, 1.0, 2.0], ValueError, r"^the policy must return 2 ctrl values, got 3 at decision step 20$"),
        ([[0.0, 0.0]], ValueError, r"got shape \(1, 2\) at decision step 20"),
        (
            [0.0, float("nan")],
            ValueError,
            r"^the policy returned a ctrl that is not finite at decision step 20: ctrl\[1\] is nan$",
        ),
        ("left", ValueError, r"at decision step 20"),
        (None, ValueError, r"at decision step 20"),
    ],
)
def test_a_wrong_ctrl_is_a_value_error_naming_the_decision_step(answer, error, words):
    def policy(obs):
        return [0.0, 0.0] if obs.step < 20 else answer

    with pytest.raises(error, match=words):
        simloop.run_scenario(constant_pusht(), policy=policy, control_every=10)


def test_arguments_are_checked():
    with pytest.raises(TypeError, match="policy must be None or a callable"):
        simloop.run_scenario(constant_pusht(), policy=3)
    with pytest.raises(ValueError, match="control_every must be"):
        simloop.run_scenario(constant_pusht(), policy=lambda o: [0, 0], control_every=0)
    with pytest.raises(TypeError, match="control_every must be an int"):
        simloop.run_scenario(constant_pusht(), policy=lambda o: [0, 0], control_every=2.5)
    with pytest.raises(ValueError, match=r"^control_every=-1 needs a policy"):
        simloop.run(control_every=-1)


@pytest.mark.parametrize("threads", [1, 2])
def test_batches_with_a_policy_equal_sequential_runs(threads):
    scenario = constant_pusht(300)

    def policy(obs):  # depends on the observation only
        return [np.tanh(obs["tblock_x"] - 0.3), -np.tanh(obs["tblock_vy"])]

    batch = simloop.run_scenario_batch(
        scenario, seeds=range(4), timesteps=[None, 0.001], threads=threads, policy=policy, control_every=20
    )
    i = 0
    for seed in range(4):
        for timestep in (None, 0.001):
            alone = simloop.run_scenario(scenario, seed=seed, timestep=timestep, policy=policy, control_every=20)
            assert same_bits(batch.results[i].trajectory, alone.trajectory), (seed, timestep)
            i += 1


def test_a_batch_policy_is_called_with_the_gil_and_workers_step_in_between():
    # Two workers, one policy: a decision takes the GIL only for its call, so
    # while one worker's policy sleeps (holding no C++ lock) the other keeps
    # stepping; and the calls never overlap (the GIL).
    inside = []
    overlap = []
    lock = threading.Lock()

    def policy(obs):
        if not lock.acquire(blocking=False):
            overlap.append(obs.step)
        else:
            inside.append(threading.get_ident())
            lock.release()
        return [0.1, 0.1]

    simloop.run_scenario_batch(constant_pusht(400), seeds=range(6), threads=2, policy=policy, control_every=10)
    assert overlap == []
    assert len(inside) == 6 * 40


def test_between_decisions_the_gil_is_free():
    # A run in another thread, a decision every 10,000 steps: meanwhile this
    # thread keeps running Python.
    decisions = []
    worker = threading.Thread(
        target=lambda: simloop.run_scenario(
            constant_pusht(30_000), policy=lambda obs: decisions.append(obs.step) or [0.1, 0.1], control_every=10_000
        )
    )
    worker.start()
    spins = 0
    while worker.is_alive():
        spins += 1
    worker.join()
    assert decisions == [0, 10_000, 20_000]
    assert spins > 1000


def test_a_keyboard_interrupt_in_the_policy_stops_the_run():
    def policy(obs):
        if obs.step == 30:
            raise KeyboardInterrupt
        return [0.0, 0.0]

    with pytest.raises(KeyboardInterrupt):
        simloop.run_scenario(constant_pusht(), policy=policy, control_every=10)


def test_the_observation_names_are_the_runs_columns_checked_before_the_first_decision():
    seen = []
    for perturb in (True, False):
        result = simloop.run_scenario(
            constant_pusht(steps=30), perturb=perturb, policy=lambda obs: seen.append(obs.names) or [0, 0]
        )
        assert seen[-1] == tuple(result.column_names[2:])
    assert len(seen[0]) > len(seen[-1])  # the disturbance's force columns come and go with it
    calls = []
    with pytest.raises(ValueError, match="no body named 'tblok'"):
        simloop.run_scenario(
            simloop.Scenario(scene=PUSHT, steps=30, record={"bodies": ["tblok"]}),
            policy=lambda obs: calls.append(obs) or [0, 0],
        )
    assert calls == []
