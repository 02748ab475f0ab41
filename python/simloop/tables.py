"""Batch and sweep results as tables: one row per run, flat columns.

    >>> import simloop
    >>> results = simloop.run_batch(seeds=range(8))
    >>> simloop.to_pandas(results)            # a pandas.DataFrame, 8 rows
    >>> simloop.run_batch(seeds=range(10_000), metrics_only=True).to_arrow()

`table(results)` turns a list of RunResult (from run / run_batch) or of
ScenarioResult (from run_scenario / run_scenario_batch) into a BatchTable:
numpy columns, one row per run, in the list's order. A metrics-only batch
returns one directly. `to_pandas(results)` and `to_arrow(results)` are
`table(results).to_pandas()` and `.to_arrow()`; SweepResult has its own
`.to_pandas()` and `.to_arrow()`, one row per timestep.

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
from typing import Any, Dict, Iterable, List, Mapping, Sequence

import numpy as np

from . import _core

WARNING_NAMES = tuple(_core.WARNING_NAMES)
# The warnings that mean the run's state blew up or was reset by MuJoCo.
DIVERGENCE_WARNINGS = ("mjWARN_BADQPOS", "mjWARN_BADQVEL", "mjWARN_BADQACC", "simloop_DIVERGED")
_ENERGY = ("energy_start", "energy_end", "work_actuator", "work_shove", "work_passive", "work_constraint",
           "work_constraint_positive", "unexplained")


def _need(module: str) -> Any:
    try:
        return __import__(module)
    except ImportError:
        raise ImportError(f"this conversion needs {module}, which comes with simloop's 'tables' extra: "
                          f"pip install 'simloop[tables]'") from None


class BatchTable:
    """Runs as a table: numpy columns of equal length, one row per run.

    table["lateral_drift"] is a column (a numpy array); table.column_names
    their order; len(table) the runs; to_pandas() a pandas.DataFrame,
    to_arrow() a pyarrow.Table, to_dict() {name: list}. Tables pickle, and
    BatchTable.concat(tables) joins tables of the same columns end to end.
    """

    def __init__(self, columns: Mapping[str, np.ndarray]) -> None:
        self._columns: Dict[str, np.ndarray] = {name: np.asarray(values) for name, values in columns.items()}
        lengths = {len(values) for values in self._columns.values()}
        if len(lengths) > 1:
            raise ValueError(f"columns must all have the same length, got lengths {sorted(lengths)}")
        self._rows = lengths.pop() if lengths else 0

    @property
    def column_names(self) -> List[str]:
        return list(self._columns)

    @property
    def columns(self) -> Dict[str, np.ndarray]:
        """Every column by name (the arrays themselves: do not write to them)."""
        return dict(self._columns)

    def __len__(self) -> int:
        return self._rows

    def __getitem__(self, name: str) -> np.ndarray:
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
            for a, b in zip(self._columns.values(), other._columns.values()))

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
        return pa.table({name: pa.array(values.tolist() if values.dtype == object else values)
                         for name, values in self._columns.items()})

    @staticmethod
    def concat(tables: Iterable["BatchTable"]) -> "BatchTable":
        """The tables' rows end to end (they must have the same columns, in the same order)."""
        parts = list(tables)
        if not parts:
            return BatchTable({})
        names = parts[0].column_names
        for i, part in enumerate(parts):
            if not isinstance(part, BatchTable):
                raise TypeError(f"tables[{i}] must be a BatchTable, got {type(part).__name__}")
            if part.column_names != names:
                raise ValueError(f"tables[{i}] has other columns than tables[0]")
        return BatchTable({name: np.concatenate([p._columns[name] for p in parts]) for name in names})


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
        "seed": np.uint64(config.seed), "rng": config.rng, "timestep": r.timestep, "steps": metrics["steps"],
        "perturb": config.perturb, "record_every": config.record_every, "audit_energy": config.audit_energy,
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


def _scenario_row(r: Any) -> Dict[str, Any]:
    row: Dict[str, Any] = {"scenario": r.name, "seed": np.uint64(r.seed), "rng": r.rng, "timestep": r.timestep,
                           "steps": r.steps, "perturb": r.perturb, "sim_time": r.sim_time}
    final = r.final_row
    for body, c in sorted(r.bodies.items()):
        for i, axis in enumerate("xyz"):
            row[f"{body}_final_pos_{axis}"] = float(final[c + i])
        row[f"{body}_final_speed"] = math.sqrt(sum(float(v) ** 2 for v in final[c + 7:c + 10]))
    for i, d in enumerate(r.disturbances):
        for axis, value in zip(("fx", "fy", "fz"), d["force"]):
            row[f"disturbance{i}_{axis}"] = float(value)
        for axis, value in zip(("tx", "ty", "tz"), d["torque"]):
            row[f"disturbance{i}_{axis}"] = float(value)
        row[f"disturbance{i}_start_step"] = d["start_step"]
        row[f"disturbance{i}_steps"] = d["end_step"] - d["start_step"]
    _warning_counts(row, r.warnings)
    return row


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


def _from_rows(rows: List[Dict[str, Any]]) -> BatchTable:
    names: Dict[str, None] = {}
    for row in rows:
        names.update(dict.fromkeys(row))
    # The warnings last, sorted by name; diverged after them.
    ordered = [n for n in names if not n.startswith("warning_") and n != "diverged"]
    ordered += sorted(n for n in names if n.startswith("warning_"))
    ordered += [n for n in names if n == "diverged"]
    return BatchTable({name: _column(name, [row.get(name) for row in rows]) for name in ordered})


def table(results: Iterable[Any]) -> BatchTable:
    """A BatchTable of a list of RunResult or of ScenarioResult, one row per run."""
    if isinstance(results, BatchTable):
        return results
    if isinstance(results, (_core.RunResult, _core.ScenarioResult, str, bytes)) or not isinstance(results, Iterable):
        raise TypeError(f"results must be a list of RunResult or of ScenarioResult, got {type(results).__name__}")
    items = list(results)
    kinds = {type(r) for r in items}
    if kinds == {_core.RunResult}:
        return _from_rows([_run_row(r) for r in items])
    if kinds == {_core.ScenarioResult}:
        return _from_rows([_scenario_row(r) for r in items])
    if not items:
        return BatchTable({})
    raise TypeError("results must be a list of RunResult or of ScenarioResult, not a mix, got "
                    + ", ".join(sorted(k.__name__ for k in kinds)))


def to_pandas(results: Iterable[Any]) -> Any:
    """table(results).to_pandas(): a pandas.DataFrame, one row per run."""
    return table(results).to_pandas()


def to_arrow(results: Iterable[Any]) -> Any:
    """table(results).to_arrow(): a pyarrow.Table, one row per run."""
    return table(results).to_arrow()


def sweep_table(result: Any) -> BatchTable:
    """A sweep as a BatchTable: one row per timestep, ascending."""
    edge = result.edge
    rows = []
    for p in result.points:
        rows.append({
            "timestep": p.timestep, "steps": p.steps, "duration": result.duration, "stable": p.stable,
            "edge": edge is not None and p.timestep == edge, "peak_box_z": p.peak_box_z,
            "max_abs_box_y": p.max_abs_box_y, "final_box_x": p.final_box_x, "final_box_y": p.final_box_y,
            "final_box_z": p.final_box_z, "final_pusher_x": p.final_pusher_x, "warnings": p.warnings,
            "energy_change": p.energy_change, "energy_unexplained": p.energy_unexplained,
            "work_constraint_positive": p.work_constraint_positive,
        })
    return _from_rows(rows)
