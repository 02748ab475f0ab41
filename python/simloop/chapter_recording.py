"""The chapter's run as a rerun recording: the one recorder (recording.py) with
what the chapter says to look for added on top.

ChapterRecording is the chapter's run on the same recorder,
its scene drawn like any other. What it adds:
- the chapter's entity paths, "the same entity paths every chapter uses":
  world/objects/box and world/robot/pusher (a --model scene's pusher under
  its own name: world/robot/<body>), each with its geoms below it
  (world/objects/box/box_geom); the floor at world/static/floor.
- the poses, from the chapter's trajectory: the box's from box_x..box_qz
  (qpos, the state entering each step; the chapter logs mjData.xpos, which
  mj_step computed before integrating, so it lags qpos by one step); the
  pusher's (whichever body actuator 0 drives) its home pose moved by pusher_x
  along its slide axis. Only these two bodies are drawn: a --model scene's
  other moving bodies are not in the trajectory.
- world/objects/box/shove: an Arrows3D (amber, 8 mm thick), the shove scaled
  by 0.02 while it acts and zero-length otherwise. A child of the box, so drawn in the box's frame:
  logged from SHOVE_ARROW_HEIGHT above the box's centre (3 cm above its top
  face, where the camera, above and in front, sees the whole arrow for either
  sign: from the centre a +y arrow went away behind the box and the pusher,
  and half of a -y one was inside the box), with the world-frame shove and
  offset rotated into that frame (the chapter passes world coordinates there,
  which would put the arrow at twice the box's position).
- its series: plots/box_x, box_y, box_z, pusher_x, ncon, plots/box_speed, and
  with the energy audit plots/<column> for each of its columns, in joules
  (not every column: that would more than double the file).
- the 3D view's camera following the box: it tracks
  world/objects/box/camera_frame, an invisible box around it (rerun frames a
  tracked entity by its bounds).
- its panels, stacked beside the 3D view: box z first, on a fixed 0.04 to
  0.12 m axis widened only if the box leaves it (the chapter's diagnosis for
  Break It), box y, the pusher's and the box's x, the box's speed, the
  contacts, and the energy audit; their time axes from 0 to the run's end,
  an axis at least MIN_AXIS_SPAN wide, a legend (top left) only where a
  panel holds more than one series.

The recording id is derived from what decides the run: seed, steps,
timestep, shove, generator, record_every, energy audit, the model and the
MuJoCo it steps on (recording.mujoco_build).
"""

from __future__ import annotations

import hashlib
import json
import os
import uuid
from pathlib import Path
from typing import Any, Dict, Mapping, Optional, Sequence, Tuple, Union

from . import _core
from ._checks import ModelLike, _pusher_scene, load_model
from .recording import Recording, _eye, _layout, _rotate_into_body, mujoco_build

# rerun accepts these application ids as they are (no "/" or ".").
APPLICATION_ID = "simloop_ch0_1_sim_loop"
# Every chapter recording id lives in this namespace (uuid5 of the run's parameters).
RECORDING_NAMESPACE = uuid.UUID("5b1e6c2e-9d7a-4f0e-8a43-0c6f3f1d2a10")
SHOVE_ARROW_SCALE = 0.02
SHOVE_ARROW_HEIGHT = 0.08  # m above the box's centre, in the world's z
# The arrow in a colour of its own (not the box's red), thick enough to see.
SHOVE_ARROW_COLOR = (255, 190, 0)
SHOVE_ARROW_RADIUS = 0.008  # m
CAMERA_FRAME = 0.6  # m, the half size of the region around the box the camera keeps in view
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
        "mujoco": mujoco_build(),
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
    shove = f"shove {result.shove.force_y:+.1f} N ({config.rng}, seed {config.seed})" if config.perturb else "no shove"
    return f"{result.metrics['steps']} steps of {result.timestep:g} s, {shove}"


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
    module's docstring), fed by the command's run as it steps and put in
    place with its outputs. `model_key` identifies the model in the
    recording id (None: the chapter's scene; a path: that file, by its
    bytes); `model` is the scene itself."""

    def __init__(self, config: _core.RunConfig, model_key: ModelLike, model: _core.Model, target: Path) -> None:
        self._expected = list(_core.COLUMN_NAMES) + (list(_core.ENERGY_COLUMN_NAMES) if config.audit_energy else [])
        self._energy = config.audit_energy
        self._track = _core.pusher_track(model)
        self._pusher, self._pusher_quat = _pusher_body(model)
        self._ranges: Dict[str, Tuple[float, float]] = {}  # each plotted series' (low, high), for the axes
        self._time_end = 0.0  # the last row's sim time: the plots' time axes run from 0 to it
        super().__init__(
            model, target, config_recording_id(config, model_key), APPLICATION_ID, bodies=["box", self._pusher]
        )
        try:
            self._rec.log(
                f"{self._entity('box')}/shove",
                self._rr.Arrows3D.from_fields(colors=[SHOVE_ARROW_COLOR], radii=[SHOVE_ARROW_RADIUS]),
                static=True,
            )
            # What the camera follows: rerun frames a tracked entity by its
            # bounds, and the box alone (10 cm) would fill the view; this
            # invisible frame around it keeps the pusher and the floor in view.
            self._rec.log(
                f"{self._entity('box')}/camera_frame",
                self._rr.Boxes3D(
                    half_sizes=[[CAMERA_FRAME, CAMERA_FRAME, CAMERA_FRAME / 2]],
                    colors=[[0, 0, 0, 0]],
                    fill_mode="majorwireframe",
                    radii=[0.0],
                ),
                static=True,
            )
        except BaseException:
            self.close()
            raise

    def columns(self, names: Sequence[str]) -> None:
        if list(names) != self._expected:  # the run and the recording disagree on what a row holds
            raise ValueError(
                f"the chapter's recording draws the columns {self._expected}, the run records {list(names)}"
            )
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

    def _entity(self, body: str) -> str:
        """The chapter's paths: the pusher under world/robot, the box under world/objects."""
        return f"world/robot/{body}" if body == self._pusher else f"world/objects/{body}"

    def _style(self, name: str) -> Tuple[str, Optional[Sequence[int]]]:
        if name in ENERGY_COLORS:
            return name + " (J)", ENERGY_COLORS[name]
        # box_* in the box's colour, pusher_* in the pusher's.
        colour = {"box": self.colours.get("box"), "pusher": self.colours.get(self._pusher), "ncon": CONTACTS_COLOR}.get(
            name.split("_")[0]
        )
        return CHAPTER_LABELS.get(name, name), colour

    def _send_more(self, times: list, cols: Mapping[str, Any]) -> None:
        import numpy as np

        speed = np.sqrt(cols["box_vx"] ** 2 + cols["box_vy"] ** 2 + cols["box_vz"] ** 2)
        self._send_series("box_speed", times, speed)
        # The final row has no step after it, so no shove (its input cells are NaN).
        shove = SHOVE_ARROW_SCALE * np.nan_to_num(np.column_stack([cols["shove_x"], cols["shove_y"], cols["shove_z"]]))
        quat = _box_quat(cols)
        above = np.tile([0.0, 0.0, SHOVE_ARROW_HEIGHT], (len(shove), 1))
        self._rec.send_columns(
            f"{self._entity('box')}/shove",
            indexes=times,
            columns=self._rr.Arrows3D.columns(
                origins=_rotate_into_body(quat, above), vectors=_rotate_into_body(quat, shove)
            ),
        )
        for name, values in [("box_speed", speed), *((c, cols[c]) for c in PLOTTED)]:
            finite = values[np.isfinite(values)]
            if finite.size:
                low, high = float(finite.min()), float(finite.max())
                seen = self._ranges.get(name)
                self._ranges[name] = (low, high) if seen is None else (min(seen[0], low), max(seen[1], high))
        self._time_end = max(self._time_end, float(np.nanmax(cols["time"])))

    def _blueprint(self) -> Any:
        """The chapter's panels, stacked: box z first (its diagnosis for Break It)."""
        import rerun.blueprint as rrb

        # Time from 0 to the run's end (rerun opened Break It's on empty negative time); a legend only where a
        # panel has more than one series (its name says the rest), at the top left, where a run's x and energy
        # are not yet (at the bottom right it covered the z panel's 0.05 m rest line).
        time_axis = rrb.TimeAxis(
            view_range=rrb.TimeRange(
                start=rrb.TimeRangeBoundary.absolute(seconds=0.0),
                end=rrb.TimeRangeBoundary.absolute(seconds=self._time_end),
            )
        )

        def panel(name, columns, axis_range=None):
            axis_range = axis_range or value_axis_range([self._ranges[c] for c in columns if c in self._ranges])
            return rrb.TimeSeriesView(
                name=name,
                origin="/plots",
                contents=["/plots/" + c for c in columns],
                axis_x=time_axis,
                axis_y=rrb.ScalarAxis(range=axis_range) if axis_range else None,
                plot_legend=rrb.PlotLegend(corner=rrb.Corner2D.LeftTop, visible=len(columns) > 1),
            )

        plots = [
            panel("box z (m): height of its centre", ["box_z"], z_axis_range(self._ranges.get("box_z"))),
            panel("box y (m): sideways", ["box_y"]),
            panel("x (m): the pusher and the box", ["box_x", "pusher_x"]),
            panel("box speed (m/s)", ["box_speed"]),
            panel("contacts", ["ncon"]),
        ]
        if self._energy:
            plots.append(panel("energy audit (J)", list(_core.ENERGY_COLUMN_NAMES)))
        # The camera follows the box (its invisible frame: rerun frames what
        # it tracks by its bounds); in Break It the pusher runs 211 m away.
        eye = _eye(self._low, self._high, tracking=f"{self._entity('box')}/camera_frame")
        return _layout(rrb.Vertical(*plots), eye)

    def _name(self, result: Any) -> str:
        return recording_name(result)


def _box_quat(cols: Mapping[str, Any]) -> Any:
    import numpy as np

    return np.column_stack([cols["box_qw"], cols["box_qx"], cols["box_qy"], cols["box_qz"]])


# The series whose ranges set their panels' axes (box_speed is computed, not a column).
PLOTTED = ("box_z", "box_y", "box_x", "pusher_x", "ncon")
# The narrowest a value axis shows: below it rerun labelled a still box's y
# (1e-15 m of rounding on MuJoCo 4) "-0.000 000 000 000 002".
MIN_AXIS_SPAN = 0.01


def value_axis_range(ranges: Sequence[Tuple[float, float]]) -> Optional[Tuple[float, float]]:
    """None (rerun fits the data) unless the series together span less than MIN_AXIS_SPAN: then that span,
    centred on them."""
    if not ranges:
        return None
    low, high = min(r[0] for r in ranges), max(r[1] for r in ranges)
    if high - low >= MIN_AXIS_SPAN:
        return None
    middle = (low + high) / 2
    return (middle - MIN_AXIS_SPAN / 2, middle + MIN_AXIS_SPAN / 2)


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
