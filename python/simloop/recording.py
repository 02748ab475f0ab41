"""The run as a rerun recording (.rrd), as the chapter logs it.

Layout: static Boxes3D for world/objects/box and world/robot/pusher; every 5th
step a Transform3D for each on the `sim_time` timeline (seconds, as a
duration); an Arrows3D at world/objects/box/shove showing the shove scaled by
0.02 while it acts and zero-length otherwise.

Two choices differ from the chapter's listing, on purpose:
- The poses come from the trajectory (qpos, the state entering each step).
  The chapter logs mjData.xpos, which mj_step computed before integrating, so
  it lags qpos by one step.
- The arrow's entity is a child of the box, so rerun draws it in the box's
  frame. The chapter passes world coordinates there, which would put the
  arrow at twice the box's position; we log it from the box's own origin,
  with the world-frame shove rotated into the box's frame.

Frames are sent as columns (rerun's send_columns), one call per entity,
rather than one log call per frame: for 400 frames this is several times
faster. rerun is imported only here, only when recording; the stream writes
to a file sink, so no viewer is spawned and no connection is made.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import Optional, Union

from . import _core
from ._api import ModelLike, load_model

# rerun accepts this application id as it is (no "/" or ".").
APPLICATION_ID = "simloop_ch0_1_sim_loop"
FRAME_EVERY = 5
SHOVE_ARROW_SCALE = 0.02
BOX_HALF_SIZES = (0.05, 0.05, 0.05)
BOX_COLOR = (217, 76, 64)
PUSHER_HALF_SIZES = (0.04, 0.12, 0.05)
PUSHER_COLOR = (64, 115, 217)


def _rotate_into_body(quat_wxyz, vectors):
    """Rotates world vectors into each body's frame (by the conjugate quaternion)."""
    import numpy as np

    w = quat_wxyz[:, :1]
    u = -quat_wxyz[:, 1:]  # conjugate: the inverse rotation for a unit quaternion
    t = 2.0 * np.cross(u, vectors)
    return vectors + w * t + np.cross(u, t)


def frames(result: _core.RunResult, model: ModelLike = None) -> dict:
    """What record() logs, as arrays: one row per frame (every 5th step).

    Keys: step, sim_time, box_translation, box_quaternion_xyzw,
    pusher_translation, shove_vector (box frame, scaled), shove_world (scaled).
    """
    import numpy as np

    cols = result.columns
    steps = cols["step"]
    # Every 5th step that the trajectory holds, entering the step (the final
    # state, which enters no step, is not a frame: as in the chapter).
    pick = np.flatnonzero((steps % FRAME_EVERY == 0) & (steps < steps[-1]))
    box = np.column_stack([cols["box_x"][pick], cols["box_y"][pick], cols["box_z"][pick]])
    quat_wxyz = np.column_stack([cols[c][pick] for c in ("box_qw", "box_qx", "box_qy", "box_qz")])
    rest, axis, q0 = _core.pusher_track(load_model(model))
    pusher = rest + np.outer(cols["pusher_x"][pick] - q0, axis)
    shove_world = SHOVE_ARROW_SCALE * np.column_stack([cols["shove_x"][pick], cols["shove_y"][pick],
                                                       cols["shove_z"][pick]])
    return {
        "step": steps[pick].astype(np.int64),
        "sim_time": cols["time"][pick],
        "box_translation": box,
        # MuJoCo stores quaternions w-x-y-z; rerun wants x-y-z-w.
        "box_quaternion_xyzw": quat_wxyz[:, [1, 2, 3, 0]],
        "pusher_translation": pusher,
        "shove_world": shove_world,
        "shove_vector": _rotate_into_body(quat_wxyz, shove_world),
    }


def record(result: _core.RunResult, path: Union[str, "os.PathLike[str]"], model: ModelLike = None) -> Path:
    """Writes the run to `path` as an .rrd recording and returns the path.

    The file is written beside its destination and renamed into place, so a
    failure leaves any earlier recording as it was. `model` is the one the
    run used (None: the chapter's scene); it places the pusher.
    """
    import numpy as np
    import rerun as rr

    target = Path(path)
    data = frames(result, model)
    fd, temp_name = tempfile.mkstemp(prefix="." + target.name + ".", suffix=".tmp", dir=target.parent)
    os.close(fd)
    try:
        rec = rr.RecordingStream(APPLICATION_ID, recording_id="simloop", send_properties=False)
        rec.save(temp_name)
        # Shapes and colours never change: static, logged once.
        rec.log("world/objects/box", rr.Boxes3D(half_sizes=[BOX_HALF_SIZES], colors=[BOX_COLOR]), static=True)
        rec.log("world/robot/pusher", rr.Boxes3D(half_sizes=[PUSHER_HALF_SIZES], colors=[PUSHER_COLOR]),
                static=True)
        times = [rr.TimeColumn("sim_time", duration=data["sim_time"])]
        rec.send_columns("world/objects/box", indexes=times,
                         columns=rr.Transform3D.columns(translation=data["box_translation"],
                                                        quaternion=data["box_quaternion_xyzw"]))
        rec.send_columns("world/robot/pusher", indexes=times,
                         columns=rr.Transform3D.columns(translation=data["pusher_translation"]))
        rec.send_columns("world/objects/box/shove", indexes=times,
                         columns=rr.Arrows3D.columns(origins=np.zeros_like(data["shove_vector"]),
                                                     vectors=data["shove_vector"]))
        rec.flush()
        rec.disconnect()
        os.chmod(temp_name, 0o644)
        os.replace(temp_name, target)
    except BaseException:
        Path(temp_name).unlink(missing_ok=True)
        raise
    return target
