"""What the compiled classes do not yet do as the package promises, done in
Python until the bindings do it (python/bindings.cc; then this module goes).

- A wrong argument to a method: pybind11 answers with its several-line
  "incompatible function arguments" and the signatures; these methods
  answer with one line naming the argument (and, being Python, a wrong
  argument count gets Python's own one line too). Only types are checked
  here: the values are the C++ side's to check.
- A convenience of the sweep's result: SweepResult.to_pandas / to_arrow
  (simloop.tables).

`import simloop` runs install() once, before anyone can reach the classes.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Dict, List, Tuple, Union

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray

from ._checks import PathLike, _check_path, _check_real, _check_text, _describe, _show
from ._core import Model, RunResult, SweepResult


def install() -> None:
    """Replaces the compiled methods with the checked ones (once)."""
    compiled: Dict[Tuple[type, str], Callable[..., Any]] = {(cls, name): getattr(cls, name) for cls, name in (
        (Model, "from_file"), (Model, "from_xml_string"), (Model, "pusher_scene"), (Model, "with_timestep"),
        (RunResult, "column"), (RunResult, "write"), (RunResult, "metrics_json"), (RunResult, "trajectory_csv"),
        (RunResult, "summary"), (SweepResult, "write"), (SweepResult, "csv"), (SweepResult, "summary"))}

    def from_file(path: PathLike) -> Model:
        model: Model = compiled[Model, "from_file"](_check_path("path", path, "an MJCF file"))
        return model

    def from_xml_string(xml: Union[str, bytes], source: str = "<string>") -> Model:
        model: Model = compiled[Model, "from_xml_string"](_check_text("xml", xml), _check_text("source", source))
        return model

    def pusher_scene() -> Model:
        model: Model = compiled[Model, "pusher_scene"]()
        return model

    def with_timestep(self: Model, timestep: float) -> Model:
        copy: Model = compiled[Model, "with_timestep"](self, _check_real("timestep", timestep))
        return copy

    def column(self: RunResult, name: str) -> NDArray[np.float64]:
        if not isinstance(name, str):
            raise TypeError(f"name must be a str (a column name), got {_describe(name)}")
        if name not in self.column_names:  # (the compiled lookup cannot take a str UTF-8 cannot encode)
            raise KeyError(f"no trajectory column named {_show(name)}; see result.column_names")
        view: NDArray[np.float64] = compiled[RunResult, "column"](self, name)
        return view

    def write_run(self: RunResult, out: PathLike) -> Tuple[Path, Path]:
        paths: Tuple[Path, Path] = compiled[RunResult, "write"](self, _check_path("out", out, "a directory"))
        return paths

    def write_sweep(self: SweepResult, out: PathLike) -> Path:
        path: Path = compiled[SweepResult, "write"](self, _check_path("out", out, "a directory"))
        return path

    def no_arguments(cls: type, name: str) -> Callable[[object], str]:
        def method(self: object) -> str:
            text: str = compiled[cls, name](self)
            return text
        return method

    def sweep_to_pandas(self: SweepResult) -> Any:
        from .tables import sweep_table  # numpy and pandas: loaded when asked for

        return sweep_table(self).to_pandas()

    def sweep_to_arrow(self: SweepResult) -> Any:
        from .tables import sweep_table  # numpy and pyarrow: loaded when asked for

        return sweep_table(self).to_arrow()

    static: List[Tuple[Callable[..., Model], str]] = [
        (from_file, "Compiles an MJCF file: OSError if it cannot be read, simloop.MujocoError if MuJoCo rejects it, "
                    "ValueError if it lacks a body 'box' on a free joint or an actuator 0 on a slide or hinge joint."),
        (from_xml_string, "Compiles MJCF text (str or UTF-8 bytes); it needs a body 'box' on a free joint and an "
                          "actuator 0 on a slide or hinge joint. source names it in errors."),
        (pusher_scene, "The chapter's scene.")]
    for function, doc in static:
        function.__qualname__ = f"Model.{function.__name__}"
        function.__doc__ = doc
        setattr(Model, function.__name__, staticmethod(function))
    methods: List[Tuple[type, str, Callable[..., Any], str]] = [
        (Model, "with_timestep", with_timestep, "A copy with opt.timestep set (a positive, finite number)."),
        (RunResult, "column", column, "One trajectory column as a read-only (strided) view (no copy); "
                                      "KeyError if the result has no such column."),
        (RunResult, "write", write_run, "Writes metrics.json and trajectory.csv into out (a directory, made if "
                                        "missing), the bytes sim_loop writes; returns their paths."),
        (SweepResult, "write", write_sweep, "Writes sweep.csv into out (atomically); returns its path."),
        (RunResult, "metrics_json", no_arguments(RunResult, "metrics_json"), "metrics.json's text."),
        (RunResult, "trajectory_csv", no_arguments(RunResult, "trajectory_csv"), "trajectory.csv's text."),
        (RunResult, "summary", no_arguments(RunResult, "summary"), "The lines sim_loop prints about the run."),
        (SweepResult, "csv", no_arguments(SweepResult, "csv"), "sweep.csv's text."),
        (SweepResult, "summary", no_arguments(SweepResult, "summary"), "The sweep's table, edge and criterion."),
        (SweepResult, "to_pandas", sweep_to_pandas, "A pandas.DataFrame: one row per timestep (see simloop.tables)."),
        (SweepResult, "to_arrow", sweep_to_arrow, "A pyarrow.Table: one row per timestep (see simloop.tables)."),
    ]
    for cls, name, checked, doc in methods:
        checked.__name__ = name
        checked.__qualname__ = f"{cls.__name__}.{name}"
        checked.__doc__ = doc
        setattr(cls, name, checked)
