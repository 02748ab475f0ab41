"""repr() says what a result, a config or a scenario holds."""

import simloop
from conftest import ROOT
from simloop import _core

PUSHT = ROOT / "tests" / "scenes" / "pusht.toml"


def test_the_chapters_run():
    from expected import expected

    assert repr(simloop.run()) == (
        "RunResult(seed=0, steps=2000, timestep=0.002, rows=2001, "
        f"lateral_drift={expected('chapter.seed0_lateral_drift')}, warnings=0)"
    )
    r = simloop.run(seed=7, steps=500, timestep=0.004, record_every=10)
    assert repr(r) == (
        f"RunResult(seed=7, steps=500, timestep=0.004, rows=51, "
        f"lateral_drift={r.metrics['lateral_drift']!r}, warnings=0)"
    )
    blown = simloop.run(steps=200, timestep=5.0)
    assert repr(blown).endswith(f"warnings={len(blown.warnings)})") and blown.warnings


def test_configs():
    assert repr(simloop.run(seed=3, steps=10, rng="numpy").config) == (
        "RunConfig(seed=3, steps=10, timestep=0.002, perturb=True, smoke=False, record_every=1, "
        "audit_energy=False, rng='numpy')"
    )
    assert repr(_core.ScenarioConfig(5, "mt19937_64", 0.01, None, False, 4)) == (
        "ScenarioConfig(seed=5, rng='mt19937_64', timestep=0.01, steps=None, perturb=False, record_every=4)"
    )


def test_sweeps():
    sweep = simloop.sweep(timesteps=[0.002, 0.1], duration=1.0)
    assert repr(sweep) == f"SweepResult(points=2, timesteps=0.002..0.1, duration=1.0, edge={sweep.edge!r})"
    scenario_sweep = simloop.sweep(scenario=simloop.Scenario.chapter(), timesteps=[0.002, 0.1], duration=1.0)
    assert repr(scenario_sweep) == (
        f"ScenarioSweepResult(name='ch0.1-sim-loop', points=2, timesteps=0.002..0.1, "
        f"duration=1.0, edge={scenario_sweep.edge!r})"
    )
    p = sweep.points[1]
    assert repr(p) == (
        f"SweepPoint(timestep=0.1, steps=10, stable={p.stable!r}, "
        f"peak_box_z={round(p.peak_box_z, 6)!r}, warnings={p.warnings})"
    )


def test_scenarios_and_their_results():
    s = simloop.Scenario.from_file(PUSHT)
    assert repr(s) == (
        f"Scenario(name='pusht', scene={s.scene!r}, timestep=None, duration=2.0, "
        "controls=['push_x', 'push_y'], disturbances=1, bodies=['tblock', 'pusher'])"
    )
    assert repr(simloop.Scenario.chapter()) == (
        "Scenario(name='ch0.1-sim-loop', scene=None, timestep=0.002, steps=2000, controls=['push_motor'], "
        "disturbances=1, bodies=['box'])"
    )
    r = simloop.run_scenario(s, seed=2, steps=300, record_every=3)
    assert repr(r) == (
        f"ScenarioResult(name='pusht', seed=2, steps=300, timestep=0.002, rows=101, "
        f"columns={len(r.column_names)}, disturbances=1, warnings=0)"
    )
    assert repr(simloop.run_scenario(s, steps=300, perturb=False)).endswith("disturbances=0, warnings=0)")


def test_a_metrics_only_table():
    t = simloop.run_batch(seeds=range(3), steps=10, metrics_only=True)
    assert repr(t) == (
        f"BatchTable(rows=3, columns=[run, seed, rng, timestep, steps, perturb, ... ({len(t.column_names)} columns)])"
    )
