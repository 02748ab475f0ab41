"""A run as a rerun recording (.rrd): one recorder for any scene, drawn from
its own geometry, and what a kind of run shows beyond it given as a view
(recording_views: a scenario's, and the chapter's with what it says to look
for); record() writes a chapter run held in memory as the command does.

Layout (rerun-sdk 0.41), every recorded row (every step by default, the final
state included) on two timelines, `sim_time` (seconds, as a duration; the
viewer opens on it) and `step` (a sequence):

- world/static/<geom>: the world body's geoms, where they are. A plane
  (infinite for MuJoCo's collisions) is a thin slab whose top is the plane,
  of the size the scene gives it (widened to reach 0.5 m beyond where the
  bodies start, if they start off it): the scene's floor, not the run's.
- world/bodies/<body>: a Transform3D per row for every body that moves; its
  geoms below it, world/bodies/<body>/<geom>, static, with their shape,
  colour and place on the body: boxes, spheres and ellipsoids, capsules,
  cylinders; meshes as their bounding boxes.
- plots/<column>: trajectory columns as scalars (float64: the values
  exactly); a scenario's every column but step and time, in panels by
  quantity (positions, orientations, velocities, forces, controls, contacts,
  the rest), each named with its unit.

The 3D view opens framed on where the moving bodies start (the chapter's
follows its box instead).

Recording is the recorder, as a scenario's run uses it: python -m simloop
(__main__._drawings) makes one, and the command's run into --out (the
library's run_to_folder) writes trajectory.csv as it steps (its columns are
the scenario's, recording or not) and keeps each block of rows followed by
every moving body's pose (its frame in the world, read where the recorded
bodies' poses are), which __main__._draw hands the recording once the run is
done.

The chapter's run is drawn by the same recorder through its view
(recording_views.chapter_view: its paths, its poses from its trajectory, the
shove arrow, its series and panels, its recording id).

The recording id is derived from what decides the run (the chapter's: seed,
steps, timestep, shove, generator, record_every, energy audit and the model;
a scenario's: the command line and the bytes of its scenario and scene
files) and from the MuJoCo it steps on (recording_views.mujoco_build), so
the same run on one build always gets the same id and two different runs, or
the same run on the two builds, open as two recordings instead of merging
into one. rerun does not let us make
the bytes repeat: it stamps every chunk and row with a time-based id and
gives the embedded blueprint a random store id, so two identical runs give
two files with the same data (`rerun rrd compare --unordered a.rrd b.rrd`
says so: rerun may batch the same rows into chunks differently) but
different bytes.

Rows come in blocks and are sent as columns (rerun's send_columns, one call
per entity) every BLOCK_ROWS rows, each block written before the next is
gathered, so memory stays bounded however long the run; the planes, the
blueprint (with the z axis's range) and the recording's name are logged at
its end. rerun is imported only here (and in _rerun_parts, the pieces it
logs), only when recording; its file sink
writes into a pipe whose bytes simloop writes to the file and checks
(RrdFile), so no viewer is spawned, no connection is made, and a full disk is
an error, not a hang or a truncated file.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Dict, List, Mapping, Sequence, Tuple, Union

from . import _core
from ._checks import ModelLike, load_model
from ._command import signals_wait
from ._rerun_parts import QUANTITIES, _eye, _layout, _plane_slab, _pose, _rgba, _rotate_into_body, _shape
from ._rrd_file import RrdFile
from .recording_views import Panel, View, chapter_view

# Rows gathered before they go to the file as columns: a few hundred kB of
# numbers for a scene of tens of columns.
BLOCK_ROWS = 4096
POSE = ("_x", "_y", "_z", "_qw", "_qx", "_qy", "_qz")  # after a scenario's columns, per moving body


class Recording:
    """The .rrd of one run of `model`'s scene, drawn as `view` says
    (recording_views: a scenario's, the chapter's), written as the run goes:
    the run calls columns(names) once, rows(block) per block of rows and
    finish(result) once it is done, before it puts its outputs in place
    together with `files`. close() abandons the file if it was not finished.
    `path` is where the recording goes; it is written beside it and checked
    first (RrdFile)."""

    def __init__(self, model: _core.Model, path: Union[str, "os.PathLike[str]"], view: View) -> None:
        import rerun as rr

        self._rr = rr
        self.view = view
        self.moving_bodies: List[str] = list(_core.moving_bodies(model))
        self._nq = model.nq  # a scenario's drawn rows end with qpos (for pictures)
        self._names: List[str] = []  # the trajectory's columns
        self._series: List[str] = []  # those plotted, then the speeds
        self._ranged: set = set()  # those whose panel sets its value axis from their range
        self._pending: list = []
        self._pending_rows = 0
        self._planes: list = []  # the world's planes: drawn once the bodies' start is known
        self._low: Any = None  # the smallest and largest finite x, y, z of a body at the start
        self._high: Any = None
        self._units: Dict[str, str] = {}  # column: unit, from the result
        self._ranges: Dict[str, Tuple[float, float]] = {}  # (low, high) of each series whose panel sets its axis
        self._time_end = 0.0  # the last row's sim time
        self.colours: Dict[str, list] = {}  # body: its first geom's colour
        self.file = RrdFile(rr, view.application_id, view.recording_id, Path(os.fspath(path)))
        self._rec: Any = self.file.rec
        try:
            drawn = set(self.moving_bodies if view.paths is None else view.paths)
            for geom in _core.scene_geometry(model):
                if geom["body_id"] == 0:
                    if geom["kind"] == "plane":
                        self._planes.append(geom)
                        continue
                    entity = f"world/static/{geom['name']}"
                elif geom["body"] in drawn:
                    entity = f"{self._entity(geom['body'])}/{geom['name']}"
                else:
                    continue  # welded to the world under a body of its own (it never moves), or not posed
                shape = _shape(rr, geom)
                if shape is None:
                    continue
                self.colours.setdefault(geom["body"], _rgba(geom["rgba"]))
                self._rec.log(entity, _pose(rr, geom), static=True)
                self._rec.log(entity, shape, static=True)
            if view.arrow is not None:
                arrow = view.arrow
                self._rec.log(
                    f"{self._entity(arrow.body)}/{arrow.name}",
                    rr.Arrows3D.from_fields(colors=[arrow.colour], radii=[arrow.radius]),
                    static=True,
                )
            if view.camera is not None:
                # What the camera follows: rerun frames a tracked entity by its
                # bounds, and the body alone (the chapter's box: 10 cm) would fill
                # the view; this invisible frame around it keeps more in view.
                body, half = view.camera
                self._rec.log(
                    f"{self._entity(body)}/camera_frame",
                    rr.Boxes3D(
                        half_sizes=[[half, half, half / 2]],
                        colors=[[0, 0, 0, 0]],
                        fill_mode="majorwireframe",
                        radii=[0.0],
                    ),
                    static=True,
                )
        except BaseException:
            self.file.close()
            raise

    # The drawing sink's three calls.
    def columns(self, names: Sequence[str]) -> None:
        """The columns of the rows to come: the view's, or a scenario's
        trajectory's, then x y z qw qx qy qz per moving body, then qpos."""
        expected = self.view.columns
        if expected is None:
            self._names = list(names[: len(names) - len(POSE) * len(self.moving_bodies) - self._nq])
        elif list(names) == expected:
            self._names = list(names)
        else:  # the run and the recording disagree on what a row holds
            raise ValueError(f"the recording draws the columns {expected}, the run records {list(names)}")
        series = self.view.series
        plotted = [n for n in self._names if (n not in ("step", "time") if series is None else n in series)]
        self._series = plotted + list(self.view.speeds)
        self._ranged = {c for panel in self.view.panels or [] if panel.axis is not None for c in panel.columns}
        for name in self._series:
            label, colour = (name, None) if series is None else series[name]
            if isinstance(colour, str):  # a body's
                colour = self.colours.get(colour)
            self._rec.log(
                f"plots/{name}",
                self._rr.SeriesLines(names=[label], colors=None if colour is None else [colour]),
                static=True,
            )

    def rows(self, block: Any) -> None:
        self._pending.append(block)
        self._pending_rows += len(block)
        if self._pending_rows >= BLOCK_ROWS:
            self._send()

    def finish(self, result: Any) -> None:
        """Sends what is left, the world's planes, the blueprint and the
        recording's name, and checks the file."""
        self._send()
        self._units = dict(result.column_units)
        rr = self._rr
        for plane in self._planes:
            centre, half = _plane_slab(plane, self._low, self._high)
            entity = f"world/static/{plane['name']}"
            self._rec.log(entity, _pose(rr, plane), static=True)
            self._rec.log(
                entity,
                rr.Boxes3D(centers=[centre], half_sizes=[half], colors=[_rgba(plane["rgba"])], fill_mode="solid"),
                static=True,
            )
        with signals_wait():  # rerun's blueprint passes through a MemorySink that warns if dropped full
            self._rec.send_blueprint(self._blueprint(), make_active=False, make_default=True)
        self._rec.send_recording_name(self.view.name(result))
        self.file.finish()

    @property
    def files(self) -> list:
        """The run's `also`: the recording's file."""
        return self.file.files

    def close(self) -> None:
        """Abandons the file if it was not finished."""
        self.file.close()

    def _entity(self, body: str) -> str:
        """Where a moving body is drawn: the view's path, or world/bodies/<body>."""
        paths = self.view.paths
        return f"world/bodies/{body}" if paths is None else paths[body]

    def _poses(self, block: Any, cols: Mapping[str, Any]) -> Dict[str, Tuple[Any, Any]]:
        """{body: (positions, w x y z quaternions)}, a row each: the view's, or the poses after the trajectory's
        columns."""
        if self.view.poses is not None:
            return self.view.poses(cols, len(block))
        at = len(self._names)
        return {
            body: (block[:, at + 7 * i : at + 7 * i + 3], block[:, at + 7 * i + 3 : at + 7 * (i + 1)])
            for i, body in enumerate(self.moving_bodies)
        }

    def _send(self) -> None:
        import numpy as np

        if not self._pending:
            return
        rr = self._rr
        block = np.concatenate(self._pending)
        self._pending, self._pending_rows = [], 0
        cols = {name: block[:, c] for c, name in enumerate(self._names)}
        for name, (vx, vy, vz) in self.view.speeds.items():
            cols[name] = np.sqrt(cols[vx] ** 2 + cols[vy] ** 2 + cols[vz] ** 2)
        times = [
            rr.TimeColumn("sim_time", duration=cols["time"]),
            rr.TimeColumn("step", sequence=cols["step"].astype(np.int64)),
        ]
        starts = []  # where the bodies are in the run's first row
        poses = self._poses(block, cols)
        for body, (position, quat_wxyz) in poses.items():
            if self._low is None and len(position) and np.all(np.isfinite(position[0])):
                starts.append(position[0])
            self._rec.send_columns(
                self._entity(body),
                indexes=times,  # rerun's quaternions are x y z w
                columns=rr.Transform3D.columns(
                    translation=np.ascontiguousarray(position), quaternion=quat_wxyz[:, [1, 2, 3, 0]]
                ),
            )
        if starts:
            self._low, self._high = np.min(starts, axis=0), np.max(starts, axis=0)
        for name in self._series:
            values = cols[name]
            self._rec.send_columns(
                f"plots/{name}", indexes=times, columns=rr.Scalars.columns(scalars=np.ascontiguousarray(values))
            )
            finite = values[np.isfinite(values)] if name in self._ranged else values[:0]
            if finite.size:
                low, high = float(finite.min()), float(finite.max())
                seen = self._ranges.get(name)
                self._ranges[name] = (low, high) if seen is None else (min(seen[0], low), max(seen[1], high))
        if self.view.arrow is not None:
            self._send_arrow(times, cols, poses)
        self._time_end = max(self._time_end, float(np.nanmax(cols["time"])))
        # rerun writes the file on a thread of its own and queues what it has
        # not written yet: waiting for it here keeps that queue to one block
        # (10^6 rows of 35 columns sent as fast as they came: 280 MiB more without).
        self.file.flush()

    def _send_arrow(self, times: list, cols: Mapping[str, Any], poses: Mapping[str, Tuple[Any, Any]]) -> None:
        """The view's arrow, rotated into its body's frame (its parent's): the
        vector, and its origin above the body's centre in the world's z."""
        import numpy as np

        arrow = self.view.arrow
        assert arrow is not None
        # The final row has no step after it, so no shove (its input cells are NaN).
        vectors = arrow.scale * np.nan_to_num(np.column_stack([cols[c] for c in arrow.columns]))
        quat = poses[arrow.body][1]
        above = np.tile([0.0, 0.0, arrow.height], (len(vectors), 1))
        self._rec.send_columns(
            f"{self._entity(arrow.body)}/{arrow.name}",
            indexes=times,
            columns=self._rr.Arrows3D.columns(
                origins=_rotate_into_body(quat, above), vectors=_rotate_into_body(quat, vectors)
            ),
        )

    def _blueprint(self) -> Any:
        """The series in the view's panels (or by quantity) beside the 3D view,
        whose camera looks at where the bodies start (following the view's
        camera frame if it has one)."""
        import rerun.blueprint as rrb

        view = self.view
        panels = view.panels if view.panels is not None else self._panels_by_quantity()
        time_axis = None
        if view.open_on_run:  # rerun opened Break It's on empty negative time
            time_axis = rrb.TimeAxis(
                view_range=rrb.TimeRange(
                    start=rrb.TimeRangeBoundary.absolute(seconds=0.0),
                    end=rrb.TimeRangeBoundary.absolute(seconds=self._time_end),
                )
            )
        views = []
        for panel in panels:
            spans = [self._ranges[c] for c in panel.columns if c in self._ranges]
            span = (min(s[0] for s in spans), max(s[1] for s in spans)) if spans else None
            axis_range = None if panel.axis is None else panel.axis(span)
            views.append(
                rrb.TimeSeriesView(
                    name=panel.title,
                    origin="/plots",
                    contents=[f"/plots/{c}" for c in panel.columns],
                    axis_x=time_axis,
                    axis_y=rrb.ScalarAxis(range=axis_range) if axis_range else None,
                    plot_legend=rrb.PlotLegend(corner=rrb.Corner2D.LeftTop, visible=panel.legend),
                )
            )
        tracking = None if view.camera is None else f"{self._entity(view.camera[0])}/camera_frame"
        return _layout(
            rrb.Vertical(*views) if views else rrb.TimeSeriesView(name="what was recorded", origin="/plots"),
            _eye(self._low, self._high, tracking),
        )

    def _panels_by_quantity(self) -> List[Panel]:
        """A scenario's panels: its series by quantity (QUANTITIES), from their names and units."""
        panels: Dict[str, List[str]] = {}
        for name in self._series:
            unit = self._units.get(name, "")
            title = next(title for title, holds in QUANTITIES if holds(name, unit))
            panels.setdefault(title, []).append(name)
        return [Panel(title, panels[title]) for title, _ in QUANTITIES if title in panels]


def record(result: _core.RunResult, path: Union[str, "os.PathLike[str]"], model: ModelLike = None) -> Path:
    """Writes an in-memory run of the chapter to `path` as an .rrd recording,
    as the command does, and returns the path.

    The file is written beside its destination and renamed into place, so a
    failure leaves any earlier recording as it was. `model` is the one the
    run used (None: the chapter's scene; a path identifies a file's model in
    the recording id better than a Model object can); its geometry is drawn.
    """
    target = Path(path)
    scene = load_model(model)
    recording = Recording(scene, target, chapter_view(result.config, model, scene))
    try:
        recording.columns(result.column_names)
        recording.rows(result.trajectory)
        recording.finish(result)
        _core.commit_files(recording.files)
    finally:
        recording.close()
    return target
