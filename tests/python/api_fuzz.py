"""Seeded misuse of the public Python API, run by test_fuzz_api.py in a
subprocess (so an interpreter crash fails the test instead of killing pytest).

Each call takes one public entry point with valid, quick arguments and swaps
one argument for a value drawn from POOL: wrong types, out-of-range and huge
ints, NaN and inf, None, empty and non-UTF-8 text, NUL bytes, wrong shapes.
A call may succeed (some values are valid); if it raises, the exception must
be one the API documents (TypeError, ValueError, OSError, simloop.MujocoError;
KeyError for a column name) with a one-line message. Prints one JSON line:
{"calls": N, "raised": {...}, "bad": [...]}.

    python api_fuzz.py SEED CALLS    (run in a scratch directory: writes there)
"""

import fractions
import json
import math
import numbers
import random
import sys
from pathlib import Path

import numpy as np
import simloop

POOL = [
    None,
    True,
    False,
    0,
    -1,
    1,
    3,
    2**31,
    2**62 - 1,
    2**62,
    2**63 - 1,
    2**63,
    2**64,
    -(2**63),
    2**1000,
    10**5000,
    0.0,
    -0.0,
    1.5,
    -1e300,
    1e300,
    5e-324,
    math.nan,
    math.inf,
    -math.inf,
    1j,
    "",
    "x",
    "0.002",
    "\udcfe",
    "a\0b",
    "\n",
    "x" * 10_000,
    b"",
    b"x",
    b"\xfe",
    b"a\0b",
    [],
    [1, 2],
    [0.0, 1.0, 2.0],
    [[0.002]],
    [None],
    ["0"],
    (),
    {},
    set(),
    object(),
    range(0),
    range(3),
    np.int64(-1),
    np.uint64(2**64 - 1),
    np.float64(math.nan),
    np.float32(0.5),
    np.bool_(True),
    np.array([1.0, 2.0]),
    np.zeros((3, 1)),
    np.zeros(0),
    fractions.Fraction(1, 3),
    len,
]

ALLOWED = (TypeError, ValueError, OSError, simloop.MujocoError)
MAX_STEPS = 2**62 - 1  # sim_loop's cap on --steps


def show(value):
    if isinstance(value, int) and value.bit_length() > 64:
        return f"<int of {value.bit_length()} bits>"
    return repr(value)[:60]


def is_number(v):
    return isinstance(v, numbers.Real) and not isinstance(v, bool)


def slow(name, value):
    """Values that are valid but would make the call run for long: skipped."""
    if name in ("steps", "n"):
        return isinstance(value, numbers.Integral) and 10_000 < value <= MAX_STEPS
    if name == "duration":  # the sweep runs duration / timestep steps per timestep
        return is_number(value) and value > 10
    if name in ("timesteps", "timesteps[0]"):
        values = value if isinstance(value, (list, range)) else [value]
        return any(is_number(v) and 0 < v < 1e-3 for v in values)
    return False


def main():
    seed, calls = int(sys.argv[1]), int(sys.argv[2])
    rng = random.Random(seed)
    result = simloop.run(steps=10)
    sweep = simloop.sweep(timesteps=[0.25], duration=1.0, threads=1)
    model = simloop.Model.pusher_scene()
    sim = simloop.Sim()
    any_sim = simloop.Sim(Path(__file__).resolve().parents[1] / "scenes" / "pusht.xml")

    def set_attr(obj, attr):
        return lambda v: setattr(obj, attr, v)

    # (name, argument, call taking the drawn value)
    targets = [
        ("run", "seed", lambda v: simloop.run(seed=v, steps=20)),
        ("run", "steps", lambda v: simloop.run(steps=v)),
        ("run", "timestep", lambda v: simloop.run(timestep=v, steps=20)),
        ("run", "perturb", lambda v: simloop.run(perturb=v, steps=20)),
        ("run", "smoke", lambda v: simloop.run(smoke=v, steps=20)),
        ("run", "model", lambda v: simloop.run(model=v, steps=20)),
        ("run", "record_every", lambda v: simloop.run(record_every=v, steps=20)),
        ("run", "audit_energy", lambda v: simloop.run(audit_energy=v, steps=20)),
        ("run", "progress", lambda v: simloop.run(progress=v, steps=20)),
        ("run_batch", "seeds", lambda v: simloop.run_batch(seeds=v, steps=20, threads=1)),
        ("run_batch", "timesteps", lambda v: simloop.run_batch(timesteps=v, steps=20, threads=1)),
        ("run_batch", "steps", lambda v: simloop.run_batch(steps=v, threads=1)),
        ("run_batch", "record_every", lambda v: simloop.run_batch(record_every=v, steps=20, threads=1)),
        ("run_batch", "threads", lambda v: simloop.run_batch(threads=v, steps=20)),
        ("run_batch", "seeds[0]", lambda v: simloop.run_batch(seeds=[v], steps=20, threads=1)),
        ("sweep", "timesteps", lambda v: simloop.sweep(timesteps=v, duration=1.0, threads=1)),
        ("sweep", "timesteps[0]", lambda v: simloop.sweep(timesteps=[v], duration=1.0, threads=1)),
        ("sweep", "duration", lambda v: simloop.sweep(timesteps=[0.25], duration=v, threads=1)),
        ("sweep", "threads", lambda v: simloop.sweep(timesteps=[0.25], duration=1.0, threads=v)),
        ("load_model", "model", simloop.load_model),
        ("Model.from_file", "path", simloop.Model.from_file),
        ("Model.from_xml_string", "xml", simloop.Model.from_xml_string),
        ("Model.from_xml_string", "source", lambda v: simloop.Model.from_xml_string("<mujoco/>", v)),
        ("Model.with_timestep", "timestep", model.with_timestep),
        ("RunResult.column", "name", result.column),
        ("RunResult.write", "out", result.write),
        ("RunResult.summary", "extra", result.summary),
        ("SweepResult.write", "out", sweep.write),
        ("Sim", "model", lambda v: simloop.Sim(model=v)),
        ("Sim", "timestep", lambda v: simloop.Sim(timestep=v)),
        ("Sim.step", "n", sim.step),
        ("Sim.step", "ctrl", lambda v: sim.step(1, ctrl=v)),
        ("Sim.step", "progress", lambda v: sim.step(1, progress=v)),
        ("Sim.ctrl", "value", set_attr(sim, "ctrl")),
        ("Sim.timestep", "value", set_attr(sim, "timestep")),
        ("Sim.apply_force", "force", sim.apply_force),
        ("Sim.apply_force", "force[1]", lambda v: sim.apply_force([0.0, v, 0.0])),
        # Sim on a scene without the chapter's layout: names, vectors, state.
        ("Sim.body", "key", any_sim.body),
        ("Sim.joint", "key", any_sim.joint),
        ("Sim.sensor", "key", any_sim.sensor),
        ("Sim.reset", "keyframe", lambda v: any_sim.reset(keyframe=v)),
        ("Sim.set_state", "state", any_sim.set_state),
        ("Sim.apply_force", "body", lambda v: any_sim.apply_force(body=v, force=[0.0, 0.0, 1.0])),
        ("Sim.apply_force", "torque", lambda v: any_sim.apply_force(body=1, torque=v)),
        ("Sim.step", "ctrl", lambda v: any_sim.step(1, ctrl=v)),
        ("Sim.qpos", "value", set_attr(any_sim, "qpos")),
    ]
    raised, bad = {}, []
    done = 0
    while done < calls:
        where, argument, call = rng.choice(targets)
        value = rng.choice(POOL)
        if slow(argument, value):
            continue
        done += 1
        try:
            call(value)
        except Exception as e:  # noqa: BLE001 - judging every exception is the point
            allowed = ALLOWED + ((KeyError,) if where == "RunResult.column" else ())
            message = str(e)
            kind = type(e).__name__
            raised[kind] = raised.get(kind, 0) + 1
            if not isinstance(e, allowed) or "\n" in message or not message.strip():
                bad.append(f"{where}({argument}={show(value)}): {kind}: {message[:300]!r}")
        if sim.steps_taken > 1000:
            sim.reset()
    print(json.dumps({"calls": done, "raised": raised, "bad": bad}))


if __name__ == "__main__":
    main()
