"""Batch and sweep results as tables: one row per run, flat typed columns,
unrounded metrics, warning counts; metrics-only batches give the same table
as keeping every trajectory, bit for bit."""

import pickle
import sys

import numpy as np
import pytest

import simloop
from conftest import ROOT

PUSHT = ROOT / "tests" / "scenes" / "pusht.toml"


def test_a_batch_of_runs_is_one_typed_row_per_run():
    results = simloop.run_batch(seeds=[0, 1, 2**64 - 1], steps=300, threads=2)
    df = simloop.to_pandas(results)
    assert len(df) == 3
    assert df["seed"].tolist() == [0, 1, 2**64 - 1] and df["seed"].dtype == np.uint64
    for name in ("steps", "record_every", "shove_start_step", "shove_steps"):
        assert df[name].dtype == np.int64, name
    for name in ("perturb", "shove_moved_box", "diverged", "audit_energy"):
        assert df[name].dtype == bool, name
    assert all(df[c].dtype != object for c in df.columns if c != "rng")
    for row, r in zip(df.itertuples(), results):
        exact = r.unrounded_metrics
        assert [row.box_final_pos_x, row.box_final_pos_y, row.box_final_pos_z] == exact["box_final_pos"]
        assert row.lateral_drift == exact["lateral_drift"]
        # Unrounded: metrics.json's values are these, rounded.
        assert round(row.lateral_drift, 6) == r.metrics["lateral_drift"]
        assert row.box_final_pos_x == r.column("box_x")[-1]
        assert row.shove_force_y == r.shove.force_y and row.steps == 300 and row.rng == "mt19937_64"
    assert any(round(x, 6) != x for x in df["lateral_drift"])  # really not rounded


def test_warnings_are_counts_per_name_and_a_diverged_flag():
    results = simloop.run_batch(seeds=[0], timesteps=[0.002, 5.0], steps=200)
    table = simloop.table(results)
    blown = {w.name: w.count for w in results[1].warnings}
    assert "simloop_DIVERGED" in blown and not results[0].warnings
    assert table["diverged"].tolist() == [False, True]
    for name, count in blown.items():
        assert table["warning_" + name].tolist() == [0, count]
        assert table["warning_" + name].dtype == np.int64


@pytest.mark.parametrize("threads", [1, 2])
def test_a_metrics_only_batch_is_the_table_of_the_full_batch(threads):
    kept = simloop.run_batch(seeds=range(4), timesteps=[0.002, 0.01], steps=400, threads=threads)
    lean = simloop.run_batch(seeds=range(4), timesteps=[0.002, 0.01], steps=400, threads=threads, metrics_only=True)
    assert isinstance(lean, simloop.BatchTable) and len(lean) == 8
    assert lean == simloop.table(kept)
    assert lean["seed"].tolist() == [0, 0, 1, 1, 2, 2, 3, 3]  # itertools.product order


@pytest.mark.parametrize("threads", [1, 2])
def test_a_metrics_only_scenario_batch_is_the_table_of_the_full_batch(threads):
    kept = simloop.run_scenario_batch(PUSHT, seeds=range(3), steps=700, threads=threads)
    lean = simloop.run_scenario_batch(PUSHT, seeds=range(3), steps=700, threads=threads, metrics_only=True)
    assert lean == simloop.table(kept)
    for i, r in enumerate(kept):
        body = r.bodies["tblock"]
        assert lean["tblock_final_pos_y"][i] == r.trajectory[-1, body + 1]
        assert round(lean["tblock_final_pos_y"][i], 6) == r.metrics["bodies"]["tblock"]["final_pos"][1]
        assert lean["disturbance0_fy"][i] == r.disturbances[0]["force"][1]
        assert lean["disturbance0_start_step"][i] == r.disturbances[0]["start_step"]
    assert lean["disturbance0_steps"].dtype == np.int64 and lean["scenario"].tolist() == ["pusht"] * 3


def test_arrow_types_follow_the_columns():
    pa = pytest.importorskip("pyarrow")
    t = simloop.run_batch(seeds=[0, 1], steps=100, metrics_only=True).to_arrow()
    assert t.num_rows == 2
    assert t.schema.field("seed").type == pa.uint64()
    assert t.schema.field("steps").type == pa.int64()
    assert t.schema.field("perturb").type == pa.bool_()
    assert t.schema.field("rng").type == pa.string()
    assert t.schema.field("lateral_drift").type == pa.float64()
    assert t.column("lateral_drift").to_pylist() == simloop.table(simloop.run_batch(seeds=[0, 1], steps=100))[
        "lateral_drift"].tolist()


def test_a_sweep_is_one_row_per_timestep():
    sweep = simloop.sweep(timesteps=[0.001, 0.002, 0.05, 0.1], duration=1.0)
    df = sweep.to_pandas()
    assert df["timestep"].tolist() == [p.timestep for p in sweep.points]
    assert df["stable"].tolist() == [p.stable for p in sweep.points]
    assert df["peak_box_z"].tolist() == [p.peak_box_z for p in sweep.points]
    assert df["edge"].tolist() == [p.timestep == sweep.edge for p in sweep.points]
    assert df["steps"].dtype == np.int64 and df["warnings"].dtype == np.int64
    assert sweep.to_arrow().num_rows == 4


def test_tables_pickle_and_concatenate():
    a = simloop.run_batch(seeds=[0, 1], steps=100, metrics_only=True)
    b = simloop.run_batch(seeds=[2], steps=100, metrics_only=True)
    assert pickle.loads(pickle.dumps(a)) == a
    joined = simloop.BatchTable.concat([a, b])
    assert joined == simloop.run_batch(seeds=[0, 1, 2], steps=100, metrics_only=True)
    assert joined != a
    with pytest.raises(ValueError, match=r"tables\[1\] has other columns"):
        simloop.BatchTable.concat([a, simloop.run_scenario_batch(PUSHT, steps=10, metrics_only=True)])
    with pytest.raises(KeyError, match="no column named 'drift'"):
        a["drift"]


def test_wrong_inputs_and_a_missing_extra_say_what_to_do(monkeypatch):
    with pytest.raises(TypeError, match="results must be a list of RunResult or of ScenarioResult, not a mix"):
        simloop.table([simloop.run(steps=10), simloop.run_scenario(PUSHT, steps=10)])
    with pytest.raises(TypeError, match="got RunResult"):
        simloop.table(simloop.run(steps=10))
    with pytest.raises(TypeError, match="metrics_only must be a bool"):
        simloop.run_batch(seeds=[0], metrics_only="yes")
    monkeypatch.setitem(sys.modules, "pandas", None)
    with pytest.raises(ImportError, match=r"pip install 'simloop\[tables\]'"):
        simloop.run_batch(seeds=[0], steps=10, metrics_only=True).to_pandas()


def test_the_docs_batches_example_runs(capsys, monkeypatch):
    text = (ROOT / "docs" / "scaling.md").read_text()
    section = text.split("## Batches, tables\n", 1)[1]
    code = section.split("```python\n", 1)[1].split("```", 1)[0]
    monkeypatch.chdir(ROOT)
    exec(compile(code, "docs/scaling.md: Batches, tables", "exec"), {})
    last = capsys.readouterr().out.splitlines()[-1]
    assert last.startswith("ScenarioResult(name='pusht', seed=0, steps=1000,") and last.endswith(") 25")
