"""Batches past one machine: chunks on a Dask cluster (in-process LocalCluster
and a real `dask scheduler` with `dask worker` processes), on any
concurrent.futures executor (`python -m simloop batch` into Parquet: test_batch_command.py).
Results are compared bit for bit with local runs; a worker is killed mid-batch;
an interrupted batch is resumed."""

from __future__ import annotations

import math
import multiprocessing
import os
import signal
import threading
from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor

import numpy as np
import psutil
import pytest
import simloop
from conftest import NO_WORKER_PROCESSES, ROOT, run_python
from simloop import _core, distributed

SEEDS = range(30)
TIMESTEPS = [0.002, 0.004]
STEPS = 400
PUSHT = ROOT / "tests" / "scenes" / "pusht.toml"


@pytest.fixture(scope="module")
def local():
    return simloop.run_batch(SEEDS, TIMESTEPS, steps=STEPS, threads=2)


@pytest.fixture(scope="module")
def client():
    from distributed import Client, LocalCluster

    if NO_WORKER_PROCESSES:
        pytest.skip(NO_WORKER_PROCESSES)

    with LocalCluster(n_workers=2, processes=True, threads_per_worker=1, dashboard_address=":0") as cluster:
        with Client(cluster) as c:
            yield c


def assert_same_as_local(table, local) -> None:
    """The table is the local batch's (kept rows) column for column, bit for bit, without its results; and
    every column the table takes from the final state equals the local run's."""
    assert isinstance(table, simloop.BatchTable) and not table.has_results
    assert table == local and table.column_names == local.column_names
    runs = local.results
    assert len(table) == len(runs)
    final = np.array([r.trajectory[-1] for r in runs])
    at = {name: final[:, k] for k, name in enumerate(simloop.COLUMN_NAMES)}
    assert np.array_equal(table["run"], np.arange(len(runs)))
    assert np.array_equal(table["seed"], np.array([r.config.seed for r in runs], dtype=np.uint64))
    assert np.array_equal(table["timestep"], np.array([r.timestep for r in runs]))
    for axis in "xyz":
        assert np.array_equal(table[f"box_final_pos_{axis}"], at[f"box_{axis}"])
    assert np.array_equal(table["pusher_final_x"], at["pusher_x"])
    speed = [math.sqrt(vx * vx + vy * vy + vz * vz) for vx, vy, vz in zip(at["box_vx"], at["box_vy"], at["box_vz"])]
    assert np.array_equal(table["box_final_speed"], np.array(speed))
    # The metric, rounded as metrics.json rounds it, agrees too (a second, independent route).
    assert np.array_equal(np.round(table["box_final_speed"], 6), [r.metrics["box_final_speed"] for r in runs])
    assert np.array_equal(table["shove_force_y"], [r.shove.force_y for r in runs])
    assert table["warning_mjWARN_BADQACC"].sum() == sum(
        w.count for r in runs for w in r.warnings if w.name == "mjWARN_BADQACC"
    )


def test_a_local_cluster_gives_the_bits_of_a_local_batch(client, local):
    seen = []
    table = simloop.run_batch(
        SEEDS,
        TIMESTEPS,
        steps=STEPS,
        executor=client,
        chunk_size=7,
        progress=lambda done, total: seen.append((done, total)),
    )
    assert isinstance(table, simloop.BatchTable)
    assert_same_as_local(table, local)
    assert seen[-1] == (60, 60) and len(seen) == 9  # one call per chunk of 7 (the last has 4)
    assert table.to_arrow().num_rows == 60 and list(table.to_pandas().columns) == table.column_names
    # The whole table is a local metrics-only batch's too, column for column (`run` included), bit for bit.
    alone = simloop.run_batch(SEEDS, TIMESTEPS, steps=STEPS, metrics_only=True)
    assert table == alone and [table[k].dtype for k in table] == [alone[k].dtype for k in alone]


def test_scenario_batches_and_sweeps_on_a_cluster_are_the_local_bits(client):
    scenario = simloop.Scenario.from_file(PUSHT)
    local = simloop.run_scenario_batch(scenario, seeds=range(5), timesteps=[None, 0.004])
    table = simloop.run_scenario_batch(PUSHT, seeds=range(5), timesteps=[None, 0.004], executor=client, chunk_size=3)
    assert table == local and not table.has_results  # the local batch's table, `run` and all
    for body in ("tblock", "pusher"):
        for axis in "xyz":
            assert np.array_equal(
                table[f"{body}_final_pos_{axis}"], [r.column(f"{body}_{axis}")[-1] for r in local.results]
            )
    assert np.array_equal(table["disturbance0_fy"], [r.disturbances[0]["force"][1] for r in local.results])
    assert np.array_equal(table["steps"], [r.steps for r in local.results])

    timesteps = [0.004, 0.001, 0.05, 0.002, 0.004]
    swept = simloop.sweep(timesteps, duration=1.0, executor=client, chunk_size=2)
    alone = simloop.sweep(timesteps, duration=1.0)
    assert swept.csv() == alone.csv() and swept.edge == alone.edge and swept.summary() == alone.summary()


def own_inputs(runs, steps):
    """Per-run controls and initial states for PushT: fixed test data (not a run's draws), states from a Sim."""
    controls = np.random.default_rng(5).uniform(-1, 1, size=(runs, steps, 2))
    sim = simloop.Sim(simloop.Scenario.from_file(PUSHT))
    states = []
    for i in range(runs):
        sim.step(10 + i, ctrl=np.array([0.6, 0.1 * i]))
        states.append(sim.get_state())
    return controls, np.array(states)


def test_controls_and_initial_states_go_to_a_cluster_in_chunks_with_the_local_bits(client):
    steps, seeds, timesteps = 150, range(4), [None, 0.004]
    controls, states = own_inputs(8, steps)
    kwargs = dict(seeds=seeds, timesteps=timesteps, steps=steps, controls=controls, initial_state=states)
    local = simloop.run_scenario_batch(PUSHT, **kwargs)
    table = simloop.run_scenario_batch(PUSHT, executor=client, chunk_size=3, **kwargs)
    assert table == local and not table.has_results  # chunks of 3, 3 and 2 runs: each its own rows
    assert np.array_equal(table["tblock_final_pos_x"], [r.column("tblock_x")[-1] for r in local.results])
    alone = simloop.run_scenario_batch(PUSHT, seeds=seeds, timesteps=timesteps, steps=steps)
    assert not np.array_equal(table["pusher_final_pos_x"], alone["pusher_final_pos_x"])  # the inputs were used


def test_shared_controls_and_states_go_to_an_executor_and_bad_shapes_are_refused_before_any_work():
    steps = 120
    controls, states = own_inputs(6, steps)
    kwargs = dict(seeds=range(3), timesteps=[None, 0.004], steps=steps, controls=controls[2], initial_state=states[4])
    local = simloop.run_scenario_batch(PUSHT, metrics_only=True, **kwargs)
    with ThreadPoolExecutor(2) as pool:
        assert simloop.run_scenario_batch(PUSHT, executor=pool, chunk_size=4, **kwargs) == local
        per_run = dict(kwargs, controls=controls, initial_state=states)
        assert simloop.run_scenario_batch(PUSHT, executor=pool, chunk_size=4, **per_run) == (
            simloop.run_scenario_batch(PUSHT, metrics_only=True, **per_run)
        )
        started = []
        with pytest.raises(ValueError, match=r"^controls: 5 runs' controls for 6 runs$"):
            simloop.run_scenario_batch(
                PUSHT, executor=pool, progress=lambda *a: started.append(a), **dict(per_run, controls=controls[:5])
            )
        with pytest.raises(ValueError, match=r"^initial_state must be shaped \(runs, state_size\) or \(state_size,\)"):
            simloop.run_scenario_batch(PUSHT, executor=pool, **dict(kwargs, initial_state=states[None, None]))
        assert started == []
        with pytest.raises(ValueError, match="^policy with controls, initial_state or metrics_only is not supported"):
            simloop.run_scenario_batch(PUSHT, executor=pool, policy=lambda obs: [0.0, 0.0], **kwargs)


def test_a_worker_killed_mid_batch_loses_nothing(client):
    seeds, steps = range(48), 2000
    local = simloop.run_batch(seeds, [0.002], steps=steps, threads=2)
    pids = client.run(os.getpid)
    address, victim = next(iter(pids.items()))
    killed = []

    def kill_once(done, total):
        if not killed:  # the first chunk is back: the others are in flight
            killed.append((done, len(client.processing()[address])))  # what the victim is working on
            os.kill(victim, signal.SIGKILL)

    table = simloop.run_batch(seeds, [0.002], steps=steps, executor=client, chunk_size=4, progress=kill_once)
    assert killed and killed[0][0] < len(local) and killed[0][1] >= 1  # killed mid-batch, mid-chunk
    assert_same_as_local(table, local)
    assert not psutil.pid_exists(victim) or psutil.Process(victim).status() == psutil.STATUS_ZOMBIE
    client.wait_for_workers(2, timeout=60)  # the nanny brings a new one up for the other tests


def test_a_worker_of_another_version_is_refused_before_any_work(client, monkeypatch):
    # The workers report their real versions; this client now claims another.
    monkeypatch.setattr(distributed, "versions", lambda: ("9.9.9", _core.MUJOCO_VERSION))
    with pytest.raises(
        distributed.VersionMismatch,
        match=r"^worker tcp://127\.0\.0\.1:\d+ has simloop " + _core.__version__ + r" .* the client simloop 9\.9\.9 ",
    ):
        simloop.run_batch(range(4), steps=50, executor=client)
    # A worker that joins later (after the check) refuses the chunk itself.
    monkeypatch.setattr(distributed._Pool, "check_workers", lambda self: None)
    with pytest.raises(distributed.VersionMismatch, match=r"^worker \S+ has simloop .* the client simloop 9\.9\.9"):
        simloop.run_batch(range(4), steps=50, executor=client)


def test_concurrent_futures_executors(local):
    with ThreadPoolExecutor(3) as pool:
        assert_same_as_local(simloop.run_batch(SEEDS, TIMESTEPS, steps=STEPS, executor=pool), local)
    if NO_WORKER_PROCESSES:
        pytest.skip(NO_WORKER_PROCESSES)
    with ProcessPoolExecutor(2, mp_context=multiprocessing.get_context("spawn")) as pool:
        assert_same_as_local(simloop.run_batch(SEEDS, TIMESTEPS, steps=STEPS, executor=pool, chunk_size=16), local)


def test_a_scenario_file_travels_as_itself_named_for_its_file_and_empty_or_not(tmp_path):
    """An executor gets a file's scenario as the local batch reads it: named for its file when its text names
    nothing (the table's scenario column), and an empty file is an empty scenario, not the chapter's; the
    chapter's scenario, made from a subclass too, is the chapter's."""
    unnamed = tmp_path / "walk.toml"
    unnamed.write_text(f'scene = "{ROOT / "python/simloop/scenes/pusht.xml"}"\nsteps = 50\n')
    empty = tmp_path / "empty.toml"
    empty.write_text("")

    class Mine(simloop.Scenario):
        pass

    for scenario, name in [
        (simloop.Scenario.from_file(unnamed), "walk"),
        (simloop.Scenario.from_file(empty), "empty"),
        (Mine.chapter(), "ch0.1-sim-loop"),
    ]:
        local = simloop.run_scenario_batch(scenario, seeds=[0, 1], metrics_only=True)
        with ThreadPoolExecutor(2) as pool:
            remote = simloop.run_scenario_batch(scenario, seeds=[0, 1], executor=pool)
        assert remote.column_names == local.column_names and remote == local
        assert list(remote["scenario"]) == [name, name]


def test_dask_is_imported_only_for_a_dask_client():
    result = run_python("""
        import sys
        from concurrent.futures import ThreadPoolExecutor
        import simloop
        with ThreadPoolExecutor(2) as pool:
            table = simloop.run_batch(range(3), steps=50, executor=pool)
        print(len(table), sorted(m for m in sys.modules if m.split(".")[0] in ("dask", "distributed")))
    """)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "3 []"


def test_what_cannot_travel_is_refused_in_one_line():
    with ThreadPoolExecutor(1) as pool:
        with pytest.raises(TypeError, match="a compiled simloop.Model does not travel"):
            simloop.run_batch(range(2), steps=50, executor=pool, model=simloop.Model.pusher_scene())
        with pytest.raises(TypeError, match="executor must be None, a dask.distributed Client"):
            simloop.run_batch(range(2), steps=50, executor=object())
        with pytest.raises(ValueError, match="chunk_size must be"):
            simloop.run_batch(range(2), steps=50, executor=pool, chunk_size=0)
        with pytest.raises(ValueError, match="no body named 'tblok'"):
            simloop.run_scenario_batch(
                simloop.Scenario(scene=str(ROOT / "tests/scenes/pusht.xml"), steps=10, record={"bodies": ["tblok"]}),
                executor=pool,
            )
    job = distributed.scenario_job(simloop.Scenario.chapter())
    job["versions"] = ("0.0.1", "MuJoCo 9.9.9")
    with pytest.raises(
        distributed.VersionMismatch, match=r"has simloop .* the client simloop 0.0.1 .*install the same"
    ):
        distributed.run_chunk(job, [(0, 0, None, ())])


# A policy goes to an executor with each chunk: the table's bits are the local batch's; one that does not pickle
# as the executor carries it is refused in one line naming it.
POLICY_BATCH = dict(seeds=range(5), timesteps=[None, 0.004], steps=120, control_every=10)


def towards(goal_x: float):
    """A closure (Dask carries it by value, with cloudpickle): push the block's x towards goal_x."""

    def policy(obs):
        return [float(np.clip(4.0 * (goal_x - obs["tblock_x"]), -1.0, 1.0)), 0.2]

    return policy


def test_a_policy_goes_to_a_cluster_in_chunks_with_the_local_bits(client):
    local = simloop.run_scenario_batch(PUSHT, policy=towards(0.35), threads=2, **POLICY_BATCH)
    table = simloop.run_scenario_batch(PUSHT, policy=towards(0.35), executor=client, chunk_size=3, **POLICY_BATCH)
    assert table == local and not table.has_results  # chunks of 3, 3, 3 and 1 runs
    assert np.array_equal(table["tblock_final_pos_x"], [r.column("tblock_x")[-1] for r in local.results])
    other = simloop.run_scenario_batch(PUSHT, policy=towards(0.1), executor=client, chunk_size=4, **POLICY_BATCH)
    assert not np.array_equal(other["pusher_final_pos_x"], table["pusher_final_pos_x"])  # the policy decided


def test_a_thread_pool_takes_any_policy_and_a_process_pool_a_picklable_one():
    local = simloop.run_scenario_batch(PUSHT, policy=towards(0.35), **POLICY_BATCH)
    with ThreadPoolExecutor(2) as pool:  # no pickling: a closure is fine
        assert (
            simloop.run_scenario_batch(PUSHT, policy=towards(0.35), executor=pool, chunk_size=4, **POLICY_BATCH)
            == local
        )
    with ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn")) as pool:  # refused before any start
        with pytest.raises(TypeError) as caught:
            simloop.run_scenario_batch(PUSHT, policy=towards(0.35), executor=pool, **POLICY_BATCH)
    message = str(caught.value)
    assert message.startswith("policy 'towards.<locals>.policy' cannot go to the executor: it does not pickle (")
    assert "\n" not in message


def test_a_policy_dask_cannot_carry_is_refused_naming_it(client):
    lock = threading.Lock()

    def locked(obs):
        with lock:
            return [0.5, 0.0]

    with pytest.raises(TypeError) as caught:
        simloop.run_scenario_batch(PUSHT, policy=locked, executor=client, **POLICY_BATCH)
    message = str(caught.value)
    assert message.startswith("policy 'test_a_policy_dask_cannot_carry_is_refused_naming_it.<locals>.locked' cannot")
    assert "lock" in message and "\n" not in message
