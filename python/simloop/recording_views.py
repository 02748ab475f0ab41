"""What a run's recording shows beyond its scene, as data (a View) that
recording.py's one recorder draws: a scenario's, and the chapter's on top
of it. recording.py's docstring gives the layout they share.

The chapter's view differs from a scenario's in:
- its paths, "the same entity paths every chapter uses": world/objects/box
  and world/robot/<the body actuator 0 drives> (pusher in the chapter's
  scene), their geoms below them; only these two are drawn.
- their poses, from its trajectory: the box's from box_x..box_qz (qpos, the
  state entering each step), the pusher's its home moved by pusher_x along
  its slide.
- its series, labelled and coloured (the box's in the box's colour):
  box_x, box_y, box_z, pusher_x, ncon, box_speed (from box_vx..box_vz), and
  with the energy audit each of its columns in joules (not every column:
  that would more than double the file); its panels stacked beside the 3D
  view, box z first on a fixed axis (the chapter's diagnosis for Break It).
- the shove arrow, world/objects/box/shove (rotated into the box's frame,
  from 8 cm above its centre: where the camera sees either sign whole), and
  the camera following the box's invisible camera_frame.
- its recording id, from what decides its run: seed, steps, timestep,
  shove, generator, record_every, energy audit, the model and the MuJoCo.
"""

from __future__ import annotations

import hashlib
import json
import os
import uuid
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Dict, List, Mapping, Optional, Sequence, Tuple, Union

from . import _core
from ._build import MUJOCO_BUILD
from ._checks import ModelLike, _pusher_scene
from ._rerun_parts import value_axis_range, z_axis_range

# rerun accepts these application ids as they are (no "/" or ".").
SCENARIO_APPLICATION_ID = "simloop_scenario"
APPLICATION_ID = "simloop_ch0_1_sim_loop"  # the chapter's
# Every chapter recording id lives in this namespace (uuid5 of the run's parameters).
RECORDING_NAMESPACE = uuid.UUID("5b1e6c2e-9d7a-4f0e-8a43-0c6f3f1d2a10")
Colour = Union[None, str, Sequence[int]]  # RGB, a drawn body's name (its colour), or None (rerun's choice)
AxisRule = Callable[[Optional[Tuple[float, float]]], Optional[Tuple[float, float]]]


@dataclass
class Arrow:
    """An Arrows3D at <body's path>/<name>, in the body's frame: `scale` times
    the world vector of `columns` (NaN: zero length), from `height` above the
    body's centre in the world's z."""

    body: str
    name: str
    columns: Tuple[str, str, str]
    scale: float
    height: float
    colour: Tuple[int, int, int]
    radius: float


@dataclass
class Panel:
    """A time series panel: its series, its value axis from their (low, high)
    (None: rerun fits the data), its legend shown or not."""

    title: str
    columns: List[str]
    axis: Optional[AxisRule] = None
    legend: bool = True


@dataclass
class View:
    """What a kind of run's recording shows beyond its scene. Left as None,
    each part is a scenario's."""

    recording_id: str
    application_id: str
    name: Callable[[Any], str]  # for people, in the viewer's list of recordings, from the run's result
    # The rows' columns, exactly; None: a scenario's, then each moving body's pose, then qpos.
    columns: Optional[List[str]] = None
    # {body: entity}, the bodies drawn; None: every moving body, at world/bodies/<body>.
    paths: Optional[Dict[str, str]] = None
    # {body: (positions, w x y z quaternions)} from the columns and the rows' count; None: the poses after the columns.
    poses: Optional[Callable[[Mapping[str, Any], int], Dict[str, Tuple[Any, Any]]]] = None
    series: Optional[Dict[str, Tuple[str, Colour]]] = None  # {plotted: (label, colour)}; None: all but step, time
    speeds: Dict[str, Tuple[str, str, str]] = field(default_factory=dict)  # series: the velocity it is the norm of
    arrow: Optional[Arrow] = None
    camera: Optional[Tuple[str, float]] = None  # (body, half size): the camera follows an invisible box around it
    panels: Optional[List[Panel]] = None  # None: by quantity (QUANTITIES), each with its legend
    open_on_run: bool = False  # the panels' time axes from 0 to the run's end, not rerun's choice


def mujoco_build() -> str:
    """The MuJoCo a run steps on, in its recording id: the same run on another
    MuJoCo (2.2.2 and the PyPI build's 4.0.0) moves otherwise, so it is
    another recording."""
    return f"{_core.MUJOCO_VERSION} ({MUJOCO_BUILD})"


def scenario_recording_id(run_key: str) -> str:
    """A scenario run's recording id, from what decides the run (the command's
    _run_key) and the MuJoCo it steps on."""
    return str(uuid.uuid5(uuid.NAMESPACE_URL, "simloop-scenario:" + mujoco_build() + "\0" + run_key))


def scenario_view(recording_id: str) -> View:
    """A scenario's run: every moving body, every column, panels by quantity."""
    return View(
        recording_id,
        SCENARIO_APPLICATION_ID,
        lambda r: f"{r.name or 'scenario'}: {r.steps} steps of {r.timestep:g} s, seed {r.seed}",
    )


# ---- the chapter's ----------------------------------------------------------

# Its series: label and colour ("box": the box's, "pusher": the pusher's).
CHAPTER_SERIES: Dict[str, Tuple[str, Colour]] = {
    "box_x": ("box x (m)", "box"),
    "box_y": ("box y (m), sideways", "box"),
    "box_z": ("box z (m), height of its centre", "box"),
    "pusher_x": ("pusher x (m)", "pusher"),
    "ncon": ("contacts", (90, 90, 90)),
    **{
        name: (name + " (J)", colour)
        for name, colour in {
            "energy": (0, 0, 0),
            "work_actuator": (64, 115, 217),
            "work_shove": (217, 76, 64),
            "work_passive": (120, 120, 120),
            "work_constraint": (181, 101, 29),
            "work_constraint_positive": (230, 160, 40),
            "energy_unexplained": (150, 60, 180),
        }.items()
    },
    "box_speed": ("box speed (m/s)", "box"),  # computed: CHAPTER_SPEEDS
}
CHAPTER_SPEEDS = {"box_speed": ("box_vx", "box_vy", "box_vz")}
# The shove, amber (not the box's red), 8 mm thick, 0.02 m a newton, 3 cm above the box's top face.
SHOVE_ARROW = Arrow("box", "shove", ("shove_x", "shove_y", "shove_z"), 0.02, 0.08, (255, 190, 0), 0.008)
CAMERA_FRAME = 0.6  # m, the half size of the region around the box the camera keeps in view
# Its panels, stacked: box z first, on a fixed axis; the rest no narrower than MIN_AXIS_SPAN; a legend
# (at the top left, off the z panel's 0.05 m rest line) only where a panel has more than one series.
CHAPTER_PANELS = [
    Panel("box z (m): height of its centre", ["box_z"], z_axis_range, legend=False),
    Panel("box y (m): sideways", ["box_y"], value_axis_range, legend=False),
    Panel("x (m): the pusher and the box", ["box_x", "pusher_x"], value_axis_range),
    Panel("box speed (m/s)", ["box_speed"], value_axis_range, legend=False),
    Panel("contacts", ["ncon"], value_axis_range, legend=False),
]
ENERGY_PANEL = Panel("energy audit (J)", list(_core.ENERGY_COLUMN_NAMES))


def _model_key(model: ModelLike) -> str:
    """What identifies the model in a recording id."""
    if model is None or model is _pusher_scene():
        text = _core.PUSHER_SCENE_XML.encode()
        return "pusher_scene:" + hashlib.sha256(text).hexdigest()[:16]
    if isinstance(model, (str, os.PathLike)):
        return "file:" + hashlib.sha256(Path(model).read_bytes()).hexdigest()[:16]
    # A Model built in memory: its sizes are all we can read back.
    return f"model:nq={model.nq},nv={model.nv},nu={model.nu}"


def config_parameters(config: _core.RunConfig, model: ModelLike = None) -> Dict[str, Any]:
    """The parameters that make a chapter run what it is (what the recording
    id is made of), from the run's config: known before it runs."""
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


def config_recording_id(config: _core.RunConfig, model: ModelLike = None) -> str:
    """A chapter run's recording id, from its config (before it runs): the same
    for the same run, different otherwise."""
    text = json.dumps(config_parameters(config, model), sort_keys=True)
    return str(uuid.uuid5(RECORDING_NAMESPACE, text))


def recording_id(result: _core.RunResult, model: ModelLike = None) -> str:
    """config_recording_id, from the run's result."""
    return config_recording_id(result.config, model)


def recording_name(result: _core.RunResult) -> str:
    """A chapter run's name for people, shown in the viewer's list of recordings."""
    config = result.config
    shove = f"shove {result.shove.force_y:+.1f} N ({config.rng}, seed {config.seed})" if config.perturb else "no shove"
    return f"{result.metrics['steps']} steps of {result.timestep:g} s, {shove}"


def chapter_view(config: _core.RunConfig, model_key: ModelLike, model: _core.Model) -> View:
    """The chapter's run of `config` on `model`: its scene, or a --model scene
    of its layout, whose pusher is the body actuator 0 drives (Model checked
    that it drives a slide or hinge joint). `model_key` identifies the model
    in the recording id (None: the chapter's scene; a path: that file, by its
    bytes)."""
    import numpy as np

    body = model.object_info("joint", model.object_info("actuator", 0)["joint"])["body"]
    pusher = model.names("body")[body] or f"body{body}"
    rest_quat = _core.Sim(model).array("xquat")[body].copy()  # a new Sim is at rest (qpos0), as pusher_track reads it
    home, axis, q0 = _core.pusher_track(model)

    def poses(cols: Mapping[str, Any], rows: int) -> Dict[str, Tuple[Any, Any]]:
        box = np.column_stack([cols["box_x"], cols["box_y"], cols["box_z"]])
        box_quat = np.column_stack([cols["box_qw"], cols["box_qx"], cols["box_qy"], cols["box_qz"]])
        along = home + np.outer(cols["pusher_x"] - q0, axis)
        return {"box": (box, box_quat), pusher: (along, np.tile(rest_quat, (rows, 1)))}

    energy = list(_core.ENERGY_COLUMN_NAMES) if config.audit_energy else []
    return View(
        config_recording_id(config, model_key),
        APPLICATION_ID,
        recording_name,
        columns=list(_core.COLUMN_NAMES) + energy,
        paths={"box": "world/objects/box", pusher: f"world/robot/{pusher}"},
        poses=poses,
        series={name: (label, pusher if c == "pusher" else c) for name, (label, c) in CHAPTER_SERIES.items()},
        speeds=CHAPTER_SPEEDS,
        arrow=SHOVE_ARROW,
        camera=("box", CAMERA_FRAME),
        panels=CHAPTER_PANELS + ([ENERGY_PANEL] if energy else []),
        open_on_run=True,
    )
