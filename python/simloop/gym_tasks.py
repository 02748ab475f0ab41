"""Gymnasium's MuJoCo v5 tasks as simloop scenarios (needs the `gym` extra).

    >>> import gymnasium, simloop
    >>> env = gymnasium.make("simloop/Hopper-v5", reset_noise_scale=0.0)
    >>> envs = gymnasium.make_vec("simloop/HalfCheetah-v5", num_envs=8)   # simloop's C++ threads

Each task is a ScenarioEnv (or ScenarioVectorEnv) over Gymnasium's own XML,
read from the installed gymnasium package, with Gymnasium's defaults and
keyword arguments for that task (frame_skip, reset_noise_scale, reward
weights, healthy ranges, exclude_current_positions_from_observation, ...;
xml_file as Gymnasium resolves it) and simloop's own render_mode, width,
height, rng, and for the vector env threads, autoreset_mode and
max_episode_steps. Another keyword is a TypeError naming it. The scenario
records every joint; the observation, reward and termination are made
from those rows in Gymnasium's arithmetic, in Gymnasium's order, batched:
the vector env pays no Python per env. Reset noise has Gymnasium's shapes
and scales, drawn from the episode's seeded generator, not np_random.
Gymnasium's info keys (x_position, reward_forward, ...) are not given.
"""

from __future__ import annotations

import os
from typing import Any, Callable, Dict, List, Mapping, NamedTuple, Optional, Tuple

import gymnasium
import numpy as np

from . import _core
from ._gym_setup import batched
from .gym import ScenarioEnv
from .gym_vector import ScenarioVectorEnv
from .scenario import Scenario
from .sim import Sim

__all__ = ["TASKS", "assets_folder", "make_task"]

# simloop's own keyword arguments, beside the task's.
_ENV_ARGUMENTS = ("render_mode", "width", "height", "rng")
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


class Layout:
    """Where qpos and qvel are in a recorded row (every joint recorded), and their names; data: each recorded
    mjData array's columns (its entries' in their order), which the recorder lays out after the joints'."""

    def __init__(self, names: Tuple[str, ...], model: _core.Model, data: List[Tuple[str, str, int]]) -> None:
        qpos: List[int] = []
        qvel: List[int] = []
        for j, joint in enumerate(model.names("joint")):
            info = model.object_info("joint", j)
            for column, count, into in ((joint + "_pos", info["nq"], qpos), (joint + "_vel", info["nv"], qvel)):
                into.extend(names.index(column if count == 1 else f"{column}{k}") for k in range(count))
        self.qpos, self.qvel = np.array(qpos), np.array(qvel)
        self.names = names
        columns: Dict[str, List[int]] = {}
        start = len(qpos) + len(qvel)
        for array, _, count in data:
            columns.setdefault(array, []).extend(range(start, start + count))
            start += count
        assert start == len(names), (start, len(names))  # (every column placed)
        self.data = {array: np.array(c) for array, c in columns.items()}

    def observe(self, skip: int, clip: Optional[float] = None) -> Callable[[np.ndarray], np.ndarray]:
        """Gymnasium's observation of the locomotion tasks: qpos without its first `skip` values, then qvel
        (clipped to +-clip when given)."""
        positions, velocities = self.qpos[skip:], self.qvel

        def observe(rows: np.ndarray) -> np.ndarray:
            v = rows[:, velocities]
            return np.concatenate((rows[:, positions], v if clip is None else np.clip(v, -clip, clip)), axis=1)

        setattr(observe, "names", tuple(self.names[i] for i in np.concatenate((positions, velocities))))  # noqa: B010
        return observe


def _ctrl_cost(weight: float, actions: np.ndarray) -> Any:
    return weight * np.sum(np.square(actions), axis=1)


def _forward(layout: Layout, p: Mapping[str, Any], dt: float) -> Callable[..., np.ndarray]:
    """forward_reward_weight * x velocity ((x after - x before) / dt, x = qpos[0])."""
    x = layout.qpos[0]
    return lambda before, after: p["forward_reward_weight"] * ((after[:, x] - before[:, x]) / dt)


def _planar(p: Mapping[str, Any], layout: Layout, dt: float, excluded: int) -> Tuple[Any, Any, Any]:
    """HalfCheetah and Swimmer: forward - ctrl cost, never terminated; the first `excluded` qpos left out of the
    observation (with exclude_current_positions_from_observation)."""
    forward = _forward(layout, p, dt)
    skip = excluded if p["exclude_current_positions_from_observation"] else 0
    reward = batched(lambda before, actions, after: forward(before, after) - _ctrl_cost(p["ctrl_cost_weight"], actions))
    return layout.observe(skip), reward, None


def _hopping(p: Mapping[str, Any], layout: Layout, dt: float, healthy: Callable[..., np.ndarray]) -> Tuple[Any, ...]:
    """Hopper and Walker2d: (forward + healthy reward) - ctrl cost; qvel clipped to +-10 in the observation."""
    forward = _forward(layout, p, dt)

    def reward(before: np.ndarray, actions: np.ndarray, after: np.ndarray) -> Any:
        rewards = forward(before, after) + healthy(after) * p["healthy_reward"]
        return rewards - _ctrl_cost(p["ctrl_cost_weight"], actions)

    terminate = batched(lambda after: ~healthy(after)) if p["terminate_when_unhealthy"] else None
    return layout.observe(1 if p["exclude_current_positions_from_observation"] else 0, 10.0), batched(reward), terminate


def _between(low_high: Tuple[float, float], values: np.ndarray) -> np.ndarray:
    low, high = low_high
    return np.logical_and(low < values, values < high)


def _hopper(p: Mapping[str, Any], layout: Layout, dt: float) -> Tuple[Any, ...]:
    def healthy(rows: np.ndarray) -> Any:  # z, angle = qpos[1:3]; the state past x and z in range
        state = np.concatenate((rows[:, layout.qpos], rows[:, layout.qvel]), axis=1)[:, 2:]
        in_range = np.all(_between(p["healthy_state_range"], state), axis=1)
        z, angle = rows[:, layout.qpos[1]], rows[:, layout.qpos[2]]
        return in_range & _between(p["healthy_z_range"], z) & _between(p["healthy_angle_range"], angle)

    return _hopping(p, layout, dt, healthy)


def _walker(p: Mapping[str, Any], layout: Layout, dt: float) -> Tuple[Any, ...]:
    def healthy(rows: np.ndarray) -> Any:
        z, angle = rows[:, layout.qpos[1]], rows[:, layout.qpos[2]]
        return _between(p["healthy_z_range"], z) & _between(p["healthy_angle_range"], angle)

    return _hopping(p, layout, dt, healthy)


def _inverted_pendulum(p: Mapping[str, Any], layout: Layout, dt: float) -> Tuple[Any, ...]:
    """Reward 1 while upright; terminated when the observation is not finite or the pole's angle past 0.2 rad."""
    observe = layout.observe(0)

    def fallen(rows: np.ndarray) -> Any:
        obs = observe(rows)
        return ~np.isfinite(obs).all(axis=1) | (np.abs(obs[:, 1]) > 0.2)

    reward = batched(lambda before, actions, after: (~fallen(after)).astype(np.float64))
    return observe, reward, batched(fallen)


def _ant(p: Mapping[str, Any], layout: Layout, dt: float) -> Tuple[Any, ...]:
    """Ant: (forward + healthy) - (ctrl + contact cost), from the main body's xpos and every body's cfrc_ext as
    the last step left them (data_at_step); cfrc_ext clipped to contact_force_range in the cost and the
    observation (bodies after the world)."""
    xy, forces = layout.data["xpos"][:2], layout.data["cfrc_ext"]
    skip = 2 if p["exclude_current_positions_from_observation"] else 0
    low, high = p["contact_force_range"]
    state = np.concatenate((layout.qpos, layout.qvel))
    z = layout.qpos[2]

    def healthy(rows: np.ndarray) -> Any:
        return (
            np.isfinite(rows[:, state]).all(axis=1)
            & (p["healthy_z_range"][0] <= rows[:, z])
            & (rows[:, z] <= p["healthy_z_range"][1])
        )

    def reward(before: np.ndarray, actions: np.ndarray, after: np.ndarray) -> Any:
        x_velocity = ((after[:, xy] - before[:, xy]) / dt)[:, 0]
        rewards = x_velocity * p["forward_reward_weight"] + healthy(after) * p["healthy_reward"]
        contact_cost = p["contact_cost_weight"] * np.sum(np.square(np.clip(after[:, forces], low, high)), axis=1)
        return rewards - (_ctrl_cost(p["ctrl_cost_weight"], actions) + contact_cost)

    positions, velocities = layout.qpos[skip:], layout.qvel
    observed = np.concatenate((positions, velocities, forces[6:] if p["include_cfrc_ext_in_observation"] else []))
    clipped = len(positions) + len(velocities)  # (the contact forces after it)

    def observe(rows: np.ndarray) -> np.ndarray:
        out = rows[:, observed.astype(int)]
        out[:, clipped:] = np.clip(out[:, clipped:], low, high)
        return out

    setattr(observe, "names", tuple(layout.names[i] for i in observed.astype(int)))  # noqa: B010
    terminate = batched(lambda after: ~healthy(after)) if p["terminate_when_unhealthy"] else None
    return observe, batched(reward), terminate


def _ant_data(p: Mapping[str, Any], model: _core.Model) -> List[Tuple[str, str, int]]:
    return [("xpos", str(p["main_body"]), 3)] + [("cfrc_ext", str(b), 6) for b in range(model.nbody)]


def _humanoid(p: Mapping[str, Any], layout: Layout, dt: float) -> Tuple[Any, ...]:
    """Humanoid: (forward + healthy) - (ctrl + contact cost), forward from the mass centre (body masses times
    xipos, as the last step left them); the observation adds cinert, cvel, qfrc_actuator past the root and
    cfrc_ext, each of the bodies after the world."""
    mass = p["_body_mass"]
    xipos, cfrc = layout.data["xipos"], layout.data["cfrc_ext"]
    z = layout.qpos[2]

    def mass_center(rows: np.ndarray) -> Any:
        centres = np.einsum("b,nbj->nj", mass, rows[:, xipos].reshape(len(rows), -1, 3))
        return (centres / mass.sum())[:, 0:2]

    def healthy(rows: np.ndarray) -> Any:
        low, high = p["healthy_z_range"]
        return (low < rows[:, z]) & (rows[:, z] < high)

    def reward(before: np.ndarray, actions: np.ndarray, after: np.ndarray) -> Any:
        x_velocity = ((mass_center(after) - mass_center(before)) / dt)[:, 0]
        rewards = p["forward_reward_weight"] * x_velocity + healthy(after) * p["healthy_reward"]
        contact_cost = np.clip(
            p["contact_cost_weight"] * np.sum(np.square(after[:, cfrc]), axis=1), *p["contact_cost_range"]
        )
        return rewards - (_ctrl_cost(p["ctrl_cost_weight"], actions) + contact_cost)

    parts = [layout.qpos[2 if p["exclude_current_positions_from_observation"] else 0 :], layout.qvel]
    for array, width in (("cinert", 10), ("cvel", 6), ("qfrc_actuator", 0), ("cfrc_ext", 6)):
        if p[f"include_{array}_in_observation"]:
            parts.append(layout.data[array][width:])  # (after the world body; qfrc_actuator: the joints past the root)
    observed = np.concatenate(parts)
    observe = lambda rows: rows[:, observed]  # noqa: E731
    setattr(observe, "names", tuple(layout.names[i] for i in observed))  # noqa: B010
    terminate = batched(lambda after: ~healthy(after)) if p["terminate_when_unhealthy"] else None
    return observe, batched(reward), terminate


def _humanoid_data(p: Mapping[str, Any], model: _core.Model) -> List[Tuple[str, str, int]]:
    bodies = [str(b) for b in range(model.nbody)]
    joints = [(str(j), model.object_info("joint", j)["nv"]) for j in range(1, model.njnt)]
    return (
        [("xipos", b, 3) for b in bodies]
        + [("cinert", b, 10) for b in bodies]
        + [("cvel", b, 6) for b in bodies]
        + [("qfrc_actuator", j, nv) for j, nv in joints]
        + [("cfrc_ext", b, 6) for b in bodies]
    )


class Task(NamedTuple):
    """A Gymnasium v5 task: its keyword arguments with Gymnasium's defaults (xml_file and frame_skip among
    them), how its reset noise is drawn for qpos and qvel, and what makes its observe, reward and terminate."""

    defaults: Dict[str, Any]
    noise: Tuple[str, str]  # "uniform" (in +-scale) or "normal" (scale times a standard normal draw)
    parts: Callable[..., Tuple[Any, ...]]
    # The mjData arrays it records ([array, object, count]), read as the last step left them (data_at_step).
    data: Callable[[Mapping[str, Any], _core.Model], List[Tuple[str, str, int]]] = lambda p, model: []


_LOCOMOTION = {"forward_reward_weight": 1.0}
_EXCLUDE = {"exclude_current_positions_from_observation": True}
_HEALTHY = {"healthy_reward": 1.0, "terminate_when_unhealthy": True}
TASKS: Dict[str, Task] = {
    "HalfCheetah": Task(
        dict(xml_file="half_cheetah.xml", frame_skip=5, **_LOCOMOTION, ctrl_cost_weight=0.1, reset_noise_scale=0.1)
        | _EXCLUDE,
        ("uniform", "normal"),
        lambda p, layout, dt: _planar(p, layout, dt, 1),
    ),
    "Hopper": Task(
        dict(xml_file="hopper.xml", frame_skip=4, **_LOCOMOTION, ctrl_cost_weight=1e-3, **_HEALTHY)
        | dict(healthy_state_range=(-100.0, 100.0), healthy_z_range=(0.7, float("inf")))
        | dict(healthy_angle_range=(-0.2, 0.2), reset_noise_scale=5e-3)
        | _EXCLUDE,
        ("uniform", "uniform"),
        _hopper,
    ),
    "Walker2d": Task(
        dict(xml_file="walker2d_v5.xml", frame_skip=4, **_LOCOMOTION, ctrl_cost_weight=1e-3, **_HEALTHY)
        | dict(healthy_z_range=(0.8, 2.0), healthy_angle_range=(-1.0, 1.0), reset_noise_scale=5e-3)
        | _EXCLUDE,
        ("uniform", "uniform"),
        _walker,
    ),
    "Swimmer": Task(
        dict(xml_file="swimmer.xml", frame_skip=4, **_LOCOMOTION, ctrl_cost_weight=1e-4, reset_noise_scale=0.1)
        | _EXCLUDE,
        ("uniform", "uniform"),
        lambda p, layout, dt: _planar(p, layout, dt, 2),  # (Swimmer leaves out x and y)
    ),
    "Ant": Task(
        dict(xml_file="ant.xml", frame_skip=5, forward_reward_weight=1, ctrl_cost_weight=0.5)
        | dict(contact_cost_weight=5e-4, healthy_reward=1.0, main_body=1, terminate_when_unhealthy=True)
        | dict(healthy_z_range=(0.2, 1.0), contact_force_range=(-1.0, 1.0), reset_noise_scale=0.1)
        | _EXCLUDE
        | dict(include_cfrc_ext_in_observation=True),
        ("uniform", "normal"),
        _ant,
        _ant_data,
    ),
    "Humanoid": Task(
        dict(xml_file="humanoid.xml", frame_skip=5, forward_reward_weight=1.25, ctrl_cost_weight=0.1)
        | dict(contact_cost_weight=5e-7, contact_cost_range=(-np.inf, 10.0), healthy_reward=5.0)
        | dict(terminate_when_unhealthy=True, healthy_z_range=(1.0, 2.0), reset_noise_scale=1e-2)
        | _EXCLUDE
        | {f"include_{a}_in_observation": True for a in ("cinert", "cvel", "qfrc_actuator", "cfrc_ext")},
        ("uniform", "uniform"),
        _humanoid,
        _humanoid_data,
    ),
    "InvertedPendulum": Task(
        dict(xml_file="inverted_pendulum.xml", frame_skip=2, reset_noise_scale=0.01),
        ("uniform", "uniform"),
        _inverted_pendulum,
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
    episodes (max_episode_steps 1000 unless given, as Gymnasium registers it)."""
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
        reset=_reset(task, float(params["reset_noise_scale"])),
    )
    frame_skip = params["frame_skip"]
    probe = ScenarioEnv(scenario, model=model)  # (the recorded columns: no episode is started)
    layout = Layout(probe.observation_names, model, data)
    params["_body_mass"] = np.array(Sim(model).named.model.body_mass)  # (Humanoid's mass centre)
    observe, reward, terminate = task.parts(params, layout, model.timestep * frame_skip)
    common = {"control_every": frame_skip, "observe": observe, "reward": reward, "terminate": terminate, "model": model}
    common["data_at_step"] = bool(data)
    if num_envs is None:
        return ScenarioEnv(scenario, **common, **arguments)
    arguments.setdefault("max_episode_steps", 1000)
    return ScenarioVectorEnv(scenario, num_envs, **common, **arguments)


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
inverted_pendulum, inverted_pendulum_vector = _entry_points("InvertedPendulum")
