"""A run as a rerun recording (.rrd): one recorder for any scene, drawn from
its own geometry; the chapter's run is one scene on it, with what the chapter
says to look for added on top.

Layout (rerun-sdk 0.41), every recorded row (every step by default, the final
state included) on two timelines, `sim_time` (seconds, as a duration; the
viewer opens on it) and `step` (a sequence):

- world/static/<geom>: the world body's geoms, where they are. A plane
  (infinite for MuJoCo's collisions) is a thin slab whose top is the plane,
  of its own size (1 m where that is 0) widened to reach 0.5 m beyond
  everywhere the bodies went, so it is logged at the end of the run.
- world/bodies/<body>: a Transform3D per row for every body that moves; its
  geoms below it, world/bodies/<body>/<geom>, static, with their shape,
  colour and place on the body: boxes, spheres and ellipsoids, capsules,
  cylinders; meshes as their bounding boxes.
- plots/<column>: trajectory columns as scalars (float64: the values
  exactly); a scenario's every column but step and time.

Recording is the recorder, as a scenario's run uses it: the command runs the
scenario once with run_scenario_to_files(..., drawing=Recording(...)), which
writes trajectory.csv as it steps (its columns are the scenario's, recording
or not) and hands the recording each block of rows followed by every moving
body's pose (its frame in the world, read where the recorded bodies' poses
are). The default blueprint opens the 3D view beside one plot of every series.

ChapterRecording is the chapter's run (run_to_files) on the same recorder,
its scene drawn like any other (the chapter's: world/static/floor,
world/bodies/box/box_geom, world/bodies/pusher/pusher_geom). What it adds:
- the poses, from the chapter's trajectory: the box's from box_x..box_qz
  (qpos, the state entering each step; the chapter logs mjData.xpos, which
  mj_step computed before integrating, so it lags qpos by one step); the
  pusher's (whichever body actuator 0 drives) its home pose moved by pusher_x
  along its slide axis. Only these two bodies are drawn: a --model scene's
  other moving bodies are not in the trajectory.
- world/bodies/box/shove: an Arrows3D, the shove scaled by 0.02 while it acts
  and zero-length otherwise. A child of the box, so drawn in the box's frame:
  logged from the box's origin, with the world-frame shove rotated into that
  frame (the chapter passes world coordinates there, which would put the
  arrow at twice the box's position).
- its series: plots/box_x, box_y, box_z, pusher_x, ncon, plots/box_speed, and
  with the energy audit plots/<column> for each of its columns, in joules
  (not every column: that would more than double the file).
- its panels, stacked beside the 3D view: box z first, on a fixed 0.04 to
  0.12 m axis widened only if the box leaves it (the chapter's diagnosis for
  Break It), box y, the pusher's and the box's x, the box's speed, the
  contacts, and the energy audit.

The recording id is derived from what decides the run (the chapter's: seed,
steps, timestep, shove, generator, record_every, energy audit and the model;
a scenario's: the command line and the bytes of its scenario and scene
files), so the same run always gets the same id and two different runs open
as two recordings instead of merging into one. rerun does not let us make
the bytes repeat: it stamps every chunk and row with a time-based id and
gives the embedded blueprint a random store id, so two identical runs give
two files with the same data (`rerun rrd compare --unordered a.rrd b.rrd`
says so: rerun may batch the same rows into chunks differently) but
different bytes.

Rows come in blocks and are sent as columns (rerun's send_columns, one call
per entity) every BLOCK_ROWS rows, each block written before the next is
gathered, so memory stays bounded however long the run; the planes, the z
axis's range and the recording's name, which need the whole run, are logged
at its end. rerun is imported only here, only when recording; its file sink
writes into a pipe whose bytes simloop writes to the file and checks
(RrdFile), so no viewer is spawned, no connection is made, and a full disk is
an error, not a hang or a truncated file.
"""

from __future__ import annotations

import hashlib
import json
import os
import uuid
from pathlib import Path
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

from . import _core
from ._checks import ModelLike, _pusher_scene, load_model

# rerun accepts these application ids as they are (no "/" or ".").
APPLICATION_ID = "simloop_ch0_1_sim_loop"
SCENARIO_APPLICATION_ID = "simloop_scenario"
# Every chapter recording id lives in this namespace (uuid5 of the run's parameters).
RECORDING_NAMESPACE = uuid.UUID("5b1e6c2e-9d7a-4f0e-8a43-0c6f3f1d2a10")
# Rows gathered before they go to the file as columns: a few hundred kB of
# numbers for a scene of tens of columns.
BLOCK_ROWS = 4096
POSE = ("_x", "_y", "_z", "_qw", "_qx", "_qy", "_qz")  # after a scenario's columns, per moving body
PLANE_THICKNESS = 0.01
PLANE_MARGIN = 0.5  # how far a plane reaches beyond where the bodies went
SHOVE_ARROW_SCALE = 0.02
# The chapter's series' labels (the others are labelled by their column).
CHAPTER_LABELS = {
    "box_x": "box x (m)",
    "box_y": "box y (m), sideways",
    "box_z": "box z (m), height of its centre",
    "box_speed": "box speed (m/s)",
    "pusher_x": "pusher x (m)",
    "ncon": "contacts",
}
CONTACTS_COLOR = (90, 90, 90)
ENERGY_COLORS = {
    "energy": (0, 0, 0),
    "work_actuator": (64, 115, 217),
    "work_shove": (217, 76, 64),
    "work_passive": (120, 120, 120),
    "work_constraint": (181, 101, 29),
    "work_constraint_positive": (230, 160, 40),
    "energy_unexplained": (150, 60, 180),
}


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


def scenario_recording_id(run_key: str) -> str:
    """A scenario run's recording id, from what decides the run (the command's _run_key)."""
    return str(uuid.uuid5(uuid.NAMESPACE_URL, "simloop-scenario:" + run_key))


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
    world box [low, high] where the bodies went (None: nowhere finite)."""
    import numpy as np

    hi = np.asarray(geom["half_size"][:2], dtype=float)
    lo = -hi
    if low is not None:
        corners = np.array([[x, y, z] for x in (low[0], high[0]) for y in (low[1], high[1]) for z in (low[2], high[2])])
        local = _rotate_into_body(np.tile(geom["quat"], (len(corners), 1)), corners - geom["pos"])[:, :2]
        lo = np.minimum(lo, local.min(axis=0) - PLANE_MARGIN)
        hi = np.maximum(hi, local.max(axis=0) + PLANE_MARGIN)
    return [*((lo + hi) / 2), -PLANE_THICKNESS / 2], [*((hi - lo) / 2), PLANE_THICKNESS / 2]


def _layout(plots: Any) -> Any:
    """The blueprint: the 3D view on the left, `plots` on the right, on the sim_time timeline."""
    import rerun.blueprint as rrb

    return rrb.Blueprint(rrb.Horizontal(rrb.Spatial3DView(name="the scene", origin="/world"), plots,
                                        column_shares=[3, 2]),
                         rrb.TimePanel(timeline="sim_time"), collapse_panels=False)


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

    def __init__(self, rr: Any, application_id: str, recording_id: str, target: Path) -> None:
        self.target = Path(target)
        self.piped: Any = _core.PipedFile(self.target)
        self.rec: Any = None
        try:
            self.rec = rr.RecordingStream(application_id, recording_id=recording_id, send_properties=False)
            self.rec.save(self.piped.writer_path)
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


class Recording:
    """The .rrd of one run of `model`'s scene, written as the run goes: pass it
    as run_scenario_to_files's `drawing` and `recording.files` as its `also`;
    the run calls columns(names) once, rows(block) per block of rows and
    finish(result) once it is done, before it puts the outputs in place, all
    together. close() abandons the file if it was not finished. `path` is
    where the recording goes; it is written beside it and checked first
    (RrdFile). `bodies`: the moving bodies the rows pose (None: all of them,
    as run_scenario_to_files gives them).

    The hooks below (_poses, _style, _send_more, _blueprint, _name) are where
    a kind of run says what its rows hold; ChapterRecording is the one other."""

    def __init__(self, model: _core.Model, path: Union[str, "os.PathLike[str]"], recording_id: str,
                 application_id: str = SCENARIO_APPLICATION_ID, bodies: Optional[Sequence[str]] = None) -> None:
        import rerun as rr

        self._rr = rr
        self.moving_bodies: List[str] = list(_core.moving_bodies(model))
        self._names: List[str] = []  # the trajectory's columns
        self._series: List[str] = []  # those plotted
        self._pending: list = []
        self._pending_rows = 0
        self._planes: list = []  # the world's planes: drawn at the end, under everywhere the bodies went
        self._low: Any = None  # the smallest and largest finite x, y, z of a body so far
        self._high: Any = None
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
                    entity = f"world/bodies/{geom['body']}/{geom['name']}"
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
        """The trajectory's columns, then x y z qw qx qy qz per moving body."""
        self._names = list(names[:len(names) - len(POSE) * len(self.moving_bodies)])
        self._plot([name for name in self._names if name not in ("step", "time")])

    def rows(self, block: Any) -> None:
        self._pending.append(block)
        self._pending_rows += len(block)
        if self._pending_rows >= BLOCK_ROWS:
            self._send()

    def finish(self, result: Any) -> None:
        """Sends what is left, the world's planes, the blueprint and the
        recording's name (which need the whole run), and checks the file."""
        self._send()
        rr = self._rr
        for plane in self._planes:
            centre, half = _plane_slab(plane, self._low, self._high)
            entity = f"world/static/{plane['name']}"
            self._rec.log(entity, _pose(rr, plane), static=True)
            self._rec.log(entity, rr.Boxes3D(centers=[centre], half_sizes=[half], colors=[_rgba(plane["rgba"])],
                                             fill_mode="solid"), static=True)
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
        self._rec.log(f"plots/{name}", self._rr.SeriesLines(names=[label], colors=None if colour is None else [colour]),
                      static=True)

    def _send(self) -> None:
        import numpy as np

        if not self._pending:
            return
        rr = self._rr
        block = np.concatenate(self._pending)
        self._pending, self._pending_rows = [], 0
        cols = {name: block[:, c] for c, name in enumerate(self._names)}
        times = [rr.TimeColumn("sim_time", duration=cols["time"]),
                 rr.TimeColumn("step", sequence=cols["step"].astype(np.int64))]
        for body, (position, quat_wxyz) in self._poses(block, cols).items():
            finite = position[np.all(np.isfinite(position), axis=1)]
            if len(finite):
                low, high = finite.min(axis=0), finite.max(axis=0)
                self._low = low if self._low is None else np.minimum(self._low, low)
                self._high = high if self._high is None else np.maximum(self._high, high)
            self._rec.send_columns(f"world/bodies/{body}", indexes=times,  # rerun's quaternions are x y z w
                                   columns=rr.Transform3D.columns(translation=np.ascontiguousarray(position),
                                                                  quaternion=quat_wxyz[:, [1, 2, 3, 0]]))
        for name in self._series:
            self._send_series(name, times, cols[name])
        self._send_more(times, cols)
        # rerun writes the file on a thread of its own and queues what it has
        # not written yet: waiting for it here keeps that queue to one block
        # (10^6 rows of 35 columns sent as fast as they came: 280 MiB more without).
        self.file.flush()

    def _send_series(self, name: str, times: list, values: Any) -> None:
        import numpy as np

        self._rec.send_columns(f"plots/{name}", indexes=times,
                               columns=self._rr.Scalars.columns(scalars=np.ascontiguousarray(values)))

    # What a kind of run says about its rows; these are a scenario's.
    def _poses(self, block: Any, cols: Mapping[str, Any]) -> Dict[str, Tuple[Any, Any]]:
        """{body: (positions, w x y z quaternions)}, a row each: here the poses after the trajectory's columns."""
        at = len(self._names)
        return {body: (block[:, at + 7 * i:at + 7 * i + 3], block[:, at + 7 * i + 3:at + 7 * (i + 1)])
                for i, body in enumerate(self.moving_bodies)}

    def _style(self, name: str) -> Tuple[str, Optional[Sequence[int]]]:
        """(label, colour) of the series plots/<name>; a colour of None is rerun's choice."""
        return name, None

    def _send_more(self, times: list, cols: Mapping[str, Any]) -> None:
        """Whatever else a block of rows shows (the chapter's shove)."""

    def _blueprint(self) -> Any:
        import rerun.blueprint as rrb

        return _layout(rrb.TimeSeriesView(name="what was recorded", origin="/plots"))

    def _name(self, result: Any) -> str:
        """A name for people, shown in the viewer's list of recordings."""
        return f"{result.name or 'scenario'}: {result.steps} steps of {result.timestep:g} s, seed {result.seed}"


def _pusher_body(model: _core.Model) -> Tuple[str, Any]:
    """The name of the body actuator 0 drives (the chapter's pusher, whatever a
    --model scene calls it: Model checked that it drives a slide or hinge
    joint) and that body's orientation at rest (w x y z)."""
    joint = model.object_info("actuator", 0)["joint"]
    body = model.object_info("joint", joint)["body"]
    rest = _core.Sim(model).array("xquat")[body].copy()  # a new Sim is at rest (qpos0), as pusher_track reads it
    return model.names("body")[body] or f"body{body}", rest


class ChapterRecording(Recording):
    """The chapter's .rrd of one run: the chapter's scene (or a --model scene
    of its layout) on the one recorder, with the chapter's add-ons (see the
    module's docstring). Pass it as run_to_files's `drawing` and
    `recording.files` as its `also`. `model_key` identifies the model in the
    recording id (None: the chapter's scene; a path: that file, by its
    bytes); `model` is the scene itself."""

    def __init__(self, config: _core.RunConfig, model_key: ModelLike, model: _core.Model, target: Path) -> None:
        self._expected = list(_core.COLUMN_NAMES) + (list(_core.ENERGY_COLUMN_NAMES) if config.audit_energy else [])
        self._energy = config.audit_energy
        self._track = _core.pusher_track(model)
        self._pusher, self._pusher_quat = _pusher_body(model)
        self._z_range: Optional[Tuple[float, float]] = None  # the box z's, for its plot's axis
        super().__init__(model, target, config_recording_id(config, model_key), APPLICATION_ID,
                         bodies=["box", self._pusher])

    def columns(self, names: Sequence[str]) -> None:
        if list(names) != self._expected:  # the run and the recording disagree on what a row holds
            raise ValueError(f"the chapter's recording draws the columns {self._expected}, the run records {list(names)}")
        self._names = list(names)
        # The chapter's series only (every column would more than double the file).
        self._plot([name for name in names if name in CHAPTER_LABELS or name in ENERGY_COLORS])
        self._log_style("box_speed")

    def _poses(self, block: Any, cols: Mapping[str, Any]) -> Dict[str, Tuple[Any, Any]]:
        import numpy as np

        rest, axis, q0 = self._track
        box = np.column_stack([cols["box_x"], cols["box_y"], cols["box_z"]]), _box_quat(cols)
        pusher = rest + np.outer(cols["pusher_x"] - q0, axis), np.tile(self._pusher_quat, (len(block), 1))
        return {"box": box, self._pusher: pusher}

    def _style(self, name: str) -> Tuple[str, Optional[Sequence[int]]]:
        if name in ENERGY_COLORS:
            return name + " (J)", ENERGY_COLORS[name]
        # box_* in the box's colour, pusher_* in the pusher's.
        colour = {"box": self.colours.get("box"), "pusher": self.colours.get(self._pusher),
                  "ncon": CONTACTS_COLOR}.get(name.split("_")[0])
        return CHAPTER_LABELS.get(name, name), colour

    def _send_more(self, times: list, cols: Mapping[str, Any]) -> None:
        import numpy as np

        self._send_series("box_speed", times, np.sqrt(cols["box_vx"] ** 2 + cols["box_vy"] ** 2 + cols["box_vz"] ** 2))
        # The final row has no step after it, so no shove (its input cells are NaN).
        shove = SHOVE_ARROW_SCALE * np.nan_to_num(np.column_stack([cols["shove_x"], cols["shove_y"], cols["shove_z"]]))
        self._rec.send_columns("world/bodies/box/shove", indexes=times,
                               columns=self._rr.Arrows3D.columns(origins=np.zeros_like(shove),
                                                                 vectors=_rotate_into_body(_box_quat(cols), shove)))
        z = cols["box_z"][np.isfinite(cols["box_z"])]
        if z.size:
            low, high = float(z.min()), float(z.max())
            self._z_range = (low, high) if self._z_range is None else (min(self._z_range[0], low),
                                                                       max(self._z_range[1], high))

    def _blueprint(self) -> Any:
        """The chapter's panels, stacked: box z first (its diagnosis for Break It)."""
        import rerun.blueprint as rrb

        def panel(name, columns, axis_range=None):
            axis = rrb.ScalarAxis(range=axis_range) if axis_range else None
            return rrb.TimeSeriesView(name=name, origin="/plots", contents=["/plots/" + c for c in columns],
                                      axis_y=axis, plot_legend=rrb.PlotLegend(visible=True))

        plots = [
            panel("box z (m): height of its centre", ["box_z"], z_axis_range(self._z_range)),
            panel("box y (m): sideways", ["box_y"]),
            panel("x (m): the pusher and the box", ["box_x", "pusher_x"]),
            panel("box speed (m/s)", ["box_speed"]),
            panel("contacts", ["ncon"]),
        ]
        if self._energy:
            plots.append(panel("energy audit (J)", list(_core.ENERGY_COLUMN_NAMES)))
        return _layout(rrb.Vertical(*plots))

    def _name(self, result: Any) -> str:
        return recording_name(result)


def _box_quat(cols: Mapping[str, Any]) -> Any:
    import numpy as np

    return np.column_stack([cols["box_qw"], cols["box_qx"], cols["box_qy"], cols["box_qz"]])


def z_axis_range(z_range: Optional[Tuple[float, float]]) -> Tuple[float, float]:
    """The box z plot's range: a fixed 0.04 to 0.12 m, so a sound run looks flat
    beside Break It, widened only if the box leaves it."""
    if z_range is None:
        return (0.04, 0.12)
    return (min(0.04, z_range[0] - 0.005), max(0.12, z_range[1] + 0.005))


def record(result: _core.RunResult, path: Union[str, "os.PathLike[str]"], model: ModelLike = None) -> Path:
    """Writes an in-memory run of the chapter to `path` as an .rrd recording and returns the path.

    The file is written beside its destination and renamed into place, so a
    failure leaves any earlier recording as it was. `model` is the one the
    run used (None: the chapter's scene; a path identifies a file's model in
    the recording id better than a Model object can); its geometry is drawn.
    """
    target = Path(path)
    recording = ChapterRecording(result.config, model, load_model(model), target)
    try:
        recording.columns(result.column_names)
        recording.rows(result.trajectory)
        recording.finish(result)
        _core.commit_files(recording.files)
    finally:
        recording.close()
    return target
