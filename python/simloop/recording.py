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
with the same data (`rerun rrd compare --unordered a.rrd b.rrd` says so: rerun may
batch the same rows into chunks differently) but different
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
is what makes every step cheap. The command records as the run goes
(ChapterRecording, run_to_files's drawing): rows come in blocks, each sent
and written before the next, so memory does not grow with the run; the
floor, the z axis's range and the recording's name, which need the whole
run, are logged at its end. rerun is imported only here, only when
recording; its file sink writes into a pipe whose bytes simloop writes to
the file and checks (RrdFile), so no viewer is spawned, no connection is
made, and a full disk is an error, not a hang or a truncated file.
"""

from __future__ import annotations

import hashlib
import json
import os
import uuid
from pathlib import Path
from typing import Any, Mapping, Optional, Sequence, Union

from . import _core
from ._checks import ModelLike, _pusher_scene, load_model

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


def config_parameters(config: _core.RunConfig, model: ModelLike = None) -> dict:
    """The parameters that make a run what it is (what the recording id is
    made of), from the run's config: known before it runs."""
    return {
        "seed": config.seed,
        "steps": _core.SMOKE_STEPS if config.smoke else config.steps,
        "timestep": config.timestep,
        "perturb": config.perturb,
        "rng": config.rng,
        "record_every": config.record_every,
        "audit_energy": config.audit_energy,
        "model": _model_key(model),
    }


def run_parameters(result: _core.RunResult, model: ModelLike = None) -> dict:
    """The parameters that make a run what it is (what the recording id is made of)."""
    return config_parameters(result.config, model)


def recording_id(result: _core.RunResult, model: ModelLike = None) -> str:
    """The run's recording id: the same for the same run, different otherwise."""
    return config_recording_id(result.config, model)


def config_recording_id(config: _core.RunConfig, model: ModelLike = None) -> str:
    """recording_id, from the run's config (before it runs)."""
    text = json.dumps(config_parameters(config, model), sort_keys=True)
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


def frames(cols: Mapping[str, Any], pusher_track: tuple) -> dict:
    """What the recording logs for a block of trajectory rows, as arrays: one
    row per trajectory row. `cols`: {column name: values};
    `pusher_track`: _core.pusher_track(model).

    Keys: step, sim_time, box_translation, box_quaternion_xyzw,
    pusher_translation, shove_vector (box frame, scaled), shove_world (scaled),
    and `series`, {plots path: values} for the scalar series.
    """
    import numpy as np

    box = np.column_stack([cols["box_x"], cols["box_y"], cols["box_z"]])
    quat_wxyz = np.column_stack([cols[c] for c in ("box_qw", "box_qx", "box_qy", "box_qz")])
    rest, axis, q0 = pusher_track
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
        "step": np.asarray(cols["step"]).astype(np.int64),
        "sim_time": cols["time"],
        "box_translation": box,
        # MuJoCo stores quaternions w-x-y-z; rerun wants x-y-z-w.
        "box_quaternion_xyzw": quat_wxyz[:, [1, 2, 3, 0]],
        "pusher_translation": pusher,
        "shove_world": shove_world,
        "shove_vector": _rotate_into_body(quat_wxyz, shove_world),
        "series": series,
    }


class Extents:
    """What the floor and the z axis need to know of a whole run, gathered
    block by block: the smallest and largest finite x, y of the box and the
    pusher, and of the box's z."""

    def __init__(self) -> None:
        self.xy_low: Any = None  # numpy arrays of 2, once a finite point came
        self.xy_high: Any = None
        self.z_low: Optional[float] = None
        self.z_high: Optional[float] = None

    def add(self, data: dict) -> None:
        import numpy as np

        xy = np.vstack([data["box_translation"][:, :2], data["pusher_translation"][:, :2]])
        xy = xy[np.all(np.isfinite(xy), axis=1)]
        if len(xy):
            low, high = xy.min(axis=0), xy.max(axis=0)
            self.xy_low = low if self.xy_low is None else np.minimum(self.xy_low, low)
            self.xy_high = high if self.xy_high is None else np.maximum(self.xy_high, high)
        z = data["series"]["box/z"]
        z = z[np.isfinite(z)]
        if z.size:
            self.z_low = float(z.min()) if self.z_low is None else min(self.z_low, float(z.min()))
            self.z_high = float(z.max()) if self.z_high is None else max(self.z_high, float(z.max()))


def floor_slab(extents: Extents) -> tuple:
    """(centre, half sizes) of a slab whose top is z = 0, under everything the run did."""
    import numpy as np

    if extents.xy_low is None:
        lo, hi = np.full(2, -FLOOR_HALF_SIZE), np.full(2, FLOOR_HALF_SIZE)
    else:
        lo = np.minimum(extents.xy_low - 0.5, -FLOOR_HALF_SIZE)
        hi = np.maximum(extents.xy_high + 0.5, FLOOR_HALF_SIZE)
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


def z_axis_range(extents: Extents) -> tuple:
    """The box z plot's range: a fixed 0.04 to 0.12 m, so a sound run looks flat
    beside Break It, widened only if the box leaves it."""
    if extents.z_low is None or extents.z_high is None:
        return (0.04, 0.12)
    return (min(0.04, extents.z_low - 0.005), max(0.12, extents.z_high + 0.005))


class RrdFile:
    """A RecordingStream whose file simloop writes. rerun's file sink writes
    to a pipe (_core.PipedFile); a thread of simloop's appends every byte,
    each write checked, to a temporary file beside `target`, which is put in
    place together with the run's other outputs (pass `piped` to
    run_to_files's `also`) once finish() has checked it whole. A full disk or
    a file-size limit is an OSError naming the file, and rerun itself never
    sees it (the pipe is drained whatever happens), so nothing hangs in
    rerun and nothing half-written is put in place. Waiting for rerun takes
    at most FINISH_TIMEOUT seconds, and Ctrl-C and SIGTERM act during it."""

    FINISH_TIMEOUT = 60.0

    def __init__(self, rr: Any, application_id: str, recording_id: str, target: Path, blueprint: Any = None) -> None:
        self.target = Path(target)
        self.piped: Any = _core.PipedFile(self.target)
        self.rec: Any = None
        try:
            self.rec = rr.RecordingStream(application_id, recording_id=recording_id, send_properties=False)
            self.rec.save(self.piped.writer_path, default_blueprint=blueprint)
        except BaseException:
            self.close()
            raise
        finally:
            if self.piped is not None:
                self.piped.close_writer()  # rerun holds its own end now

    @property
    def files(self) -> list:
        """What run_to_files's `also` takes: the file, until it is closed."""
        return [] if self.piped is None else [self.piped]

    def flush(self) -> None:
        """Waits for rerun to have written what was sent (keeps its queue short)."""
        try:
            self.rec.flush(timeout_sec=self.FINISH_TIMEOUT)
        except RuntimeError as e:
            raise OSError(f"{self.target}: rerun could not write the recording ({e})") from None

    def finish(self) -> None:
        """Every byte rerun wrote is in the temporary file, checked; OSError if not."""
        self.flush()
        self.rec.disconnect()  # rerun closes its end: the end of the stream
        self.rec = None
        if not self.piped.wait(self.FINISH_TIMEOUT):
            raise OSError(f"{self.target}: rerun did not finish writing the recording within "
                          f"{self.FINISH_TIMEOUT:g} s")
        self.piped.finish()

    def close(self) -> None:
        """Abandons the file if it was not finished: the temporary file goes at
        once, and what rerun still writes is drained and dropped."""
        rec, self.rec = self.rec, None
        self.piped = None
        if rec is not None:
            rec.disconnect()


class ChapterRecording:
    """The chapter's .rrd of one run, written as the run goes: pass it as
    run_to_files's `drawing` and `recording.files` as its `also`; the rows
    come in blocks, are sent as columns every BLOCK_ROWS rows, and each block
    is written before the next is gathered, so memory stays bounded however
    long the run. finish(result) (called by run_to_files once the run is
    done) logs what needs the whole run (the floor under everywhere it went,
    the z axis's range, the recording's name) and checks the file; close()
    abandons it if it was not finished."""

    BLOCK_ROWS = 4096

    def __init__(self, config: _core.RunConfig, model_key: ModelLike, model: _core.Model, target: Path) -> None:
        import rerun as rr

        self._rr = rr
        self._energy = config.audit_energy
        self._names = list(_core.COLUMN_NAMES) + (list(_core.ENERGY_COLUMN_NAMES) if self._energy else [])
        self._track = _core.pusher_track(model)
        self._extents = Extents()
        self._pending: list = []
        self._pending_rows = 0
        self.file = RrdFile(rr, APPLICATION_ID, config_recording_id(config, model_key), target)
        rec = self.file.rec
        try:
            # Shapes, colours and series styles never change: static, logged once.
            rec.log("world/objects/box", rr.Boxes3D(half_sizes=[BOX_HALF_SIZES], colors=[BOX_COLOR]), static=True)
            rec.log("world/robot/pusher", rr.Boxes3D(half_sizes=[PUSHER_HALF_SIZES], colors=[PUSHER_COLOR]),
                    static=True)
            series = list(SERIES) + (["energy/" + name for name in ENERGY_COLORS] if self._energy else [])
            for name in series:
                label, color = series_style(name)
                rec.log("plots/" + name, rr.SeriesLines(names=[label], colors=[color]), static=True)
        except BaseException:
            self.file.close()
            raise

    # run_to_files's drawing: columns(names) once, rows(block) per block,
    # finish(result) at the end.
    def columns(self, names: Sequence[str]) -> None:
        if list(names) != self._names:  # the run and the recording disagree on what a row holds
            raise ValueError(f"the chapter's recording draws the columns {self._names}, the run records {list(names)}")

    def rows(self, block: Any) -> None:
        self._pending.append(block)
        self._pending_rows += len(block)
        if self._pending_rows >= self.BLOCK_ROWS:
            self._send()

    def _send(self) -> None:
        import numpy as np

        if not self._pending:
            return
        rr, rec = self._rr, self.file.rec
        block = np.concatenate(self._pending)
        self._pending, self._pending_rows = [], 0
        data = frames({name: block[:, c] for c, name in enumerate(self._names)}, self._track)
        self._extents.add(data)
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
            rec.send_columns("plots/" + name, indexes=times,
                             columns=rr.Scalars.columns(scalars=np.ascontiguousarray(values)))
        # rerun writes on a thread of its own and queues what it has not
        # written yet: waiting for it here keeps that queue to one block.
        self.file.flush()

    def finish(self, result: _core.RunResult) -> None:
        self._send()
        rr, rec = self._rr, self.file.rec
        centre, half = floor_slab(self._extents)
        rec.log("world/floor", rr.Boxes3D(centers=[centre], half_sizes=[half], colors=[FLOOR_COLOR],
                                          fill_mode="solid"), static=True)
        rec.send_blueprint(blueprint(self._energy, z_axis_range(self._extents)), make_active=False,
                           make_default=True)
        rec.send_recording_name(recording_name(result))
        self.file.finish()

    @property
    def files(self) -> list:
        """run_to_files's `also`: the recording's file."""
        return self.file.files

    def close(self) -> None:
        self.file.close()


def record(result: _core.RunResult, path: Union[str, "os.PathLike[str]"], model: ModelLike = None) -> Path:
    """Writes an in-memory run to `path` as an .rrd recording and returns the path.

    The file is written beside its destination and renamed into place, so a
    failure leaves any earlier recording as it was. `model` is the one the
    run used (None: the chapter's scene; a path identifies a file's model in
    the recording id better than a Model object can); it places the pusher.
    """
    target = Path(path)
    recording = ChapterRecording(result.config, model, load_model(model), target)
    try:
        recording.rows(result.trajectory)
        recording.finish(result)
        _core.commit_files(recording.files)
    finally:
        recording.close()
    return target
