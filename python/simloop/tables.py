"""Batch and sweep results as tables: one row per run, flat columns.

    >>> import simloop
    >>> batch = simloop.run_batch(seeds=range(8))
    >>> batch.to_pandas()                     # a pandas.DataFrame, 8 rows
    >>> batch.results[0].trajectory           # run 0's RunResult, kept
    >>> simloop.run_batch(seeds=range(10_000), metrics_only=True).to_arrow()

run_batch and run_scenario_batch return a BatchTable in every mode (rows
kept, metrics_only=True, executor=), with the same columns: numpy columns,
one row per run in itertools.product order, the first column `run` (the
row's index in the batch). A batch run locally without metrics_only also
keeps its runs' results (table.results); the others keep none.

`table(results)` turns a list of RunResult (from run) or of ScenarioResult
(from run_scenario) into the same kind of BatchTable, one row per run in the
list's order, keeping the list as its results. `to_pandas(results)` and
`to_arrow(results)` are `table(results).to_pandas()` and `.to_arrow()`;
of a SweepResult, `table(sweep)` is one row per timestep (and no `run`
column).

Columns are flat and typed: numbers only (no lists: box_final_pos is
box_final_pos_x, _y, _z), integers as int64 (the seed as uint64), flags as
bool, and the generator's and scenario's names as strings. Metrics are
unrounded: rounding to 6 decimals is for metrics.json. Every warning simloop
knows (WARNING_NAMES: MuJoCo's and simloop_DIVERGED) is a column
`warning_<name>` with its count, 0 where it was not raised, so that every
table of the same kind of run has the same columns (chunks of a batch join,
Parquet files append); `diverged` says whether the run's state blew up:
simloop_DIVERGED, or a MuJoCo warning after which MuJoCo resets the state
(DIVERGENCE_WARNINGS).

pandas and pyarrow are the `tables` extra (pip install 'simloop[tables]');
they are imported only when a conversion asks for them.
"""

from __future__ import annotations

import math
from typing import Any, Dict, Generic, Iterable, Iterator, List, Mapping, Optional, Sequence, TypeVar, Union, overload

import numpy as np

from . import _core
from ._checks import _check_int, _describe

WARNING_NAMES = tuple(_core.WARNING_NAMES)
# The warnings that mean the run's state blew up or was reset by MuJoCo.
DIVERGENCE_WARNINGS = ("mjWARN_BADQPOS", "mjWARN_BADQVEL", "mjWARN_BADQACC", "simloop_DIVERGED")
_ENERGY = (
    "energy_start",
    "energy_end",
    "work_actuator",
    "work_shove",
    "work_passive",
    "work_constraint",
    "work_constraint_positive",
    "unexplained",
)


def _need(module: str) -> Any:
    try:
        return __import__(module)
    except ImportError:
        raise ImportError(
            f"this conversion needs {module}, which comes with simloop's 'tables' extra: pip install 'simloop[tables]'"
        ) from None


# The kind of result a table's rows come from: RunResult (run_batch,
# table of RunResults) or ScenarioResult (run_scenario_batch, ...).
Result = TypeVar("Result", covariant=True)
_Kind = TypeVar("_Kind")

_NO_RESULTS = (
    "this BatchTable holds no results, only its columns: metrics_only=True and executor= batches "
    "keep none (run the batch locally without them to keep each run's result)"
)


class BatchTable(Generic[Result]):
    """Runs as a table: numpy columns of equal length, one row per run, and
    the runs' results when they were kept.

    What run_batch and run_scenario_batch return, locally, metrics-only or
    on an executor alike: the same columns, in the same order, of the same
    dtypes, the first being `run`, the row's index in the batch
    (itertools.product order). table["lateral_drift"] is a column (a numpy
    array); table.column_names their order; len(table) the runs;
    table.row(i) run i's row as a dict; table.results the runs' results
    (RunResult or ScenarioResult, trajectories and all) in the rows' order,
    when the table has them (has_results: a local batch without
    metrics_only; a metrics-only or executor batch has none, and asking for
    them raises ValueError). Like a pandas DataFrame, iterating a table
    yields its column names, and `name in table` is about columns; a table
    is indexed by column name only (table[0] raises TypeError: use
    table.row(0) or table.results[0]).

    to_pandas() a pandas.DataFrame, to_arrow() a pyarrow.Table, to_dict()
    {name: list}. Tables pickle (with their results), compare equal when
    their columns are (results are not compared), and
    BatchTable.concat(tables) joins tables of the same columns end to end.
    """

    @overload
    def __init__(self: "BatchTable[Any]", columns: Mapping[str, np.ndarray]) -> None: ...

    @overload
    def __init__(self, columns: Mapping[str, np.ndarray], results: Sequence[Result]) -> None: ...

    def __init__(self, columns: Mapping[str, np.ndarray], results: Optional[Sequence[Result]] = None) -> None:
        """columns: name -> values, all of one length; results: None, or
        one result per row (table.results)."""
        self._columns: Dict[str, np.ndarray] = {name: np.asarray(values) for name, values in columns.items()}
        lengths = {len(values) for values in self._columns.values()}
        if len(lengths) > 1:
            raise ValueError(f"columns must all have the same length, got lengths {sorted(lengths)}")
        self._rows = lengths.pop() if lengths else 0
        self._results: Optional[List[Result]] = None if results is None else list(results)
        if self._results is not None and len(self._results) != self._rows:
            raise ValueError(f"results must hold one result per row ({self._rows}), got {len(self._results)}")

    @property
    def column_names(self) -> List[str]:
        return list(self._columns)

    @property
    def columns(self) -> Dict[str, np.ndarray]:
        """Every column by name (the arrays themselves: do not write to them)."""
        return dict(self._columns)

    @property
    def has_results(self) -> bool:
        """Whether the table holds its runs' results (table.results)."""
        return self._results is not None

    @property
    def results(self) -> List[Result]:
        """The runs' results, one per row in the rows' order (the list itself:
        do not change it). ValueError if the table has none (has_results)."""
        if self._results is None:
            raise ValueError(_NO_RESULTS)
        return self._results

    def row(self, index: int) -> Dict[str, Any]:
        """Row `index` (negative counts from the end) as {column name: value},
        the values as Python's int, float, bool and str."""
        i = _check_int("index", index)
        if not -self._rows <= i < self._rows:
            raise IndexError(f"index {i} is out of range for a table of {self._rows} rows")
        return {
            name: values[i].item() if isinstance(values[i], np.generic) else values[i]
            for name, values in self._columns.items()
        }

    def __len__(self) -> int:
        return self._rows

    def __iter__(self) -> Iterator[str]:
        """The column names, as a pandas.DataFrame's iteration gives them."""
        return iter(self._columns)

    def __getitem__(self, name: str) -> np.ndarray:
        if not isinstance(name, str):
            shown = _describe(name)
            raise TypeError(
                f"a BatchTable is indexed by column name, got {shown}: table.row(i) is run i's row as "
                "a dict, table.results[i] its result (when the batch kept them)"
            )
        if name not in self._columns:
            raise KeyError(f"no column named {name!r}; see table.column_names")
        return self._columns[name]

    def __contains__(self, name: object) -> bool:
        return name in self._columns

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, BatchTable):
            return NotImplemented
        return self.column_names == other.column_names and all(
            a.dtype == b.dtype and a.tobytes() == b.tobytes() if a.dtype != object else list(a) == list(b)
            for a, b in zip(self._columns.values(), other._columns.values())
        )

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        names = self.column_names
        shown = ", ".join(names[:6]) + (f", ... ({len(names)} columns)" if len(names) > 6 else "")
        return f"BatchTable(rows={self._rows}, columns=[{shown}])"

    def to_dict(self) -> Dict[str, List[Any]]:
        return {name: values.tolist() for name, values in self._columns.items()}

    def to_pandas(self) -> Any:
        """A pandas.DataFrame: one row per run, the columns' dtypes kept."""
        pd = _need("pandas")
        return pd.DataFrame({name: values for name, values in self._columns.items()}, copy=False)

    def to_arrow(self) -> Any:
        """A pyarrow.Table: one row per run (strings as string, the rest as their numpy types)."""
        pa = _need("pyarrow")
        return pa.table(
            {
                name: pa.array(values.tolist() if values.dtype == object else values)
                for name, values in self._columns.items()
            }
        )

    @staticmethod
    def concat(tables: Iterable["BatchTable[_Kind]"]) -> "BatchTable[_Kind]":
        """The tables' rows end to end (they must have the same columns, in
        the same order), with their results if every table has them. The
        columns are joined as they are: a `run` column keeps each table's
        own values."""
        if isinstance(tables, (str, bytes, BatchTable)) or not isinstance(tables, Iterable):
            raise TypeError(f"tables must be a list of BatchTable, got {type(tables).__name__}")
        parts = list(tables)
        if not parts:
            return BatchTable({})
        for i, part in enumerate(parts):
            if not isinstance(part, BatchTable):
                raise TypeError(f"tables[{i}] must be a BatchTable, got {type(part).__name__}")
        names = parts[0].column_names
        for i, part in enumerate(parts):
            if part.column_names != names:
                raise ValueError(f"tables[{i}] has other columns than tables[0]")
        columns = {name: np.concatenate([p._columns[name] for p in parts]) for name in names}
        if all(p._results is not None for p in parts):
            return BatchTable(columns, [r for p in parts for r in p.results])
        return BatchTable(columns)


def _warning_counts(row: Dict[str, Any], warnings: Sequence[Any]) -> None:
    counts = {name: 0 for name in WARNING_NAMES}
    for w in warnings:
        counts[w.name] = counts.get(w.name, 0) + int(w.count)
    for name, count in counts.items():
        row["warning_" + name] = count
    row["diverged"] = any(counts.get(name, 0) > 0 for name in DIVERGENCE_WARNINGS)


def _run_row(r: Any) -> Dict[str, Any]:
    config = r.config
    metrics = r.unrounded_metrics
    row: Dict[str, Any] = {
        "seed": np.uint64(config.seed),
        "rng": config.rng,
        "timestep": r.timestep,
        "steps": metrics["steps"],
        "perturb": config.perturb,
        "record_every": config.record_every,
        "audit_energy": config.audit_energy,
    }
    for axis, value in zip("xyz", metrics["box_final_pos"]):
        row["box_final_pos_" + axis] = value
    for key in ("box_final_speed", "pusher_final_x", "lateral_drift", "shove_moved_box"):
        row[key] = metrics[key]
    row["shove_force_y"] = r.shove.force_y if config.perturb else 0.0
    row["shove_start_step"] = r.shove.start_step
    row["shove_steps"] = r.shove.steps if config.perturb else 0
    row["sim_time"] = r.sim_time
    energy = r.energy
    if energy is not None:
        for key in _ENERGY:
            row["energy_unexplained" if key == "unexplained" else key] = energy[key]
    _warning_counts(row, r.warnings)
    return row


def param_column(kind: str, name: str) -> str:
    """A scene parameter's column: friction, friction_<geom>, mass_<body>, damping, damping_<joint>,
    gravity. The rule a run's draws are named by (C++ scene_param_column), so that a value has one column."""
    return _core.scene_param_column(kind, name)


def _scenario_columns(arrays: Dict[str, Any]) -> Dict[str, np.ndarray]:
    """A scenario batch's columns from its ScenarioTable's arrays (include/simloop/batch_table.hpp: one row per
    run, reduced in C++): the ones every row has, then each layout's (a column that some runs lack is NaN there),
    then the warnings' counts, sorted by name, and `diverged`."""
    n = len(arrays["seed"])
    columns: Dict[str, np.ndarray] = {
        "scenario": np.array(arrays["scenario"], dtype=object),
        "seed": arrays["seed"],
        "rng": np.array(arrays["rng"], dtype=object),
        "timestep": arrays["timestep"],
        "steps": arrays["steps"],
        "perturb": arrays["perturb"],
        "sim_time": arrays["sim_time"],
    }
    layout, integers = arrays["layout"], set()
    for k, (names, values) in enumerate(zip(arrays["layouts"], arrays["values"])):
        rows = np.flatnonzero(layout == k)
        for c, (name, integer) in enumerate(names):
            if name not in columns:
                columns[name] = np.full(n, np.nan)
            columns[name][rows] = values[:, c]
            if integer:
                integers.add(name)
    for name in integers:  # counts of steps, where every run has one
        if not np.isnan(columns[name]).any():
            columns[name] = columns[name].astype(np.int64)
    counts = arrays["warnings"]
    for w in sorted(range(len(WARNING_NAMES)), key=lambda w: WARNING_NAMES[w]):
        columns["warning_" + WARNING_NAMES[w]] = counts[:, w].copy() if n else np.zeros(0, dtype=np.int64)
    diverged = [WARNING_NAMES.index(name) for name in DIVERGENCE_WARNINGS]
    columns["diverged"] = (counts[:, diverged] > 0).any(axis=1) if n else np.zeros(0, dtype=bool)
    return columns


def _core_table(core: Any, results: Optional[List[Any]] = None) -> BatchTable[Any]:
    """The BatchTable of a C++ ScenarioTable, with `results` kept or none."""
    columns = _scenario_columns(core.arrays())
    if len(columns["seed"]):  # an empty table has no columns at all, not even `run`
        columns = {"run": np.arange(len(columns["seed"]), dtype=np.int64), **columns}
    else:
        columns = {}
    return BatchTable(columns) if results is None else BatchTable(columns, results)


def _column(name: str, values: List[Any]) -> np.ndarray:
    present = [v for v in values if v is not None]
    if name.startswith("warning_"):
        return np.array([0 if v is None else v for v in values], dtype=np.int64)
    if len(present) < len(values):
        if all(isinstance(v, (bool, np.bool_)) for v in present):
            return np.array([False if v is None else v for v in values], dtype=bool)
        if all(isinstance(v, str) for v in present):
            return np.array(["" if v is None else v for v in values], dtype=object)
        return np.array([math.nan if v is None else float(v) for v in values], dtype=np.float64)
    first = present[0] if present else 0.0
    if isinstance(first, (bool, np.bool_)):
        return np.array(values, dtype=bool)
    if isinstance(first, np.uint64):
        return np.array(values, dtype=np.uint64)
    if isinstance(first, int):
        return np.array(values, dtype=np.int64)
    if isinstance(first, str):
        return np.array(values, dtype=object)
    return np.array(values, dtype=np.float64)


def _from_rows(rows: List[Dict[str, Any]]) -> BatchTable[Any]:
    names: Dict[str, None] = {}
    for row in rows:
        names.update(dict.fromkeys(row))
    # The warnings last, sorted by name; diverged after them.
    ordered = [n for n in names if not n.startswith("warning_") and n != "diverged"]
    ordered += sorted(n for n in names if n.startswith("warning_"))
    ordered += [n for n in names if n == "diverged"]
    return BatchTable({name: _column(name, [row.get(name) for row in rows]) for name in ordered})


@overload
def table(results: BatchTable[_Kind]) -> BatchTable[_Kind]: ...


@overload
def table(results: Iterable[_core.RunResult]) -> BatchTable[_core.RunResult]: ...


@overload
def table(results: Iterable[_core.ScenarioResult]) -> BatchTable[_core.ScenarioResult]: ...


@overload
def table(results: _core.SweepResult) -> BatchTable[Any]: ...


@overload
def table(results: Iterable[Any]) -> BatchTable[Any]: ...


def table(results: Union[_core.SweepResult, Iterable[Any]]) -> BatchTable[Any]:
    """A BatchTable of a list of RunResult or of ScenarioResult, one row per
    run in the list's order (its `run` column the index in the list), which
    keeps the list as table.results; of a SweepResult, one row per timestep
    (sweep_table). A BatchTable is returned as it is."""
    if isinstance(results, BatchTable):
        return results
    if isinstance(results, _core.SweepResult):
        return sweep_table(results)
    return _table(results, keep_results=True)


def _table(results: Iterable[Any], keep_results: bool) -> BatchTable[Any]:
    """table(results), keeping the results or not (a metrics-only batch's
    results have no trajectories: the table is all they are kept for)."""
    if isinstance(results, (_core.RunResult, _core.ScenarioResult, str, bytes)) or not isinstance(results, Iterable):
        raise TypeError(f"results must be a list of RunResult or of ScenarioResult, got {type(results).__name__}")
    items = list(results)
    # RunResult first: it is a kind of ScenarioResult (the chapter's report on the one run record).
    run_results = sum(isinstance(r, _core.RunResult) for r in items)
    if run_results == len(items) and items:
        rows = [_run_row(r) for r in items]
    elif not run_results and all(isinstance(r, _core.ScenarioResult) for r in items):
        return _core_table(_core.scenario_table(items), items if keep_results else None)
    else:
        kinds = {type(r).__name__ for r in items}
        raise TypeError(
            "results must be a list of RunResult or of ScenarioResult, not a mix, got " + ", ".join(sorted(kinds))
        )
    columns = _from_rows(rows).columns
    if items:  # an empty list has no columns at all, not even `run`
        columns = {"run": np.arange(len(items), dtype=np.int64), **columns}
    return BatchTable(columns, items) if keep_results else BatchTable(columns)


def to_pandas(results: Union[_core.SweepResult, Iterable[Any]]) -> Any:
    """table(results).to_pandas(): a pandas.DataFrame, one row per run (or timestep)."""
    return table(results).to_pandas()


def to_arrow(results: Union[_core.SweepResult, Iterable[Any]]) -> Any:
    """table(results).to_arrow(): a pyarrow.Table, one row per run (or timestep)."""
    return table(results).to_arrow()


def sweep_table(result: Any) -> BatchTable[Any]:
    """A sweep as a BatchTable: one row per timestep, ascending."""
    edge = result.edge
    rows = []
    for p in result.points:
        rows.append(
            {
                "timestep": p.timestep,
                "steps": p.steps,
                "duration": result.duration,
                "stable": p.stable,
                "edge": edge is not None and p.timestep == edge,
                "peak_box_z": p.peak_box_z,
                "max_abs_box_y": p.max_abs_box_y,
                "final_box_x": p.final_box_x,
                "final_box_y": p.final_box_y,
                "final_box_z": p.final_box_z,
                "final_pusher_x": p.final_pusher_x,
                "warnings": p.warnings,
                "energy_change": p.energy_change,
                "energy_unexplained": p.energy_unexplained,
                "work_constraint_positive": p.work_constraint_positive,
            }
        )
    return _from_rows(rows)
