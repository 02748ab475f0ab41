"""A scenario's run as a rerun recording (.rrd): the scene's own shapes.

Layout (rerun-sdk 0.41), every recorded row on the sim_time and step
timelines:

- world/static/<geom>: the world body's geoms (a floor plane drawn as a thin
  slab of its size, 1 m where MuJoCo's plane is infinite), where they are.
- world/bodies/<body>: a Transform3D per row for every recorded body (its
  position and orientation from the trajectory); its geoms below it,
  world/bodies/<body>/<geom>, with their shape, colour and place on the body:
  boxes, spheres and ellipsoids, capsules, cylinders; meshes as their
  bounding boxes. Bodies the scenario does not record are not drawn (the
  recording holds no poses for them).
- plots/<column>: every trajectory column but step and time, as scalars.

The recording id is derived from the scenario and the run's figures
(metrics.json's text), so the same run gets the same id and two runs open
side by side. As for the chapter's recording, rerun stamps time-based ids,
so two identical runs give the same data but not the same bytes.
"""

from __future__ import annotations

import os
import uuid
from pathlib import Path
from typing import Any, Mapping, Union

from . import _core
from .recording import replacing

APPLICATION_ID = "simloop_scenario"
PLANE_THICKNESS = 0.01


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


def record_scenario(result: _core.ScenarioResult, model: _core.Model,
                    path: Union[str, "os.PathLike[str]"]) -> Path:
    """Writes the run to `path` as an .rrd recording (beside it first, then
    renamed into place) and returns the path."""
    import numpy as np
    import rerun as rr
    import rerun.blueprint as rrb

    target = Path(path)
    names = list(result.column_names)
    data = np.asarray(result.trajectory)
    column = {name: data[:, i] for i, name in enumerate(names)}
    bodies = list(result.bodies)
    geoms = _core.scene_geometry(model)
    run_id = uuid.uuid5(uuid.NAMESPACE_URL, "simloop-scenario:" + result.name + ":" + result.metrics_json())
    with replacing(target) as temp_name:
        rec = rr.RecordingStream(APPLICATION_ID, recording_id=str(run_id), send_properties=False)
        blueprint = rrb.Blueprint(
            rrb.Horizontal(rrb.Spatial3DView(name="the scene", origin="/world"),
                           rrb.TimeSeriesView(name="what was recorded", origin="/plots"), column_shares=[3, 2]),
            collapse_panels=False)
        rec.save(temp_name, default_blueprint=blueprint)
        rec.send_recording_name(f"{result.name or 'scenario'}: {result.steps} steps of {result.timestep:g} s, seed {result.seed}")
        for geom in geoms:
            if geom["body"] == "world":
                entity = f"world/static/{geom['name']}"
            elif geom["body"] in bodies:
                entity = f"world/bodies/{geom['body']}/{geom['name']}"
            else:
                continue
            shape = _shape(rr, geom)
            if shape is None:
                continue
            rec.log(entity, _pose(rr, geom), static=True)
            rec.log(entity, shape, static=True)
        times = [rr.TimeColumn("sim_time", duration=column["time"]), rr.TimeColumn("step", sequence=column["step"])]
        for body in bodies:
            translation = np.stack([column[body + s] for s in ("_x", "_y", "_z")], axis=1)
            quaternion = np.stack([column[body + s] for s in ("_qx", "_qy", "_qz", "_qw")], axis=1)
            rec.send_columns(f"world/bodies/{body}", indexes=times,
                             columns=rr.Transform3D.columns(translation=translation, quaternion=quaternion))
        for name in names:
            if name in ("step", "time"):
                continue
            rec.log(f"plots/{name}", rr.SeriesLines(names=[name]), static=True)
            rec.send_columns(f"plots/{name}", indexes=times, columns=rr.Scalars.columns(scalars=column[name]))
        rec.flush()
        rec.disconnect()
    return target
