"""The chapter's loop as a 25 Hz policy would run it over a 500 Hz simulation.

It looks right. Its metrics are almost right. Find out why they are not.
"""

import simloop

DECIDE_EVERY = 20  # steps between the policy's decisions


def policy_loop(seed: int = 0, steps: int = 2000, sim=None) -> simloop.Sim:
    shove = simloop.run(seed=seed, steps=steps).shove  # the same shove schedule
    sim = sim if sim is not None else simloop.Sim()
    for step in range(0, steps, DECIDE_EVERY):
        in_shove = shove.start_step <= step < shove.start_step + shove.steps
        if in_shove:
            sim.apply_force([0.0, shove.force_y, 0.0])
        else:
            sim.clear_force()
        sim.step(DECIDE_EVERY, ctrl=1.0)
    return sim


if __name__ == "__main__":
    reference = simloop.run(seed=0)
    sim = policy_loop()
    print(f"simloop.run:  box final y {reference.metrics['box_final_pos'][1]:.6f} m")
    print(f"policy loop:  box final y {sim.box_position[1]:.6f} m")
