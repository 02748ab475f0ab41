"""The run as a rerun recording (.rrd): what the chapter says to look for.

Layout (rerun-sdk 0.41), every recorded step of the trajectory (every step
by default, the final state included) on two timelines, `sim_time` (seconds,
as a duration) and `step` (a sequence):

- world/floor: a static grey slab whose top is the floor (z = 0), covering
  the chapter's 4 m x 4 m floor and wherever the run went (MuJoCo's plane is
  infinite for collisions; its size only matters for drawing).
- world/objects/box, world/robot/pusher: static Boxes3D (the chapter's sizes
  and colours) moved by a Transform3D per step.
- world/objects/box/shove: an Arrows3D, the shove scaled by 0.02 while it
  acts and zero-length otherwise.
- plots/box/x, y, z, speed; plots/pusher/x; plots/contacts: scalar series
  (the box's z track is the chapter's diagnosis for Break It); with the energy
  audit, plots/energy/<column> for each of its columns, in joules.

The default blueprint opens the 3D view beside the time series.

The recording id is derived from the run's parameters (seed, steps,
timestep, shove, generator, record_every, energy audit and the model), so the
same run always gets the same id and two different runs open as two
recordings instead of merging into one. rerun does not let us make the bytes
repeat: it stamps every chunk and row with a time-based id and gives the
embedded blueprint a random store id, so two identical runs give two files
with the same data (`rerun rrd compare a.rrd b.rrd` says so) but different
bytes.

Two choices differ from the chapter's listing, on purpose:
- The poses come from the trajectory (qpos, the state entering each step).
  The chapter logs mjData.xpos, which mj_step computed before integrating, so
  it lags qpos by one step.
- The arrow's entity is a child of the box, so rerun draws it in the box's
  frame. The chapter passes world coordinates there, which would put the
  arrow at twice the box's position; we log it from the box's own origin,
  with the world-frame shove rotated into the box's frame.

Frames are sent as columns (rerun's send_columns), one call per entity, which
is what makes every step cheap. rerun is imported only here, only when
recording; the stream writes to a file sink, so no viewer is spawned and no
connection is made.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import tempfile
import uuid
from pathlib import Path
from typing import Iterator, Union

from . import _core
from ._api import ModelLike, _pusher_scene, load_model

# rerun accepts this application id as it is (no "/" or ".").
APPLICATION_ID = "simloop_ch0_1_sim_loop"
SHOVE_ARROW_SCALE = 0.02
BOX_HALF_SIZES = (0.05, 0.05, 0.05)
BOX_COLOR = (217, 76, 64)
PUSHER_HALF_SIZES = (0.04, 0.12, 0.05)
PUSHER_COLOR = (64, 115, 217)
FLOOR_COLOR = (217, 217, 217)  # the chapter's rgba 0.85 0.85 0.85
FLOOR_HALF_SIZE = 2.0          # the chapter's floor: size="2 2 0.1"
FLOOR_THICKNESS = 0.01
# Every recording id lives in this namespace (uuid5 of the run's parameters).
RECORDING_NAMESPACE = uuid.UUID("5b1e6c2e-9d7a-4f0e-8a43-0c6f3f1d2a10")

# plots/<path>: the scalar series, what they hold and their colour.
SERIES = {
    "box/x": ("box x (m)", BOX_COLOR),
    "box/y": ("box y (m), sideways", BOX_COLOR),
    "box/z": ("box z (m), height of its centre", BOX_COLOR),
    "box/speed": ("box speed (m/s)", BOX_COLOR),
    "pusher/x": ("pusher x (m)", PUSHER_COLOR),
    "contacts": ("contacts", (90, 90, 90)),
}
ENERGY_COLORS = {
    "energy": (0, 0, 0),
    "work_actuator": (64, 115, 217),
    "work_shove": (217, 76, 64),
    "work_passive": (120, 120, 120),
    "work_constraint": (181, 101, 29),
    "work_constraint_positive": (230, 160, 40),
    "energy_unexplained": (150, 60, 180),
}


def series_style(name: str) -> tuple:
    """(label, colour) of the series at plots/<name>."""
    if name in SERIES:
        return SERIES[name]
    column = name.split("/", 1)[1]  # energy/<column>
    return column + " (J)", ENERGY_COLORS[column]


def _model_key(model: ModelLike) -> str:
    """What identifies the model in a recording id."""
    if model is None or model is _pusher_scene():
        text = _core.PUSHER_SCENE_XML.encode()
        return "pusher_scene:" + hashlib.sha256(text).hexdigest()[:16]
    if isinstance(model, (str, os.PathLike)):
        return "file:" + hashlib.sha256(Path(model).read_bytes()).hexdigest()[:16]
    # A Model built in memory: its sizes are all we can read back.
    return f"model:nq={model.nq},nv={model.nv},nu={model.nu}"


def run_parameters(result: _core.RunResult, model: ModelLike = None) -> dict:
    """The parameters that make a run what it is (what the recording id is made of)."""
    config = result.config
    return {
        "seed": config.seed,
        "steps": result.metrics["steps"],
        "timestep": result.timestep,
        "perturb": config.perturb,
        "rng": config.rng,
        "record_every": config.record_every,
        "audit_energy": config.audit_energy,
        "model": _model_key(model),
    }


def recording_id(result: _core.RunResult, model: ModelLike = None) -> str:
    """The run's recording id: the same for the same run, different otherwise."""
    text = json.dumps(run_parameters(result, model), sort_keys=True)
    return str(uuid.uuid5(RECORDING_NAMESPACE, text))


def recording_name(result: _core.RunResult) -> str:
    """A name for people, shown in the viewer's list of recordings."""
    config = result.config
    shove = (f"shove {result.shove.force_y:+.1f} N ({config.rng}, seed {config.seed})" if config.perturb
             else "no shove")
    return f"{result.metrics['steps']} steps of {result.timestep:g} s, {shove}"


def _rotate_into_body(quat_wxyz, vectors):
    """Rotates world vectors into each body's frame (by the conjugate quaternion)."""
    import numpy as np

    w = quat_wxyz[:, :1]
    u = -quat_wxyz[:, 1:]  # conjugate: the inverse rotation for a unit quaternion
    t = 2.0 * np.cross(u, vectors)
    return vectors + w * t + np.cross(u, t)


def frames(result: _core.RunResult, model: ModelLike = None) -> dict:
    """What record() logs, as arrays: one row per trajectory row.

    Keys: step, sim_time, box_translation, box_quaternion_xyzw,
    pusher_translation, shove_vector (box frame, scaled), shove_world (scaled),
    and `series`, {plots path: values} for the scalar series.
    """
    import numpy as np

    cols = result.columns
    box = np.column_stack([cols["box_x"], cols["box_y"], cols["box_z"]])
    quat_wxyz = np.column_stack([cols[c] for c in ("box_qw", "box_qx", "box_qy", "box_qz")])
    rest, axis, q0 = _core.pusher_track(load_model(model))
    pusher = rest + np.outer(cols["pusher_x"] - q0, axis)
    # The final row has no step after it, so no shove (its input cells are NaN).
    shove_world = SHOVE_ARROW_SCALE * np.nan_to_num(np.column_stack([cols["shove_x"], cols["shove_y"],
                                                                     cols["shove_z"]]))
    series = {
        "box/x": cols["box_x"],
        "box/y": cols["box_y"],
        "box/z": cols["box_z"],
        "box/speed": np.sqrt(cols["box_vx"] ** 2 + cols["box_vy"] ** 2 + cols["box_vz"] ** 2),
        "pusher/x": cols["pusher_x"],
        "contacts": cols["ncon"],
    }
    for name in ENERGY_COLORS:
        if name in cols:
            series["energy/" + name] = cols[name]
    return {
        "step": cols["step"].astype(np.int64),
        "sim_time": cols["time"],
        "box_translation": box,
        # MuJoCo stores quaternions w-x-y-z; rerun wants x-y-z-w.
        "box_quaternion_xyzw": quat_wxyz[:, [1, 2, 3, 0]],
        "pusher_translation": pusher,
        "shove_world": shove_world,
        "shove_vector": _rotate_into_body(quat_wxyz, shove_world),
        "series": series,
    }


def floor_slab(data: dict) -> tuple:
    """(centre, half sizes) of a slab whose top is z = 0, under everything the run did."""
    import numpy as np

    xy = np.vstack([data["box_translation"][:, :2], data["pusher_translation"][:, :2]])
    xy = xy[np.all(np.isfinite(xy), axis=1)]
    lo = np.minimum(xy.min(axis=0) - 0.5, -FLOOR_HALF_SIZE) if len(xy) else np.full(2, -FLOOR_HALF_SIZE)
    hi = np.maximum(xy.max(axis=0) + 0.5, FLOOR_HALF_SIZE) if len(xy) else np.full(2, FLOOR_HALF_SIZE)
    centre = [(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, -FLOOR_THICKNESS / 2]
    half = [(hi[0] - lo[0]) / 2, (hi[1] - lo[1]) / 2, FLOOR_THICKNESS / 2]
    return centre, half


def blueprint(energy: bool, z_range: tuple):
    """The 3D view on the left; the time series stacked on the right."""
    import rerun.blueprint as rrb

    def series_view(name, contents, axis_range=None):
        axis = rrb.ScalarAxis(range=axis_range) if axis_range else None
        return rrb.TimeSeriesView(name=name, origin="/plots", contents=contents, axis_y=axis,
                                  plot_legend=rrb.PlotLegend(visible=True))

    plots = [
        series_view("box z (m): height of its centre", ["/plots/box/z"], z_range),
        series_view("box y (m): sideways", ["/plots/box/y"]),
        series_view("x (m): the pusher and the box", ["/plots/box/x", "/plots/pusher/x"]),
        series_view("box speed (m/s)", ["/plots/box/speed"]),
        series_view("contacts", ["/plots/contacts"]),
    ]
    if energy:
        plots.append(series_view("energy audit (J)", ["/plots/energy/**"]))
    scene = rrb.Spatial3DView(name="the scene", origin="/world")
    return rrb.Blueprint(rrb.Horizontal(scene, rrb.Vertical(*plots), column_shares=[3, 2]),
                         collapse_panels=False)


def z_axis_range(z) -> tuple:
    """The box z plot's range: a fixed 0.04 to 0.12 m, so a sound run looks flat
    beside Break It, widened only if the box leaves it."""
    import numpy as np

    finite = z[np.isfinite(z)]
    low = min(0.04, float(finite.min()) - 0.005) if finite.size else 0.04
    high = max(0.12, float(finite.max()) + 0.005) if finite.size else 0.12
    return (low, high)


@contextlib.contextmanager
def replacing(target: Path) -> Iterator[str]:
    """A temporary file's name beside `target`, renamed onto it when the block
    succeeds and removed when it fails: a failure leaves any earlier file as it was."""
    fd, temp_name = tempfile.mkstemp(prefix="." + target.name + ".", suffix=".tmp", dir=target.parent)
    os.close(fd)
    try:
        yield temp_name
        os.chmod(temp_name, 0o644)
        os.replace(temp_name, target)
    except BaseException:
        Path(temp_name).unlink(missing_ok=True)
        raise


def record(result: _core.RunResult, path: Union[str, "os.PathLike[str]"], model: ModelLike = None) -> Path:
    """Writes the run to `path` as an .rrd recording and returns the path.

    The file is written beside its destination and renamed into place, so a
    failure leaves any earlier recording as it was. `model` is the one the
    run used (None: the chapter's scene; a path identifies a file's model in
    the recording id better than a Model object can); it places the pusher.
    """
    import numpy as np
    import rerun as rr

    target = Path(path)
    data = frames(result, model)
    energy = result.config.audit_energy
    with replacing(target) as temp_name:
        rec = rr.RecordingStream(APPLICATION_ID, recording_id=recording_id(result, model), send_properties=False)
        rec.save(temp_name, default_blueprint=blueprint(energy, z_axis_range(data["series"]["box/z"])))
        rec.send_recording_name(recording_name(result))
        # Shapes, colours and series styles never change: static, logged once.
        centre, half = floor_slab(data)
        rec.log("world/floor", rr.Boxes3D(centers=[centre], half_sizes=[half], colors=[FLOOR_COLOR],
                                          fill_mode="solid"), static=True)
        rec.log("world/objects/box", rr.Boxes3D(half_sizes=[BOX_HALF_SIZES], colors=[BOX_COLOR]), static=True)
        rec.log("world/robot/pusher", rr.Boxes3D(half_sizes=[PUSHER_HALF_SIZES], colors=[PUSHER_COLOR]),
                static=True)
        for name in data["series"]:
            label, color = series_style(name)
            rec.log("plots/" + name, rr.SeriesLines(names=[label], colors=[color]), static=True)
        times = [rr.TimeColumn("sim_time", duration=data["sim_time"]), rr.TimeColumn("step", sequence=data["step"])]
        rec.send_columns("world/objects/box", indexes=times,
                         columns=rr.Transform3D.columns(translation=data["box_translation"],
                                                        quaternion=data["box_quaternion_xyzw"]))
        rec.send_columns("world/robot/pusher", indexes=times,
                         columns=rr.Transform3D.columns(translation=data["pusher_translation"]))
        rec.send_columns("world/objects/box/shove", indexes=times,
                         columns=rr.Arrows3D.columns(origins=np.zeros_like(data["shove_vector"]),
                                                     vectors=data["shove_vector"]))
        for name, values in data["series"].items():
            rec.send_columns("plots/" + name, indexes=times, columns=rr.Scalars.columns(scalars=values))
        rec.flush()
        rec.disconnect()
    return target
