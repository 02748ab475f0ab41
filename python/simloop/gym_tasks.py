"""Gymnasium's MuJoCo v5 tasks as simloop scenarios (needs the `gym` extra).

    >>> import gymnasium, simloop
    >>> env = gymnasium.make("simloop/Hopper-v5", reset_noise_scale=0.0)
    >>> envs = gymnasium.make_vec("simloop/HalfCheetah-v5", num_envs=8)   # simloop's C++ threads

Each task is a ScenarioEnv (or ScenarioVectorEnv) over Gymnasium's own XML,
read from the installed gymnasium package, with Gymnasium's defaults and
keyword arguments for that task (frame_skip, reset_noise_scale, reward
weights, healthy ranges, exclude_current_positions_from_observation, ...;
xml_file as Gymnasium resolves it) and simloop's own render_mode, width,
height, view, rng, on_reset, and for the vector env threads, autoreset_mode
and max_episode_steps. Another keyword is a TypeError naming it. The scenario
records every joint; the observation, reward and termination are made
from those rows in Gymnasium's arithmetic, in Gymnasium's order, batched:
the vector env pays no Python per env (the arithmetic, task by task, is in
_gym_task_families; Reacher's and Pusher's in _gym_goal_tasks). Reset noise
has Gymnasium's shapes and scales, drawn from the episode's seeded
generator, not np_random; Reacher's and Pusher's goals are drawn so by
their task's on_reset hook (on_reset=None: the XML's or the options'
start). Gymnasium's info keys (x_position, reward_forward, ...) are in
info at step and reset, made from
the same rows (a vector env's in Gymnasium's vector layout, with "_key"
masks). The default view is Gymnasium's default_camera_config, as its
render_mode "rgb_array" camera takes it (_view).
"""

from __future__ import annotations

import os
from typing import Any, Callable, Dict, Mapping, NamedTuple, Optional, Tuple, Union

import gymnasium
import numpy as np

from . import _core
from . import _gym_goal_tasks as goals
from . import _gym_task_families as families
from ._gym_registry import episode_steps
from ._gym_task_families import Layout
from .gym import ScenarioEnv
from .gym_vector import ScenarioVectorEnv
from .scenario import Scenario
from .sim import Sim

__all__ = ["TASKS", "assets_folder", "make_task"]

# simloop's own keyword arguments, beside the task's.
_ENV_ARGUMENTS = ("render_mode", "width", "height", "view", "rng", "on_reset")
_VECTOR_ARGUMENTS = ("threads", "autoreset_mode", "max_episode_steps")
# An episode ends by Gymnasium's TimeLimit (its max_episode_steps), not by the scenario's length.
_ENDLESS = _core.MAX_STEPS


def assets_folder() -> str:
    """Where the installed gymnasium keeps its MuJoCo tasks' XML."""
    return os.path.join(os.path.dirname(os.path.abspath(gymnasium.__file__)), "envs", "mujoco", "assets")


def _xml_path(xml_file: object) -> str:
    """xml_file as Gymnasium's MujocoEnv resolves it: a path starting with . or / as given, ~ expanded, else in
    its assets."""
    if not isinstance(xml_file, str):
        raise TypeError(f"xml_file must be a str, got {type(xml_file).__name__}")
    if xml_file.startswith((".", "/")):
        return xml_file
    if xml_file.startswith("~"):
        return os.path.expanduser(xml_file)
    return os.path.join(assets_folder(), xml_file)


class Task(NamedTuple):
    """A Gymnasium v5 task: its keyword arguments with Gymnasium's defaults (xml_file and frame_skip among
    them), how its reset noise is drawn for qpos and qvel, and what makes its observe, reward, terminate and
    info keys (parts(params, layout, dt))."""

    defaults: Dict[str, Any]
    noise: Tuple[str, str]  # "uniform" (in +-scale) or "normal" (scale times a standard normal draw)
    parts: Callable[..., Tuple[Any, ...]]
    camera: Mapping[str, Any]  # Gymnasium's default_camera_config (gym_tasks makes it the env's view)
    # The mjData arrays it records ([array, object, count]), read as the last step left them (data_at_step).
    data: Callable[[Mapping[str, Any], _core.Model], families.Data] = lambda p, model: []
    # Its on_reset hook, where Gymnasium's reset_model draws more than noise (Reacher's and Pusher's goals).
    start: Optional[Callable[[Mapping[str, Any]], goals.Hook]] = None


def _camera(distance: float, lookat: Optional[Tuple[float, ...]] = None, elevation: Optional[float] = None) -> Any:
    """Gymnasium's DEFAULT_CAMERA_CONFIG of a task, but trackbodyid (its rgb_array camera is a free one)."""
    camera = {"distance": distance, "lookat": lookat, "elevation": elevation}
    return {k: v for k, v in camera.items() if v is not None}


_LOCOMOTION = {"forward_reward_weight": 1.0}
_EXCLUDE = {"exclude_current_positions_from_observation": True}
_HEALTHY = {"healthy_reward": 1.0, "terminate_when_unhealthy": True}
_HUMANOID_OBSERVES = {f"include_{a}_in_observation": True for a in ("cinert", "cvel", "qfrc_actuator", "cfrc_ext")}
TASKS: Dict[str, Task] = {
    "HalfCheetah": Task(
        dict(xml_file="half_cheetah.xml", frame_skip=5, **_LOCOMOTION, ctrl_cost_weight=0.1, reset_noise_scale=0.1)
        | _EXCLUDE,
        ("uniform", "normal"),
        lambda p, layout, dt: families.planar(p, layout, dt, 1),
        _camera(4.0),
    ),
    "Hopper": Task(
        dict(xml_file="hopper.xml", frame_skip=4, **_LOCOMOTION, ctrl_cost_weight=1e-3, **_HEALTHY)
        | dict(healthy_state_range=(-100.0, 100.0), healthy_z_range=(0.7, float("inf")))
        | dict(healthy_angle_range=(-0.2, 0.2), reset_noise_scale=5e-3)
        | _EXCLUDE,
        ("uniform", "uniform"),
        families.hopper,
        _camera(3.0, (0.0, 0.0, 1.15), -20.0),
    ),
    "Walker2d": Task(
        dict(xml_file="walker2d_v5.xml", frame_skip=4, **_LOCOMOTION, ctrl_cost_weight=1e-3, **_HEALTHY)
        | dict(healthy_z_range=(0.8, 2.0), healthy_angle_range=(-1.0, 1.0), reset_noise_scale=5e-3)
        | _EXCLUDE,
        ("uniform", "uniform"),
        families.walker,
        _camera(4.0, (0.0, 0.0, 1.15), -20.0),
    ),
    "Swimmer": Task(
        dict(xml_file="swimmer.xml", frame_skip=4, **_LOCOMOTION, ctrl_cost_weight=1e-4, reset_noise_scale=0.1)
        | _EXCLUDE,
        ("uniform", "uniform"),
        lambda p, layout, dt: families.planar(p, layout, dt, 2),  # (Swimmer leaves out x and y)
        {},  # (None: Gymnasium's free camera is at the scene's extent, a distance simloop's view cannot say)
    ),
    "Ant": Task(
        dict(xml_file="ant.xml", frame_skip=5, forward_reward_weight=1, ctrl_cost_weight=0.5)
        | dict(contact_cost_weight=5e-4, healthy_reward=1.0, main_body=1, terminate_when_unhealthy=True)
        | dict(healthy_z_range=(0.2, 1.0), contact_force_range=(-1.0, 1.0), reset_noise_scale=0.1)
        | _EXCLUDE
        | dict(include_cfrc_ext_in_observation=True),
        ("uniform", "normal"),
        families.ant,
        _camera(4.0),
        families.ant_data,
    ),
    "Humanoid": Task(
        dict(xml_file="humanoid.xml", frame_skip=5, forward_reward_weight=1.25, ctrl_cost_weight=0.1)
        | dict(contact_cost_weight=5e-7, contact_cost_range=(-np.inf, 10.0), healthy_reward=5.0)
        | dict(terminate_when_unhealthy=True, healthy_z_range=(1.0, 2.0), reset_noise_scale=1e-2)
        | _EXCLUDE
        | _HUMANOID_OBSERVES,
        ("uniform", "uniform"),
        families.humanoid,
        _camera(4.0, (0.0, 0.0, 2.0), -20.0),
        families.humanoid_data,
    ),
    "HumanoidStandup": Task(
        dict(xml_file="humanoidstandup.xml", frame_skip=5, uph_cost_weight=1, ctrl_cost_weight=0.1)
        | dict(impact_cost_weight=0.5e-6, impact_cost_range=(-np.inf, 10.0), reset_noise_scale=1e-2)
        | _EXCLUDE
        | _HUMANOID_OBSERVES,
        ("uniform", "uniform"),
        families.humanoid_standup,
        _camera(4.0, (0.0, 0.0, 0.8925), -20.0),
        lambda p, model: families.humanoid_data(p, model, standup=True),
    ),
    "InvertedPendulum": Task(
        dict(xml_file="inverted_pendulum.xml", frame_skip=2, reset_noise_scale=0.01),
        ("uniform", "uniform"),
        families.inverted_pendulum,
        _camera(2.04),
    ),
    "InvertedDoublePendulum": Task(
        dict(xml_file="inverted_double_pendulum.xml", frame_skip=5, healthy_reward=10.0, reset_noise_scale=0.1),
        ("uniform", "normal"),
        families.inverted_double_pendulum,
        {},  # (Gymnasium's default_camera_config is None, as Swimmer's)
        lambda p, model: [("site_xpos", "0", 3), ("qfrc_constraint", "0", 1)],  # (the tip; the cart's slider)
    ),
    "Reacher": Task(
        dict(xml_file="reacher.xml", frame_skip=2, reward_dist_weight=1, reward_control_weight=1),
        ("uniform", "uniform"),  # (unused: no reset_noise_scale; the start is drawn by the hook)
        goals.reacher,
        {},  # (Gymnasium's config is trackbodyid 0 only: its free camera at the scene's extent, as Swimmer's)
        goals.reacher_data,
        goals.reacher_reset,
    ),
    "Pusher": Task(
        dict(xml_file="pusher_v5.xml", frame_skip=5, reward_near_weight=0.5, reward_dist_weight=1)
        | dict(reward_control_weight=0.1),
        ("uniform", "uniform"),  # (unused, as Reacher's)
        goals.pusher,
        _camera(4.0),
        goals.pusher_data,
        goals.pusher_reset,
    ),
}


def _reset(task: Task, scale: float) -> Optional[Dict[str, Any]]:
    """The scenario's [reset]: noise of the task's shapes at this scale (none at 0): uniform in +-scale, or scale
    times a standard normal draw, per coordinate, qpos then qvel, from the episode's generator."""
    if not scale:
        return None
    qpos, qvel = task.noise
    return {"qpos_noise": scale, "qvel_noise": scale, "qpos_noise_distribution": qpos, "qvel_noise_distribution": qvel}


def make_task(name: str, num_envs: Optional[int] = None, **kwargs: Any) -> Any:
    """Gymnasium's task `name` ("Hopper", a key of TASKS) as a ScenarioEnv, or a ScenarioVectorEnv of num_envs
    episodes (max_episode_steps as Gymnasium registers the task unless given: 1000, Reacher's 50, Pusher's 100)."""
    task = TASKS[name]
    params = dict(task.defaults)
    arguments: Dict[str, Any] = {}
    allowed = _ENV_ARGUMENTS + (_VECTOR_ARGUMENTS if num_envs is not None else ())
    unknown = [k for k in kwargs if k not in params and k not in allowed]
    if unknown:
        raise TypeError(
            f"simloop/{name}-v5 got unexpected keyword arguments {', '.join(map(repr, unknown))} "
            f"(it takes {', '.join(list(params) + list(allowed))})"
        )
    for key, value in kwargs.items():
        (params if key in params else arguments)[key] = value
    path = _xml_path(params["xml_file"])
    model = _core.Model.from_file(path)
    data = task.data(params, model)
    scenario = Scenario(
        path,
        steps=_ENDLESS,
        record={"joints": "all", "contacts": False, "data": [(array, name) for array, name, _ in data]},
        reset=_reset(task, float(params.get("reset_noise_scale", 0.0))),
    )
    frame_skip = params["frame_skip"]
    probe = ScenarioEnv(scenario, model=model)  # (the recorded columns: no episode is started)
    layout = Layout(probe.observation_names, model, data)
    sim = Sim(model)  # (the model's facts Gymnasium's tasks read: its initial state, masses, geoms)
    params.update(_qpos0=np.array(sim.named.model.qpos0), _body_mass=np.array(sim.named.model.body_mass))
    params["_nv"] = len(sim.named.data.qvel)
    params["_timestep"] = model.timestep
    observe, reward, terminate, info = task.parts(params, layout, model.timestep * frame_skip)
    common = {"control_every": frame_skip, "observe": observe, "reward": reward, "terminate": terminate, "model": model}
    common["data_at_step"] = bool(data)
    arguments.setdefault("view", _view(task.camera, sim))
    if task.start is not None:  # (on_reset=None or a hook of one's own replaces the goal draw)
        arguments.setdefault("on_reset", task.start(params))
    env: Union[ScenarioEnv, ScenarioVectorEnv]
    if num_envs is None:
        env = ScenarioEnv(scenario, **common, **arguments)
    else:
        arguments.setdefault("max_episode_steps", episode_steps(name))
        env = ScenarioVectorEnv(scenario, num_envs, **common, **arguments)
    env._setup.task_info = info  # (Gymnasium's info keys, made from the rows as the reward is)
    return env


def _view(camera: Mapping[str, Any], sim: Sim) -> Dict[str, Any]:
    """Gymnasium's default_camera_config as a view: its render_mode "rgb_array" camera is MuJoCo's free camera
    (mjCAMERA_FREE, which ignores trackbodyid), at the config's distance and lookat, else at the median of the geoms'
    positions (here the scene's initial state's; Gymnasium's at the first picture's), azimuth 90 and elevation -45
    (a new MjvCamera's) unless the config says; with no distance (Swimmer's and InvertedDoublePendulum's config is
    None: Gymnasium's is the scene's extent) simloop's default free camera's, 1.5 times the extent."""
    lookat = camera.get("lookat", np.median(np.array(sim.named.data.geom_xpos), axis=0))
    view = {"azimuth": 90.0, "elevation": camera.get("elevation", -45.0), "lookat": [float(x) for x in lookat]}
    return view | ({"distance": camera["distance"]} if "distance" in camera else {})


def _entry_points(name: str) -> Tuple[Callable[..., ScenarioEnv], Callable[..., ScenarioVectorEnv]]:
    def single(**kwargs: Any) -> ScenarioEnv:
        return make_task(name, None, **kwargs)  # type: ignore[no-any-return]

    def vector(num_envs: int = 1, **kwargs: Any) -> ScenarioVectorEnv:
        return make_task(name, num_envs, **kwargs)  # type: ignore[no-any-return]

    single.__doc__ = vector.__doc__ = f"simloop/{name}-v5: Gymnasium's {name}-v5 over its own XML (make_task)."
    return single, vector


half_cheetah, half_cheetah_vector = _entry_points("HalfCheetah")
hopper, hopper_vector = _entry_points("Hopper")
walker2d, walker2d_vector = _entry_points("Walker2d")
swimmer, swimmer_vector = _entry_points("Swimmer")
ant, ant_vector = _entry_points("Ant")
humanoid, humanoid_vector = _entry_points("Humanoid")
humanoid_standup, humanoid_standup_vector = _entry_points("HumanoidStandup")
inverted_pendulum, inverted_pendulum_vector = _entry_points("InvertedPendulum")
inverted_double_pendulum, inverted_double_pendulum_vector = _entry_points("InvertedDoublePendulum")
reacher, reacher_vector = _entry_points("Reacher")
pusher, pusher_vector = _entry_points("Pusher")
