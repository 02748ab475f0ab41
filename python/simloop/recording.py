"""A run as a rerun recording (.rrd): one recorder for any scene, drawn from
its own geometry; the chapter's run is one scene on it, with what the chapter
says to look for added on top.

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

The chapter's run adds its own on top (chapter_recording.ChapterRecording:
its poses from its trajectory, the shove arrow, its series and panels).

The recording id is derived from what decides the run (the chapter's: seed,
steps, timestep, shove, generator, record_every, energy audit and the model;
a scenario's: the command line and the bytes of its scenario and scene
files) and from the MuJoCo it steps on (mujoco_build: version and build), so
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
its end. rerun is imported only here, only when recording; its file sink
writes into a pipe whose bytes simloop writes to the file and checks
(RrdFile), so no viewer is spawned, no connection is made, and a full disk is
an error, not a hang or a truncated file.
"""

from __future__ import annotations

import os
import uuid
from pathlib import Path
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

from . import _core
from ._build import MUJOCO_BUILD
from ._command import signals_wait
from ._rrd_file import RrdFile

# rerun accepts these application ids as they are (no "/" or ".").
SCENARIO_APPLICATION_ID = "simloop_scenario"
# Rows gathered before they go to the file as columns: a few hundred kB of
# numbers for a scene of tens of columns.
BLOCK_ROWS = 4096
POSE = ("_x", "_y", "_z", "_qw", "_qx", "_qy", "_qz")  # after a scenario's columns, per moving body
PLANE_THICKNESS = 0.01
PLANE_MARGIN = 0.5  # how far a plane reaches beyond where the bodies start


def mujoco_build() -> str:
    """The MuJoCo a run steps on, in its recording id: the same run on another
    MuJoCo (2.2.2 and the PyPI build's 4.0.0) moves otherwise, so it is
    another recording."""
    return f"{_core.MUJOCO_VERSION} ({MUJOCO_BUILD})"


def scenario_recording_id(run_key: str) -> str:
    """A scenario run's recording id, from what decides the run (the command's
    _run_key) and the MuJoCo it steps on."""
    return str(uuid.uuid5(uuid.NAMESPACE_URL, "simloop-scenario:" + mujoco_build() + "\0" + run_key))


def _rotate_into_body(quat_wxyz, vectors):
    """Rotates world vectors into each body's frame (by the conjugate quaternion)."""
    import numpy as np

    w = quat_wxyz[:, :1]
    u = -quat_wxyz[:, 1:]  # conjugate: the inverse rotation for a unit quaternion
    t = 2.0 * np.cross(u, vectors)
    return vectors + w * t + np.cross(u, t)


def _rgba(colour) -> list:
    return [int(round(255 * max(0.0, min(1.0, c)))) for c in colour]


def _shape(rr, geom: Mapping[str, Any]):
    """The rerun archetype that draws `geom` in its own frame (a plane: see _plane_slab)."""
    kind, half, colour = geom["kind"], geom["half_size"], [_rgba(geom["rgba"])]
    if kind == "box":
        return rr.Boxes3D(half_sizes=[half], colors=colour, fill_mode="solid")
    if kind == "mesh":
        return rr.Boxes3D(half_sizes=[half], centers=[geom["mesh_center"]], colors=colour, fill_mode="solid")
    if kind in ("sphere", "ellipsoid"):
        return rr.Ellipsoids3D(half_sizes=[half], colors=colour, fill_mode="solid")
    if kind == "capsule":  # rerun's capsule runs from its translation along +z
        return rr.Capsules3D(lengths=[2 * half[2]], radii=[half[0]], translations=[[0, 0, -half[2]]], colors=colour)
    if kind == "cylinder":
        return rr.Cylinders3D(lengths=[2 * half[2]], radii=[half[0]], colors=colour, fill_mode="solid")
    return None  # heightfields and the like: not drawn


def _pose(rr, geom: Mapping[str, Any]):
    w, x, y, z = geom["quat"]
    return rr.Transform3D(translation=geom["pos"], quaternion=[x, y, z, w])


def _plane_slab(geom: Mapping[str, Any], low: Any, high: Any) -> Tuple[list, list]:
    """(centre, half sizes), in the plane's frame, of a slab whose top is the
    plane: the plane's own size, widened to reach PLANE_MARGIN beyond the
    world box [low, high] where the bodies start (None: nowhere finite)."""
    import numpy as np

    hi = np.asarray(geom["half_size"][:2], dtype=float)
    lo = -hi
    if low is not None:
        corners = np.array([[x, y, z] for x in (low[0], high[0]) for y in (low[1], high[1]) for z in (low[2], high[2])])
        local = _rotate_into_body(np.tile(geom["quat"], (len(corners), 1)), corners - geom["pos"])[:, :2]
        lo = np.minimum(lo, local.min(axis=0) - PLANE_MARGIN)
        hi = np.maximum(hi, local.max(axis=0) + PLANE_MARGIN)
    return [*((lo + hi) / 2), -PLANE_THICKNESS / 2], [*((hi - lo) / 2), PLANE_THICKNESS / 2]


def _layout(plots: Any, eye: Any = None) -> Any:
    """The blueprint: the 3D view on the left (its camera `eye`), `plots` on
    the right, on the sim_time timeline."""
    import rerun.blueprint as rrb

    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Spatial3DView(name="the scene", origin="/world", eye_controls=eye), plots, column_shares=[3, 2]
        ),
        rrb.TimePanel(timeline="sim_time"),
        collapse_panels=False,
    )


def _eye(low: Any, high: Any, tracking: Optional[str] = None) -> Any:
    """A camera on the region [low, high] where the moving bodies start, from
    the front left and above, far enough to see all of it (at least a metre
    across); following `tracking`'s entity if given."""
    import numpy as np
    import rerun.blueprint as rrb

    if low is None:
        return None
    centre = (np.asarray(low) + np.asarray(high)) / 2
    span = max(1.0, float(np.max(np.asarray(high) - np.asarray(low))))
    position = centre + span * np.array([-0.6, -1.2, 0.7])
    return rrb.EyeControls3D(look_target=centre.tolist(), position=position.tolist(), tracking_entity=tracking)


# A scenario's panels: each column's quantity, by its name and unit, in this order.
QUANTITIES = [
    ("positions (m)", lambda name, unit: unit == "m" and name[-3:] not in ("_qw", "_qx", "_qy", "_qz")),
    ("orientations (quaternion w x y z)", lambda name, unit: name[-3:] in ("_qw", "_qx", "_qy", "_qz")),
    ("velocities (m/s, rad/s)", lambda name, unit: unit.startswith(("m/s", "rad/s"))),
    ("forces (N, N m)", lambda name, unit: unit.startswith("N")),
    ("controls", lambda name, unit: name.endswith("_ctrl")),
    ("contacts", lambda name, unit: name in ("contacts", "ncon")),
    ("the rest", lambda name, unit: True),
]


class Recording:
    """The .rrd of one run of `model`'s scene, written as the run goes: the
    run calls columns(names) once, rows(block) per block of rows and
    finish(result) once it is done, before it puts its outputs in place
    together with `files`. close() abandons the file if it was not finished. `path` is
    where the recording goes; it is written beside it and checked first
    (RrdFile). `bodies`: the moving bodies the rows pose (None: all of them,
    as the command's run gives them).

    The hooks below (_entity, _poses, _style, _send_more, _blueprint, _name)
    are where a kind of run says what its rows hold and where it draws them;
    chapter_recording.ChapterRecording is the one other."""

    def __init__(
        self,
        model: _core.Model,
        path: Union[str, "os.PathLike[str]"],
        recording_id: str,
        application_id: str = SCENARIO_APPLICATION_ID,
        bodies: Optional[Sequence[str]] = None,
    ) -> None:
        import rerun as rr

        self._rr = rr
        self.moving_bodies: List[str] = list(_core.moving_bodies(model))
        self._nq = model.nq  # a scenario's drawn rows end with qpos (for pictures)
        self._names: List[str] = []  # the trajectory's columns
        self._series: List[str] = []  # those plotted
        self._pending: list = []
        self._pending_rows = 0
        self._planes: list = []  # the world's planes: drawn once the bodies' start is known
        self._low: Any = None  # the smallest and largest finite x, y, z of a body at the start
        self._high: Any = None
        self._units: Dict[str, str] = {}  # column: unit, from the result
        self.colours: Dict[str, list] = {}  # body: its first geom's colour
        self.file = RrdFile(rr, application_id, recording_id, Path(os.fspath(path)))
        self._rec: Any = self.file.rec
        try:
            drawn = set(self.moving_bodies if bodies is None else bodies)
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
        except BaseException:
            self.file.close()
            raise

    # The drawing sink's three calls.
    def columns(self, names: Sequence[str]) -> None:
        """The trajectory's columns, then x y z qw qx qy qz per moving body, then qpos."""
        self._names = list(names[: len(names) - len(POSE) * len(self.moving_bodies) - self._nq])
        self._plot([name for name in self._names if name not in ("step", "time")])

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
        self._rec.send_recording_name(self._name(result))
        self.file.finish()

    @property
    def files(self) -> list:
        """The run's `also`: the recording's file."""
        return self.file.files

    def close(self) -> None:
        """Abandons the file if it was not finished."""
        self.file.close()

    def _plot(self, columns: Sequence[str]) -> None:
        """The columns shown as series, plots/<column>, each named and coloured once."""
        self._series = list(columns)
        for name in self._series:
            self._log_style(name)

    def _log_style(self, name: str) -> None:
        label, colour = self._style(name)
        self._rec.log(
            f"plots/{name}",
            self._rr.SeriesLines(names=[label], colors=None if colour is None else [colour]),
            static=True,
        )

    def _send(self) -> None:
        import numpy as np

        if not self._pending:
            return
        rr = self._rr
        block = np.concatenate(self._pending)
        self._pending, self._pending_rows = [], 0
        cols = {name: block[:, c] for c, name in enumerate(self._names)}
        times = [
            rr.TimeColumn("sim_time", duration=cols["time"]),
            rr.TimeColumn("step", sequence=cols["step"].astype(np.int64)),
        ]
        starts = []  # where the bodies are in the run's first row
        for body, (position, quat_wxyz) in self._poses(block, cols).items():
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
            self._send_series(name, times, cols[name])
        self._send_more(times, cols)
        # rerun writes the file on a thread of its own and queues what it has
        # not written yet: waiting for it here keeps that queue to one block
        # (10^6 rows of 35 columns sent as fast as they came: 280 MiB more without).
        self.file.flush()

    def _send_series(self, name: str, times: list, values: Any) -> None:
        import numpy as np

        self._rec.send_columns(
            f"plots/{name}", indexes=times, columns=self._rr.Scalars.columns(scalars=np.ascontiguousarray(values))
        )

    # What a kind of run says about its rows; these are a scenario's.
    def _entity(self, body: str) -> str:
        """Where a moving body is drawn: world/bodies/<body>."""
        return f"world/bodies/{body}"

    def _poses(self, block: Any, cols: Mapping[str, Any]) -> Dict[str, Tuple[Any, Any]]:
        """{body: (positions, w x y z quaternions)}, a row each: here the poses after the trajectory's columns."""
        at = len(self._names)
        return {
            body: (block[:, at + 7 * i : at + 7 * i + 3], block[:, at + 7 * i + 3 : at + 7 * (i + 1)])
            for i, body in enumerate(self.moving_bodies)
        }

    def _style(self, name: str) -> Tuple[str, Optional[Sequence[int]]]:
        """(label, colour) of the series plots/<name>; a colour of None is rerun's choice."""
        return name, None

    def _send_more(self, times: list, cols: Mapping[str, Any]) -> None:
        """Whatever else a block of rows shows (the chapter's shove)."""

    def _blueprint(self) -> Any:
        """The series in panels by quantity; the 3D view on where the bodies start."""
        import rerun.blueprint as rrb

        panels: Dict[str, List[str]] = {}
        for name in self._series:
            unit = self._units.get(name, "")
            title = next(title for title, holds in QUANTITIES if holds(name, unit))
            panels.setdefault(title, []).append(name)
        views = [
            rrb.TimeSeriesView(
                name=title,
                origin="/plots",
                contents=[f"/plots/{c}" for c in panels[title]],
                plot_legend=rrb.PlotLegend(corner=rrb.Corner2D.LeftTop, visible=True),
            )
            for title, _ in QUANTITIES
            if title in panels
        ]
        return _layout(
            rrb.Vertical(*views) if views else rrb.TimeSeriesView(name="what was recorded", origin="/plots"),
            _eye(self._low, self._high),
        )

    def _name(self, result: Any) -> str:
        """A name for people, shown in the viewer's list of recordings."""
        return f"{result.name or 'scenario'}: {result.steps} steps of {result.timestep:g} s, seed {result.seed}"
