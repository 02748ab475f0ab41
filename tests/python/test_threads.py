"""One Sim, many Python threads: calls take turns, never a crash.

Each check runs in a subprocess, so a crash of the interpreter is a test
failure rather than the end of pytest."""

import pytest
import simloop
from conftest import run_python


def test_threads_stepping_reading_and_changing_one_sim_do_not_crash():
    proc = run_python("""
        import threading
        import simloop

        sim = simloop.Sim()

        def stepper(n):
            for _ in range(150):
                sim.step(n)
                sim.box_position, sim.contacts, sim.warnings, sim.time

        def changer():
            for i in range(150):
                sim.timestep = 0.001 if i % 2 else 0.002
                sim.apply_force([0.0, float(i % 5), 0.0])
                sim.ctrl = 0.5
                if i % 10 == 0:
                    sim.reset()

        threads = [threading.Thread(target=stepper, args=(n,)) for n in (1, 20, 100)]
        threads.append(threading.Thread(target=changer))
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        print("survived")
    """)
    assert proc.returncode == 0, f"exit {proc.returncode}: {proc.stderr[-2000:]}"
    assert proc.stdout == "survived\n"


def test_steps_from_many_threads_add_up_to_the_same_state_as_one_thread():
    # Each step call holds the Sim for its whole length, so N steps taken from
    # four threads in any interleaving are N steps of the one trajectory.
    proc = run_python("""
        import threading
        import simloop

        shared, alone = simloop.Sim(), simloop.Sim()
        shared.ctrl = alone.ctrl = 1.0
        calls = [(1, 400), (7, 60), (64, 10), (150, 4)]  # (n, calls): 420 + 640 + 600 = 2060 steps

        def stepper(n, count):
            for _ in range(count):
                shared.step(n)

        threads = [threading.Thread(target=stepper, args=c) for c in calls]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        total = sum(n * count for n, count in calls)
        alone.step(total)
        print(shared.steps_taken == total, shared.time == alone.time,
              list(shared.box_position) == list(alone.box_position),
              list(shared.box_velocity) == list(alone.box_velocity))
    """)
    assert proc.returncode == 0, f"exit {proc.returncode}: {proc.stderr[-2000:]}"
    assert proc.stdout == "True True True True\n"


def test_a_sim_called_from_inside_its_own_step_refuses_instead_of_deadlocking():
    sim = simloop.Sim()
    seen = []

    def progress(done, total):
        seen.append(done)
        sim.box_position  # the Sim is mid-step on this very thread

    with pytest.raises(ValueError) as caught:
        sim.step(200_000, progress=progress)
    assert "this Sim is in the middle of a call on this thread" in str(caught.value)
    assert "\n" not in str(caught.value)
    assert len(seen) == 1 and 0 < seen[0] < 200_000
    # The steps taken stay taken (the poll came after them) and the Sim works on.
    assert sim.steps_taken == seen[0]
    sim.step(1)
    assert sim.steps_taken == seen[0] + 1


def test_a_vector_env_read_from_another_thread_mid_step_waits_instead_of_deadlocking():
    """Episodes (under the vector env): a second thread's call waits for a long step without the GIL."""
    proc = run_python(
        """
        import threading, time
        import numpy as np
        from simloop import _core, Scenario

        scenario = Scenario.chapter()
        config = _core.ScenarioConfig(0, "mt19937_64", None, 10_000_000, False, 1)
        episodes = _core.Episodes(scenario.model(), scenario._core, config, 2)
        for i in range(2):
            episodes.reset(i, i)
        started = threading.Event()

        def long_step():
            started.set()
            episodes.step(np.zeros((2, 1)), 400_000)

        stepper = threading.Thread(target=long_step)
        stepper.start()
        started.wait()
        time.sleep(0.2)
        steps, _ = episodes.progress()  # waits for the step to end
        stepper.join()
        print("waited", steps.tolist(), episodes.steps_taken(0), episodes.time(1) > 0, episodes.warnings(0))
    """,
        timeout=60,
    )
    assert proc.returncode == 0, f"exit {proc.returncode}: {proc.stderr[-2000:]}"
    assert proc.stdout.split() == ["waited", "[400000,", "400000]", "400000", "True", "[]"]


def test_episodes_called_from_a_signal_handler_inside_their_own_step_refuse_instead_of_deadlocking():
    proc = run_python(
        """
        import signal
        import numpy as np
        from simloop import _core, Scenario

        scenario = Scenario.chapter()
        config = _core.ScenarioConfig(0, "mt19937_64", None, 10_000_000, False, 1)
        episodes = _core.Episodes(scenario.model(), scenario._core, config, 1)
        episodes.reset(0, 0)
        signal.signal(signal.SIGALRM, lambda *_: episodes.progress())
        signal.setitimer(signal.ITIMER_REAL, 0.05)
        try:
            episodes.step(np.zeros((1, 1)), 5_000_000)
            print("not refused")
        except ValueError as e:
            print(e)
        signal.setitimer(signal.ITIMER_REAL, 0)
        steps, _ = episodes.progress()  # usable again
        print(0 < steps[0] < 5_000_000)
    """,
        timeout=60,
    )
    assert proc.returncode == 0, f"exit {proc.returncode}: {proc.stderr[-2000:]}"
    assert proc.stdout.splitlines() == [
        "these episodes are in the middle of a call on this thread (a signal handler or progress callback called "
        "it); call it after that call returns",
        "True",
    ]
