"""The chapter's loop, written out by hand with simloop.Sim.

It looks right: full throttle on the motor, the shove at step 1000, step,
2000 times. Run it and compare with simloop.run(seed=0). Then find out what
went wrong, and fix it.
"""

import simloop


def chapter_loop(seed: int = 0, steps: int = 2000, sim=None) -> simloop.Sim:
    shove = simloop.draw_shove(seed=seed, steps=steps)  # the same shove simloop.run draws
    sim = sim if sim is not None else simloop.Sim()
    for step in range(steps):
        sim.ctrl = 1.0  # full throttle on the slide motor
        if step == shove.start_step:
            sim.apply_force([0.0, shove.force_y, 0.0])  # the shove: shove.steps (50) steps of it
        sim.step()
    return sim


if __name__ == "__main__":
    reference = simloop.run(seed=0)
    sim = chapter_loop()
    print(f"simloop.run:  box final position {reference.metrics['box_final_pos']}")
    print(f"this loop:    box final position {[round(float(v), 6) for v in sim.box_position]}")
