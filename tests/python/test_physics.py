"""What the chapter teaches, held as tests: the blow-up, the shove, persistence."""

import numpy as np
import pytest
import simloop
from expected import expected


def test_break_it_the_coarse_timestep_hops_and_drifts():
    # Measured on MuJoCo 2.2.2, 2000 steps, no shove:
    #   timestep 0.002: peak box z 0.05345 m, largest |y| 0.0515 m
    #   timestep 0.05:  peak box z 0.0927 m, final y -0.2541 m
    fine = simloop.run(timestep=0.002, perturb=False)
    coarse = simloop.run(timestep=0.05, perturb=False)
    assert fine.column("box_z").max() < 0.056
    assert 0.085 < coarse.column("box_z").max() < 0.10
    assert np.abs(fine.column("box_y")).max() < 0.07
    # The drift is MuJoCo 2.2's (-0.254 m); 4.0 keeps the symmetric push symmetric.
    assert expected("break_it.final_y_min") <= coarse.column("box_y")[-1] <= expected("break_it.final_y_max")
    # Nothing pushed sideways: every shove written was zero (NaN: the final
    # row has no inputs), and MuJoCo raised no warning. The energy came from
    # the integrator.
    shove_y = coarse.column("shove_y")
    assert np.all(shove_y[:-1] == 0.0) and np.isnan(shove_y[-1])
    assert coarse.warnings == [] and fine.warnings == []


@pytest.mark.parametrize("timestep", [0.002, 0.05])
def test_the_first_step_is_free_fall_whatever_the_timestep(timestep):
    """The tutorial's 'sink at step 1': the box starts exactly touching the
    floor, MuJoCo makes a contact a force only once it is in the floor, so
    step 1 is one step of free fall: 0.04 mm at 0.002 s, 2.45 cm at 0.05 s."""
    z = simloop.run(timestep=timestep, steps=10, perturb=False).column("box_z")
    assert z[1] == pytest.approx(0.05 - 9.81 * timestep**2, abs=1e-15)
    assert z[2] > z[1] - 2 * 9.81 * timestep**2 + 1e-6  # step 2 is not free fall: the contact acts


def test_break_its_hops_start_at_the_pusher_and_grow_to_the_peak():
    """The tutorial's Break It, told from the trajectory: no hop before the
    pusher touches the box (t = 0.35 s, the contact count rises), hops that
    grow (the first 2 s stay below the peak), the peak at its step."""
    run = simloop.run(timestep=0.05, perturb=False)
    z, ncon = run.column("box_z"), run.column("ncon")
    first_contact = int(np.argmax(ncon > ncon[0]))
    assert first_contact == 7
    assert z[: first_contact + 1].max() < 0.05 + 0.005  # nothing hops before the pusher arrives
    peak = int(np.argmax(z))
    assert peak == expected("break_it.peak_step")
    assert z[peak] == pytest.approx(expected("break_it.peak_z"), abs=5e-5)
    assert z[:41].max() < z[peak] - 0.015  # the first 2 s hop well below the peak


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_shove_moves_the_box_sideways(seed):
    # Measured lateral_drift: 0.045, 0.054, 0.208 m for seeds 0, 1, 2.
    result = simloop.run(seed=seed)
    baseline = simloop.run(seed=seed, perturb=False)
    assert result.metrics["shove_moved_box"] is True
    assert result.metrics["lateral_drift"] > 0.01
    off_line = result.metrics["box_final_pos"][1] - baseline.metrics["box_final_pos"][1]
    assert result.shove.sign * off_line > 0.02  # it went the way it was shoved


def test_without_the_shove_the_drift_is_small():
    # 0.0167 m: the pusher's face contact is not symmetric on MuJoCo 2.2.2.
    assert simloop.run(perturb=False).metrics["lateral_drift"] < 0.02


def test_the_seed_changes_the_shove_and_nothing_else():
    a, b = simloop.run(seed=0, steps=600), simloop.run(seed=1, steps=600)
    assert (a.shove.newtons, a.shove.sign) != (b.shove.newtons, b.shove.sign)
    assert a.shove.start_step == b.shove.start_step == 300
    before = slice(0, 300)  # rows before the shove starts
    assert a.trajectory[before].tobytes() == b.trajectory[before].tobytes()
    assert a.metrics["box_final_pos"] != b.metrics["box_final_pos"]
    base_a, base_b = simloop.run(seed=0, steps=600, perturb=False), simloop.run(seed=1, steps=600, perturb=False)
    assert base_a.trajectory.tobytes() == base_b.trajectory.tobytes()
    assert {k: v for k, v in base_a.metrics.items() if k != "seed"} == {
        k: v for k, v in base_b.metrics.items() if k != "seed"
    }


def chapter_loop_with_sim(steps, shove, clear_after_shove):
    """The chapter's loop written with Sim; optionally with the classic bug."""
    sim = simloop.Sim()
    for step in range(steps):
        sim.ctrl = 1.0
        if step == shove.start_step:
            sim.apply_force([0.0, shove.force_y, 0.0])
        if clear_after_shove and step == shove.start_step + shove.steps:
            sim.clear_force()
        sim.step()
    return sim


def test_a_force_persists_until_cleared():
    sim = simloop.Sim()
    sim.apply_force([0.0, 9.0, 0.0])
    velocities = []
    for _ in range(30):
        sim.step()
        velocities.append(sim.box_velocity[1])
        assert sim.applied_force[1] == 9.0  # MuJoCo never cleared it
    # Still accelerating (unevenly: the box rocks on its contacts as it slides).
    assert velocities[0] < velocities[9] < velocities[19] < velocities[29]
    sim.clear_force()
    sim.step(300)
    assert abs(sim.box_velocity[1]) < 1e-3  # friction stops it once it is gone


def test_forgetting_to_clear_the_shove_changes_the_metrics():
    reference = simloop.run(seed=0, steps=2000)
    right = chapter_loop_with_sim(2000, reference.shove, clear_after_shove=True)
    forgot = chapter_loop_with_sim(2000, reference.shove, clear_after_shove=False)
    final = reference.trajectory[-1]
    names = simloop.COLUMN_NAMES
    # Written right, the Sim loop is the chapter's loop, bit for bit.
    assert list(right.box_position) == [final[names.index(c)] for c in ("box_x", "box_y", "box_z")]
    # Forgotten, the shove pushes for 1000 steps instead of 50.
    assert abs(forgot.box_position[1] - right.box_position[1]) > 0.5


def test_sim_reads_are_copies():
    sim = simloop.Sim()
    position = sim.box_position
    sim.step(100, ctrl=1.0)
    assert position[0] == 0.4  # what we held did not move with the simulation
    assert sim.box_position[0] != 0.4 or sim.pusher_x > 0.0
    position[0] = 99.0
    assert sim.box_position[0] != 99.0


def test_sim_contacts_and_timestep():
    sim = simloop.Sim(timestep=0.01)
    assert sim.timestep == 0.01
    names = {(c.geom1, c.geom2) for c in sim.contacts}
    assert names == {("floor", "box_geom"), ("floor", "pusher_geom")}
    sim.step(10, ctrl=1.0)
    assert sim.time == pytest.approx(0.1)
    assert sim.ctrl == 1.0
