"""Exercise 3's physics, for check.py: the box's slide as MuJoCo runs it,
phase by phase, and the back-of-envelope sum beside it."""

import simloop

MASS, MU, G, PUSH_S = 0.5, 1.0, 9.81, 0.1  # the box (kg), MuJoCo's default friction, gravity, the push (s)


def slide_phases(force: float) -> dict:
    """A box at rest pushed sideways with `force` N for 50 steps, then left
    for 500: how far it had moved when the push ended (m) and its speed then
    (m/s), the furthest it got (m), how far its centre rose above rest (m),
    and where it ended (m)."""
    sim = simloop.Sim()
    sim.step(100)  # settle on the floor, motor off
    (_, y0, z0) = sim.box_position
    sim.apply_force([0.0, force, 0.0])
    sim.step(50)
    sim.clear_force()
    out = {
        "released": sim.box_position[1] - y0,
        "speed": float(sim.qvel[1]),  # the box's free joint: qvel[0:3]
        "furthest": 0.0,
        "rise": 0.0,
    }
    for _ in range(500):
        sim.step()
        (_, y, z) = sim.box_position
        out["furthest"], out["rise"] = max(out["furthest"], y - y0), max(out["rise"], z - z0)
    out["end"] = sim.box_position[1] - y0
    return out


def rigid_sum(force: float) -> dict:
    """The sum for a rigid box: friction (N); by the release, its speed (m/s)
    and the slide during the push (cm); the coast after it (cm)."""
    friction = MASS * G * MU
    accel = (force - friction) / MASS
    speed = accel * PUSH_S
    return {
        "friction": friction,
        "speed": speed,
        "push_cm": 0.5 * accel * PUSH_S**2 * 100,
        "coast_cm": speed * speed / (2 * MU * G) * 100,
    }


def half_of_the_sum(predicted_cm: float, s: dict, mujoco_cm: float, accepted: bool):
    """What a prediction that is only the push's part or only the coast's
    (within 10%) left out, or None."""
    parts = {"push": s["push_cm"], "coast": s["coast_cm"]}
    near = [name for name, cm in parts.items() if abs(predicted_cm - cm) <= 0.1 * cm]
    if not near:
        return None
    half = min(near, key=lambda name: abs(predicted_cm - parts[name]))
    left_out = (
        f"the {s['coast_cm']:.1f} cm it coasts after the push (v^2 / (2 mu g))"
        if half == "push"
        else f"the {s['push_cm']:.1f} cm it slides during the push itself (a t^2 / 2, a = net force / m)"
    )
    return (
        f"9 N: {predicted_cm:g} cm is half the sum, the {half} alone: it leaves out {left_out}. Both parts "
        f"give {s['push_cm'] + s['coast_cm']:.1f} cm; MuJoCo slid it {mujoco_cm:.2f} cm"
        + (", so yours is within a factor of 2 of it, but short for that reason." if accepted else ".")
    )


def sum_beside_mujoco(force: float, s: dict, m: dict) -> list:
    """The solution's sum, then what MuJoCo did in each part."""
    return [
        f"The sum: {force:g} N - {s['friction']:.2f} N friction = {force - s['friction']:.2f} N net on {MASS:g} kg "
        f"for {PUSH_S:g} s gives {s['speed']:.2f} m/s and {s['push_cm']:.1f} cm by the release; coasting against "
        f"friction adds {s['coast_cm']:.1f} cm: {s['push_cm'] + s['coast_cm']:.1f} cm in all.",
        f"MuJoCo, by the release: {m['released'] * 100:.2f} cm at {m['speed']:.2f} m/s (the sum: "
        f"{s['push_cm']:.1f} cm at {s['speed']:.2f} m/s). After it, the box slides "
        f"{(m['furthest'] - m['released']) * 100:.2f} cm more (the sum: {s['coast_cm']:.1f}), to "
        f"{m['furthest'] * 100:.2f} cm"
        + (
            ", and rocks: friction acts at its base, below its centre, and a cube with mu = 1 is at the edge of "
            f"tipping (mu = width / height), so it tips forward (its centre rises {m['rise'] * 1000:.1f} mm) "
            f"and falls back, ending {(m['furthest'] - m['end']) * 100:.2f} cm behind its furthest, at "
            f"{m['end'] * 100:.2f} cm."
            if m["rise"] > 0.002
            else ", where it stays."
        ),
    ]
