"""A scenario's run as a rerun recording (.rrd): the scene's own shapes.

Layout (rerun-sdk 0.41), every recorded row on the sim_time and step
timelines:

- world/static/<geom>: the world body's geoms (a floor plane drawn as a thin
  slab of its size, 1 m where MuJoCo's plane is infinite), where they are.
- world/bodies/<body>: a Transform3D per row for every body that moves (not
  welded to the world, or mocap), recorded or not: the walker's legs as well
  as its torso. Its geoms below it, world/bodies/<body>/<geom>, with their
  shape, colour and place on the body: boxes, spheres and ellipsoids,
  capsules, cylinders; meshes as their bounding boxes.
- plots/<column>: every trajectory column but step and time, as scalars.

The poses come from the run itself: the command runs the scenario once with
run_scenario_to_files(..., drawing=ScenarioRecording(...)), which writes
trajectory.csv as it steps (its columns are the scenario's, recording or not)
and hands this class each block of rows followed by every moving body's pose
(its frame in the world, read where the recorded bodies' poses are). Blocks
are sent as columns every BLOCK_ROWS rows, and each block is written before
the next is gathered, so memory stays bounded however long the run.

The recording id is derived from what decides the run (the command line and
the bytes of the scenario and scene files), so the same run gets the same id
and two runs open side by side. As for the chapter's recording, rerun stamps
time-based ids, so two identical runs give the same data but not the same
bytes.
"""

from __future__ import annotations

import os
import uuid
from pathlib import Path
from typing import Any, List, Mapping, Sequence, Union

from . import _core
from .recording import RrdFile

APPLICATION_ID = "simloop_scenario"
PLANE_THICKNESS = 0.01
# Rows gathered before they go to the file as columns: a few hundred kB of
# numbers for a scene of tens of columns.
BLOCK_ROWS = 4096
POSE = ("_x", "_y", "_z", "_qw", "_qx", "_qy", "_qz")


def _rgba(colour) -> list:
    return [int(round(255 * max(0.0, min(1.0, c)))) for c in colour]


def _shape(rr, geom: Mapping[str, Any]):
    """The rerun archetype that draws `geom` in its own frame."""
    kind, half, colour = geom["kind"], geom["half_size"], [_rgba(geom["rgba"])]
    if kind == "box":
        return rr.Boxes3D(half_sizes=[half], colors=colour, fill_mode="solid")
    if kind == "mesh":
        return rr.Boxes3D(half_sizes=[half], centers=[geom["mesh_center"]], colors=colour, fill_mode="solid")
    if kind == "plane":
        return rr.Boxes3D(half_sizes=[[half[0], half[1], PLANE_THICKNESS / 2]], centers=[[0, 0, -PLANE_THICKNESS / 2]],
                          colors=colour, fill_mode="solid")
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


class ScenarioRecording:
    """The .rrd of one scenario run, written as the run goes: pass it as
    run_scenario_to_files's `drawing` and `recording.files` as its `also`;
    run_scenario_to_files calls finish(result) once the run is done, before
    it puts the outputs in place, all together. close() abandons the file if
    it was not finished. `path` is where the recording goes; it is written
    beside it and checked first (recording.RrdFile)."""

    def __init__(self, model: _core.Model, path: Union[str, "os.PathLike[str]"], run_key: str) -> None:
        import rerun as rr
        import rerun.blueprint as rrb

        self._rr = rr
        self.moving_bodies: List[str] = list(_core.moving_bodies(model))
        self._names: List[str] = []
        self._pending: list = []
        self._pending_rows = 0
        run_id = uuid.uuid5(uuid.NAMESPACE_URL, "simloop-scenario:" + run_key)
        blueprint = rrb.Blueprint(
            rrb.Horizontal(rrb.Spatial3DView(name="the scene", origin="/world"),
                           rrb.TimeSeriesView(name="what was recorded", origin="/plots"), column_shares=[3, 2]),
            collapse_panels=False)
        self.file = RrdFile(rr, APPLICATION_ID, str(run_id), Path(os.fspath(path)), blueprint)
        self._rec: Any = self.file.rec
        try:
            moving = set(self.moving_bodies)
            for geom in _core.scene_geometry(model):
                if geom["body"] == "world":
                    entity = f"world/static/{geom['name']}"
                elif geom["body"] in moving:
                    entity = f"world/bodies/{geom['body']}/{geom['name']}"
                else:
                    continue  # welded to the world under a body of its own: it never moves
                shape = _shape(rr, geom)
                if shape is None:
                    continue
                self._rec.log(entity, _pose(rr, geom), static=True)
                self._rec.log(entity, shape, static=True)
        except BaseException:
            self.file.close()
            raise

    # The drawing sink's two calls (see run_scenario_to_files).
    def columns(self, names: Sequence[str]) -> None:
        """The trajectory's columns, then x y z qw qx qy qz per moving body."""
        self._names = list(names[:len(names) - len(POSE) * len(self.moving_bodies)])
        for name in self._names:
            if name not in ("step", "time"):
                self._rec.log(f"plots/{name}", self._rr.SeriesLines(names=[name]), static=True)

    def rows(self, block) -> None:
        self._pending.append(block)
        self._pending_rows += len(block)
        if self._pending_rows >= BLOCK_ROWS:
            self._send()

    def _send(self) -> None:
        import numpy as np

        if not self._pending:
            return
        rr = self._rr
        data = np.concatenate(self._pending)
        self._pending, self._pending_rows = [], 0
        width = len(self._names)
        times = [rr.TimeColumn("sim_time", duration=data[:, self._names.index("time")]),
                 rr.TimeColumn("step", sequence=data[:, self._names.index("step")])]
        for i, body in enumerate(self.moving_bodies):
            pose = data[:, width + len(POSE) * i:width + len(POSE) * (i + 1)]
            self._rec.send_columns(f"world/bodies/{body}", indexes=times,
                                   columns=rr.Transform3D.columns(translation=np.ascontiguousarray(pose[:, 0:3]),
                                                                  quaternion=pose[:, [4, 5, 6, 3]]))
        for c, name in enumerate(self._names):
            if name not in ("step", "time"):
                self._rec.send_columns(f"plots/{name}", indexes=times,
                                       columns=rr.Scalars.columns(scalars=np.ascontiguousarray(data[:, c])))
        # rerun writes the file on a thread of its own and queues what it has
        # not written yet: waiting for it here keeps that queue to one block
        # (10^6 rows of 35 columns sent as fast as they came: 280 MiB more without).
        self.file.flush()

    def finish(self, result: _core.ScenarioResult) -> None:
        """Sends what is left, names the recording after the run, checks the file."""
        self._send()
        self._rec.send_recording_name(
            f"{result.name or 'scenario'}: {result.steps} steps of {result.timestep:g} s, seed {result.seed}")
        self.file.finish()

    @property
    def files(self) -> list:
        """run_scenario_to_files's `also`: the recording's file."""
        return self.file.files

    def close(self) -> None:
        """Abandons the file if it was not finished."""
        self.file.close()
