"""Batch and sweep results as tables: one row per run, flat typed columns,
unrounded metrics, warning counts; metrics-only batches give the same table
as keeping every trajectory, bit for bit."""

import pickle
import sys
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest
import simloop
from conftest import ROOT

PUSHT = ROOT / "tests" / "scenes" / "pusht.toml"


def test_a_batch_of_runs_is_one_typed_row_per_run():
    batch = simloop.run_batch(seeds=[0, 1, 2**64 - 1], steps=300, threads=2)
    df = batch.to_pandas()
    assert len(df) == 3
    assert df["run"].tolist() == [0, 1, 2] and df["run"].dtype == np.int64
    assert df["seed"].tolist() == [0, 1, 2**64 - 1] and df["seed"].dtype == np.uint64
    for name in ("steps", "record_every", "shove_start_step", "shove_steps"):
        assert df[name].dtype == np.int64, name
    for name in ("perturb", "shove_moved_box", "diverged", "audit_energy"):
        assert df[name].dtype == bool, name
    assert all(df[c].dtype != object for c in df.columns if c != "rng")
    for row, r in zip(df.itertuples(), batch.results):
        exact = r.unrounded_metrics
        assert [row.box_final_pos_x, row.box_final_pos_y, row.box_final_pos_z] == exact["box_final_pos"]
        assert row.lateral_drift == exact["lateral_drift"]
        # Unrounded: metrics.json's values are these, rounded.
        assert round(row.lateral_drift, 6) == r.metrics["lateral_drift"]
        assert row.box_final_pos_x == r.column("box_x")[-1]
        assert row.shove_force_y == r.shove.force_y and row.steps == 300 and row.rng == "mt19937_64"
    assert any(round(x, 6) != x for x in df["lateral_drift"])  # really not rounded


def test_warnings_are_counts_per_name_and_a_diverged_flag():
    table = simloop.run_batch(seeds=[0], timesteps=[0.002, 5.0], steps=200)
    blown = {w.name: w.count for w in table.results[1].warnings}
    assert "simloop_DIVERGED" in blown and not table.results[0].warnings
    assert table["diverged"].tolist() == [False, True]
    for name, count in blown.items():
        assert table["warning_" + name].tolist() == [0, count]
        assert table["warning_" + name].dtype == np.int64


@pytest.mark.parametrize("threads", [1, 2])
def test_a_metrics_only_batch_is_the_table_of_the_full_batch(threads):
    kept = simloop.run_batch(seeds=range(4), timesteps=[0.002, 0.01], steps=400, threads=threads)
    lean = simloop.run_batch(seeds=range(4), timesteps=[0.002, 0.01], steps=400, threads=threads, metrics_only=True)
    assert isinstance(lean, simloop.BatchTable) and len(lean) == 8
    assert lean == kept and [lean[k].dtype for k in lean] == [kept[k].dtype for k in kept]
    assert kept.has_results and not lean.has_results
    assert simloop.table(kept.results) == kept  # the table of the results kept is the batch's
    assert lean["seed"].tolist() == [0, 0, 1, 1, 2, 2, 3, 3]  # itertools.product order


@pytest.mark.parametrize("threads", [1, 2])
def test_a_metrics_only_scenario_batch_is_the_table_of_the_full_batch(threads):
    kept = simloop.run_scenario_batch(PUSHT, seeds=range(3), steps=700, threads=threads)
    lean = simloop.run_scenario_batch(PUSHT, seeds=range(3), steps=700, threads=threads, metrics_only=True)
    assert lean == kept and lean.column_names[:2] == ["run", "scenario"]
    assert simloop.table(kept.results) == kept
    for i, r in enumerate(kept.results):
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
    assert t.schema.field("run").type == pa.int64() and t.column_names[0] == "run"
    assert t.schema.field("steps").type == pa.int64()
    assert t.schema.field("perturb").type == pa.bool_()
    assert t.schema.field("rng").type == pa.string()
    assert t.schema.field("lateral_drift").type == pa.float64()
    assert (
        t.column("lateral_drift").to_pylist()
        == simloop.table(simloop.run_batch(seeds=[0, 1], steps=100))["lateral_drift"].tolist()
    )


def test_a_sweep_is_one_row_per_timestep():
    sweep = simloop.sweep(timesteps=[0.001, 0.002, 0.05, 0.1], duration=1.0)
    df = simloop.to_pandas(sweep)
    assert df["timestep"].tolist() == [p.timestep for p in sweep.points]
    assert df["stable"].tolist() == [p.stable for p in sweep.points]
    assert df["peak_box_z"].tolist() == [p.peak_box_z for p in sweep.points]
    assert df["edge"].tolist() == [p.timestep == sweep.edge for p in sweep.points]
    assert df["steps"].dtype == np.int64 and df["warnings"].dtype == np.int64
    assert (
        simloop.to_arrow(sweep).num_rows == 4 and simloop.table(sweep)["timestep"].tolist() == df["timestep"].tolist()
    )


def test_tables_pickle_and_concatenate():
    a = simloop.run_batch(seeds=[0, 1], steps=100, metrics_only=True)
    b = simloop.run_batch(seeds=[2], steps=100, metrics_only=True)
    assert pickle.loads(pickle.dumps(a)) == a
    joined = simloop.BatchTable.concat([a, b])
    whole = simloop.run_batch(seeds=[0, 1, 2], steps=100, metrics_only=True)
    # Joined as they are: each table's `run` is its own; every other column is the whole batch's.
    assert joined["run"].tolist() == [0, 1, 0]
    assert all(np.array_equal(joined[k], whole[k]) for k in whole if k not in ("run", "rng"))
    assert joined["rng"].tolist() == whole["rng"].tolist() and joined.column_names == whole.column_names
    assert joined != a and joined != whole
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


def seed_and_timestep(result):
    """A RunResult's or a ScenarioResult's (seed, timestep)."""
    seed = result.config.seed if isinstance(result, simloop.RunResult) else result.seed
    return seed, result.timestep


@pytest.mark.parametrize("kind", ["chapter", "scenario"])
def test_a_batch_is_one_kind_of_table_locally_metrics_only_and_on_an_executor(kind):
    def batch(seeds=(5, 6), **kwargs):
        if kind == "chapter":
            return simloop.run_batch(seeds=seeds, timesteps=[0.002, 0.004], steps=200, **kwargs)
        return simloop.run_scenario_batch(PUSHT, seeds=seeds, timesteps=[None, 0.004], steps=200, **kwargs)

    kept = batch(threads=2)
    lean = batch(metrics_only=True, threads=2)
    with ThreadPoolExecutor(2) as pool:
        remote = batch(executor=pool, chunk_size=3)
    for table in (kept, lean, remote):
        assert type(table) is simloop.BatchTable and len(table) == 4
        assert table.column_names == kept.column_names and table.column_names[0] == "run"
        assert [table[name].dtype for name in table] == [kept[name].dtype for name in kept]
        assert table == kept  # bit for bit
        assert table["run"].tolist() == [0, 1, 2, 3]
    assert (kept.has_results, lean.has_results, remote.has_results) == (True, False, False)
    # The results are the rows' runs, in the rows' order (itertools.product(seeds, timesteps)).
    assert [seed_and_timestep(r) for r in kept.results] == [
        (kept.row(i)["seed"], kept.row(i)["timestep"]) for i in range(len(kept))
    ]
    assert kept["seed"].tolist() == [5, 5, 6, 6]
    # No runs: no rows and no columns, in every mode.
    with ThreadPoolExecutor(1) as pool:
        empty = [batch(seeds=[]), batch(seeds=[], metrics_only=True), batch(seeds=[], executor=pool)]
    assert [(len(t), t.column_names, t.has_results) for t in empty] == [(0, [], True), (0, [], False), (0, [], False)]


def test_a_table_iterates_over_its_column_names_and_is_indexed_by_name_only():
    t = simloop.run_batch(seeds=[0, 1, 2], steps=50)
    assert list(t) == t.column_names and "lateral_drift" in t and 0 not in t
    for index in (0, np.int64(1), -1, slice(0, 2), True):
        with pytest.raises(
            TypeError,
            match=r"^a BatchTable is indexed by column name, got .+: table\.row\(i\) is "
            r"run i's row as a dict, table\.results\[i\] its result \(when the batch "
            r"kept them\)$",
        ):
            t[index]
    with pytest.raises(KeyError, match="no column named 'drift'"):
        t["drift"]
    row = t.row(1)
    assert list(row) == t.column_names
    assert row["run"] == 1 and row["seed"] == 1 and row["timestep"] == 0.002 and row["rng"] == "mt19937_64"
    assert [type(row[k]) for k in ("seed", "steps", "perturb", "rng", "lateral_drift")] == [int, int, bool, str, float]
    assert row["lateral_drift"] == t["lateral_drift"][1] == t.results[1].unrounded_metrics["lateral_drift"]
    assert t.row(-1) == t.row(2) and t.row(np.int64(0)) == t.row(0) and t.row(0) != t.row(2)
    for index in (3, -4):
        with pytest.raises(IndexError, match=rf"^index {index} is out of range for a table of 3 rows$"):
            t.row(index)
    with pytest.raises(TypeError, match=r"^index must be an int, got '1' \(str\)$"):
        t.row("1")


def test_a_table_without_results_says_so_in_one_line():
    lean = simloop.run_batch(seeds=[0], steps=50, metrics_only=True)
    assert not lean.has_results
    with pytest.raises(
        ValueError,
        match=r"^this BatchTable holds no results, only its columns: metrics_only=True and "
        r"executor= batches keep none \(run the batch locally without them to keep "
        r"each run's result\)$",
    ):
        lean.results
    with pytest.raises(ValueError, match=r"^results must hold one result per row \(2\), got 1$"):
        simloop.BatchTable({"x": np.zeros(2)}, [simloop.run(steps=10)])


def test_results_survive_pickling_and_concat_when_every_table_has_them():
    a = simloop.run_batch(seeds=[0, 1], steps=100)
    b = simloop.run_batch(seeds=[2], steps=100)
    back = pickle.loads(pickle.dumps(a))
    assert back == a and back.has_results and len(back.results) == 2
    assert [r.trajectory.tobytes() for r in back.results] == [r.trajectory.tobytes() for r in a.results]
    joined = simloop.BatchTable.concat([a, b])
    assert [id(r) for r in joined.results] == [id(r) for r in a.results + b.results]
    mixed = simloop.BatchTable.concat([a, simloop.run_batch(seeds=[2], steps=100, metrics_only=True)])
    assert len(mixed) == 3 and not mixed.has_results
    with pytest.raises(TypeError, match=r"^tables\[0\] must be a BatchTable, got list$"):
        simloop.BatchTable.concat([a.results, b])


def test_a_table_of_a_list_of_results_numbers_them_and_keeps_them():
    runs = [simloop.run(seed=s, steps=50) for s in (7, 3)]
    t = simloop.table(runs)
    assert t["run"].tolist() == [0, 1] and t["seed"].tolist() == [7, 3]
    assert [id(r) for r in t.results] == [id(r) for r in runs]
    assert simloop.table(t) is t and simloop.to_pandas(runs)["seed"].tolist() == [7, 3]
    empty = simloop.table([])
    assert len(empty) == 0 and empty.column_names == [] and empty.results == []


def test_the_docs_batches_example_runs(capsys, monkeypatch):
    text = (ROOT / "docs" / "scaling.md").read_text()
    section = text.split("## Batches, tables\n", 1)[1]
    code = section.split("```python\n", 1)[1].split("```", 1)[0]
    monkeypatch.chdir(ROOT)
    exec(compile(code, "docs/scaling.md: Batches, tables", "exec"), {})
    last = capsys.readouterr().out.splitlines()[-1]
    assert last.startswith("ScenarioResult(name='pusht', seed=0, steps=1000,") and last.endswith(") 25")


def test_a_table_of_runs_with_different_columns_leaves_a_gap_as_nan():
    # A perturbed run has its disturbance's columns; a baseline run (perturb=False) has none: the table of both
    # has the union, NaN where a run has no such value, and a count of steps stays an integer where every run has it.
    pushed = simloop.run_scenario(PUSHT, seed=0, steps=200)
    baseline = simloop.run_scenario(PUSHT, seed=1, steps=200, perturb=False)
    t = simloop.table([baseline, pushed])
    assert t["disturbance0_fy"][1] == pushed.disturbances[0]["force"][1] and np.isnan(t["disturbance0_fy"][0])
    assert t["disturbance0_start_step"].dtype == np.float64 and np.isnan(t["disturbance0_start_step"][0])
    assert t.column_names.index("tblock_final_pos_x") < t.column_names.index("disturbance0_fx")
    assert t["tblock_final_pos_x"].tolist() == [r.trajectory[-1, r.bodies["tblock"]] for r in (baseline, pushed)]
    alone = simloop.table([pushed, pushed])
    assert alone["disturbance0_start_step"].dtype == np.int64 and alone["steps"].tolist() == [200, 200]
    assert not t["diverged"].any() and t["warning_simloop_DIVERGED"].tolist() == [0, 0]
