"""Gymnasium's MuJoCo v5 tasks, family by family, as arithmetic on a batch of recorded rows (gym_tasks.TASKS
names each task's defaults, reset noise and camera, and makes the environments): what makes a task's observation,
reward, termination and info keys, in Gymnasium's arithmetic and order, so that the numbers are Gymnasium's bit for
bit and a vector env pays no Python per env; and the mjData arrays a task records for them."""

from __future__ import annotations

from typing import Any, Callable, Dict, List, Mapping, Optional, Tuple

import numpy as np

from . import _core
from ._gym_setup import TaskInfo, batched

Rows = np.ndarray
Info = Dict[str, np.ndarray]
Data = List[Tuple[str, str, int]]  # the mjData arrays a task records: [array, object, count]


class Layout:
    """Where qpos and qvel are in a recorded row (every joint recorded), and their names; data: each recorded
    mjData array's columns (its entries' in their order), which the recorder lays out after the joints'."""

    def __init__(self, names: Tuple[str, ...], model: _core.Model, data: Data) -> None:
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

    def observe(self, skip: int, clip: Optional[float] = None) -> Callable[[Rows], np.ndarray]:
        """Gymnasium's observation of the locomotion tasks: qpos without its first `skip` values, then qvel
        (clipped to +-clip when given)."""
        positions, velocities = self.qpos[skip:], self.qvel
        index = np.concatenate((positions, velocities))
        columns, first_velocity = _columns(index), len(positions)

        def observe(rows: Rows) -> np.ndarray:
            out = rows[:, columns]  # (one gather, or a view of consecutive columns: the env copies what it hands out)
            if clip is None:
                return out
            out = np.array(out)
            np.clip(out[:, first_velocity:], -clip, clip, out=out[:, first_velocity:])
            return out

        return _named(observe, tuple(self.names[i] for i in index))

    def where(self, y: bool = False, z: Optional[Tuple[int, float]] = None) -> Callable[[Rows], Info]:
        """Gymnasium's info keys for where the robot is: x_position (qpos[0]); with y, y_position and
        distance_from_origin (the norm of qpos[0:2]); z (a qpos index and its initial value): z_distance_from_origin;
        tendon_length and tendon_velocity where the task records them (Humanoid's)."""
        x, xy, tendons = self.qpos[0], self.qpos[:2], self.data.get("ten_length")

        def where(rows: Rows) -> Info:
            out = {"x_position": rows[:, x].copy()}  # (a copy: the rows change as envs reset)
            if y:
                position = rows[:, xy]
                out["y_position"] = position[:, 1].copy()
                # np.linalg.norm's is a BLAS dot product, as vecdot's: the same bits (a sum of squares is not)
                out["distance_from_origin"] = np.sqrt(np.vecdot(position, position))
            if z is not None:
                out["z_distance_from_origin"] = rows[:, self.qpos[z[0]]] - z[1]
            if tendons is not None:
                out["tendon_length"], out["tendon_velocity"] = rows[:, tendons], rows[:, self.data["ten_velocity"]]
            return out

        return where


def _columns(index: np.ndarray) -> Any:
    """These columns as a slice where they are consecutive (a view: no gather), else the index array."""
    if len(index) and (np.diff(index) == 1).all():
        return slice(int(index[0]), int(index[-1]) + 1)
    return index


def _once(of_rows: Callable[[Rows], Any]) -> Callable[[Rows], Any]:
    """A function of a step's rows, computed once for its reward, termination and info keys, which the env asks
    with the same rows object (as _shared's terms)."""
    last: List[Any] = [None, None]

    def once(rows: Rows) -> Any:
        if last[0] is not rows:
            last[:] = [rows, of_rows(rows)]
        return last[1]

    return once


def _named(observe: Callable[[Rows], np.ndarray], names: Tuple[str, ...]) -> Callable[[Rows], np.ndarray]:
    setattr(observe, "names", names)  # noqa: B010 (what ScenarioEnv calls observation_names)
    return observe


def _sum_of_squares(values: np.ndarray) -> Any:
    """Each row's sum of squares, as np.sum(np.square(row)) adds it (pairwise): of a C-ordered copy where the rows
    are not contiguous (rows[:, columns] of n > 1 rows is not), whose sum would add column by column, other bits."""
    return np.sum(np.square(np.ascontiguousarray(values)), axis=1)


def _ctrl_cost(weight: float, actions: np.ndarray) -> Any:
    return weight * _sum_of_squares(actions)


def _velocity(columns: Any, dt: float) -> Callable[[Rows, Rows], np.ndarray]:
    """(after - before) / dt of these columns (Gymnasium's x_velocity from qpos[0], xy from a body's xpos)."""
    return lambda before, after: (after[:, columns] - before[:, columns]) / dt


def _shared(terms: Callable[[Rows, np.ndarray, Rows], Tuple[Any, ...]]) -> Callable[..., Tuple[Any, ...]]:
    """A step's reward terms, made once for its reward and its info keys: the env asks for both with the same
    before and after rows (the same objects), so the last result is kept with them and given again. A step's rows
    are new arrays, so the next step never meets it (a batch of some envs' rows is a new array too: made anew)."""
    last: List[Any] = [None, None, ()]

    def shared(before: Rows, actions: np.ndarray, after: Rows) -> Tuple[Any, ...]:
        if last[0] is not before or last[1] is not after:
            last[:] = [before, after, terms(before, actions, after)]
        return last[2]  # type: ignore[no-any-return]

    return shared


def _parts(observe: Any, reward: Any, terminate: Any, step: Any, reset: Any) -> Tuple[Any, ...]:
    """A task's observe, @batched reward and terminate (or None), and its info keys."""
    return observe, batched(reward), terminate and batched(terminate), TaskInfo(step, reset)


def planar(p: Mapping[str, Any], layout: Layout, dt: float, excluded: int) -> Tuple[Any, ...]:
    """HalfCheetah and Swimmer: forward - ctrl cost, never terminated; the first `excluded` qpos left out of the
    observation (with exclude_current_positions_from_observation). Swimmer's info adds y (its x and y are free)."""
    velocity, where = _velocity(layout.qpos[:excluded], dt), layout.where(y=excluded == 2)

    @_shared
    def terms(before: Rows, actions: np.ndarray, after: Rows) -> Tuple[Any, ...]:
        v = velocity(before, after)
        return v, p["forward_reward_weight"] * v[:, 0], _ctrl_cost(p["ctrl_cost_weight"], actions)

    def reward(before: Rows, actions: np.ndarray, after: Rows) -> Any:
        _, forward, ctrl = terms(before, actions, after)
        return forward - ctrl

    def step(before: Rows, actions: np.ndarray, after: Rows) -> Info:
        v, forward, ctrl = terms(before, actions, after)
        out = where(after) | {"x_velocity": v[:, 0], "reward_forward": forward, "reward_ctrl": -ctrl}
        return out | ({"y_velocity": v[:, 1]} if excluded == 2 else {})

    skip = excluded if p["exclude_current_positions_from_observation"] else 0
    return _parts(layout.observe(skip), reward, None, step, where)


def _hopping(p: Mapping[str, Any], layout: Layout, dt: float, healthy: Callable[[Rows], Any]) -> Tuple[Any, ...]:
    """Hopper and Walker2d: (forward + healthy reward) - ctrl cost; qvel clipped to +-10 in the observation."""
    velocity, where = _velocity(layout.qpos[0], dt), layout.where(z=(1, p["_qpos0"][1]))

    @_shared
    def terms(before: Rows, actions: np.ndarray, after: Rows) -> Tuple[Any, ...]:
        v = velocity(before, after)
        survive = healthy(after) * p["healthy_reward"]
        return v, p["forward_reward_weight"] * v, survive, _ctrl_cost(p["ctrl_cost_weight"], actions)

    def reward(before: Rows, actions: np.ndarray, after: Rows) -> Any:
        _, forward, survive, ctrl = terms(before, actions, after)
        return (forward + survive) - ctrl

    def step(before: Rows, actions: np.ndarray, after: Rows) -> Info:
        v, forward, survive, ctrl = terms(before, actions, after)
        return where(after) | {
            "x_velocity": v,
            "reward_forward": forward,
            "reward_ctrl": -ctrl,
            "reward_survive": survive,
        }

    terminate = (lambda after: ~healthy(after)) if p["terminate_when_unhealthy"] else None
    observe = layout.observe(1 if p["exclude_current_positions_from_observation"] else 0, 10.0)
    return _parts(observe, reward, terminate, step, where)


def _between(low_high: Tuple[float, float], values: np.ndarray) -> np.ndarray:
    low, high = low_high
    return np.logical_and(low < values, values < high)


def hopper(p: Mapping[str, Any], layout: Layout, dt: float) -> Tuple[Any, ...]:
    @_once
    def healthy(rows: Rows) -> Any:  # z, angle = qpos[1:3]; the state past x and z in range
        state = np.concatenate((rows[:, layout.qpos], rows[:, layout.qvel]), axis=1)[:, 2:]
        in_range = np.all(_between(p["healthy_state_range"], state), axis=1)
        z, angle = rows[:, layout.qpos[1]], rows[:, layout.qpos[2]]
        return in_range & _between(p["healthy_z_range"], z) & _between(p["healthy_angle_range"], angle)

    return _hopping(p, layout, dt, healthy)


def walker(p: Mapping[str, Any], layout: Layout, dt: float) -> Tuple[Any, ...]:
    @_once
    def healthy(rows: Rows) -> Any:
        z, angle = rows[:, layout.qpos[1]], rows[:, layout.qpos[2]]
        return _between(p["healthy_z_range"], z) & _between(p["healthy_angle_range"], angle)

    return _hopping(p, layout, dt, healthy)


def _walking(terms: Callable[..., Tuple[Any, ...]], where: Callable[[Rows], Info]) -> Tuple[Any, Any]:
    """Ant's and Humanoid's reward, (forward + healthy) - (ctrl + contact cost), and info keys, from their terms
    (the xy velocity, forward reward, healthy reward, ctrl cost, contact cost)."""

    def reward(before: Rows, actions: np.ndarray, after: Rows) -> Any:
        _, forward, survive, ctrl, contact = terms(before, actions, after)
        return (forward + survive) - (ctrl + contact)

    def step(before: Rows, actions: np.ndarray, after: Rows) -> Info:
        v, forward, survive, ctrl, contact = terms(before, actions, after)
        out = where(after) | {"x_velocity": v[:, 0], "y_velocity": v[:, 1], "reward_forward": forward}
        return out | {"reward_ctrl": -ctrl, "reward_contact": -contact, "reward_survive": survive}

    return reward, step


def ant(p: Mapping[str, Any], layout: Layout, dt: float) -> Tuple[Any, ...]:
    """Ant: (forward + healthy) - (ctrl + contact cost), from the main body's xpos and every body's cfrc_ext as
    the last step left them (data_at_step); cfrc_ext clipped to contact_force_range in the cost and the
    observation (bodies after the world)."""
    velocity, forces = _velocity(layout.data["xpos"][:2], dt), layout.data["cfrc_ext"]
    skip = 2 if p["exclude_current_positions_from_observation"] else 0
    low, high = p["contact_force_range"]
    state = np.concatenate((layout.qpos, layout.qvel))
    z, where = layout.qpos[2], layout.where(y=True)

    @_once
    def healthy(rows: Rows) -> Any:
        return (
            np.isfinite(rows[:, state]).all(axis=1)
            & (p["healthy_z_range"][0] <= rows[:, z])
            & (rows[:, z] <= p["healthy_z_range"][1])
        )

    @_shared
    def terms(before: Rows, actions: np.ndarray, after: Rows) -> Tuple[Any, ...]:
        v = velocity(before, after)
        contact = p["contact_cost_weight"] * _sum_of_squares(np.clip(after[:, forces], low, high))
        survive = healthy(after) * p["healthy_reward"]
        return v, v[:, 0] * p["forward_reward_weight"], survive, _ctrl_cost(p["ctrl_cost_weight"], actions), contact

    reward, step = _walking(terms, where)

    positions, velocities = layout.qpos[skip:], layout.qvel
    observed = np.concatenate((positions, velocities, forces[6:] if p["include_cfrc_ext_in_observation"] else []))
    observed = observed.astype(int)
    clipped = len(positions) + len(velocities)  # (the contact forces after it)

    def observe(rows: Rows) -> np.ndarray:
        out = rows[:, observed]
        out[:, clipped:] = np.clip(out[:, clipped:], low, high)
        return out

    terminate = (lambda after: ~healthy(after)) if p["terminate_when_unhealthy"] else None
    return _parts(_named(observe, tuple(layout.names[i] for i in observed)), reward, terminate, step, where)


def ant_data(p: Mapping[str, Any], model: _core.Model) -> Data:
    return [("xpos", str(p["main_body"]), 3)] + [("cfrc_ext", str(b), 6) for b in range(model.nbody)]


def _humanoid_observe(p: Mapping[str, Any], layout: Layout) -> Callable[[Rows], np.ndarray]:
    """Humanoid's and HumanoidStandup's observation: qpos (past x and y), qvel, then cinert, cvel, qfrc_actuator
    past the root and cfrc_ext, each of the bodies after the world, as the last step left them."""
    parts = [layout.qpos[2 if p["exclude_current_positions_from_observation"] else 0 :], layout.qvel]
    for array, width in (("cinert", 10), ("cvel", 6), ("qfrc_actuator", 0), ("cfrc_ext", 6)):
        if p[f"include_{array}_in_observation"]:
            parts.append(layout.data[array][width:])  # (after the world body; qfrc_actuator: the joints past the root)
    observed = np.concatenate(parts)
    return _named(lambda rows: rows[:, observed], tuple(layout.names[i] for i in observed))


def humanoid(p: Mapping[str, Any], layout: Layout, dt: float) -> Tuple[Any, ...]:
    """Humanoid: (forward + healthy) - (ctrl + contact cost), forward from the mass centre (body masses times
    xipos, as the last step left them)."""
    mass = p["_body_mass"]
    xipos, cfrc = layout.data["xipos"], layout.data["cfrc_ext"]
    z, where = layout.qpos[2], layout.where(y=True)

    def mass_center(rows: Rows) -> Any:
        centres = np.einsum("b,nbj->nj", mass, rows[:, xipos].reshape(len(rows), -1, 3))
        return (centres / mass.sum())[:, 0:2]

    @_once
    def healthy(rows: Rows) -> Any:
        low, high = p["healthy_z_range"]
        return (low < rows[:, z]) & (rows[:, z] < high)

    @_shared
    def terms(before: Rows, actions: np.ndarray, after: Rows) -> Tuple[Any, ...]:
        v = (mass_center(after) - mass_center(before)) / dt
        survive = healthy(after) * p["healthy_reward"]
        contact = np.clip(p["contact_cost_weight"] * _sum_of_squares(after[:, cfrc]), *p["contact_cost_range"])
        return v, p["forward_reward_weight"] * v[:, 0], survive, _ctrl_cost(p["ctrl_cost_weight"], actions), contact

    reward, step = _walking(terms, where)

    terminate = (lambda after: ~healthy(after)) if p["terminate_when_unhealthy"] else None
    return _parts(_humanoid_observe(p, layout), reward, terminate, step, where)


def humanoid_standup(p: Mapping[str, Any], layout: Layout, dt: float) -> Tuple[Any, ...]:
    """HumanoidStandup: the torso's height over the physics timestep (not dt, as Gymnasium's) - ctrl cost -
    impact cost (every body's cfrc_ext, clipped) + 1; never terminated; Humanoid's observation."""
    cfrc, z, timestep = layout.data["cfrc_ext"], layout.qpos[2], p["_timestep"]
    where = layout.where(y=True, z=(2, p["_qpos0"][2]))

    @_shared
    def terms(before: Rows, actions: np.ndarray, after: Rows) -> Tuple[Any, ...]:
        uph = (after[:, z] - 0) / timestep
        impact = np.clip(p["impact_cost_weight"] * _sum_of_squares(after[:, cfrc]), *p["impact_cost_range"])
        return uph, _ctrl_cost(p["ctrl_cost_weight"], actions), impact

    def reward(before: Rows, actions: np.ndarray, after: Rows) -> Any:
        uph, ctrl, impact = terms(before, actions, after)
        return uph - ctrl - impact + 1

    def step(before: Rows, actions: np.ndarray, after: Rows) -> Info:
        uph, ctrl, impact = terms(before, actions, after)
        return where(after) | {"reward_linup": uph, "reward_quadctrl": -ctrl, "reward_impact": -impact}

    return _parts(_humanoid_observe(p, layout), reward, None, step, where)


def humanoid_data(p: Mapping[str, Any], model: _core.Model, standup: bool = False) -> Data:
    bodies = [str(b) for b in range(model.nbody)]
    joints = [(str(j), model.object_info("joint", j)["nv"]) for j in range(1, model.njnt)]
    tendons = [str(t) for t in range(len(model.names("tendon")))]
    return (
        ([] if standup else [("xipos", b, 3) for b in bodies])  # (Humanoid's mass centre)
        + [("cinert", b, 10) for b in bodies]
        + [("cvel", b, 6) for b in bodies]
        + [("qfrc_actuator", j, nv) for j, nv in joints]
        + [("cfrc_ext", b, 6) for b in bodies]
        + [("ten_length", t, 1) for t in tendons]
        + [("ten_velocity", t, 1) for t in tendons]
    )


def _no_info(rows: Rows) -> Info:
    return {}


def inverted_pendulum(p: Mapping[str, Any], layout: Layout, dt: float) -> Tuple[Any, ...]:
    """Reward 1 while upright; terminated when the observation is not finite or the pole's angle past 0.2 rad."""
    observe = layout.observe(0)

    @_once
    def fallen(rows: Rows) -> Any:
        obs = observe(rows)
        return ~np.isfinite(obs).all(axis=1) | (np.abs(obs[:, 1]) > 0.2)

    def step(before: Rows, actions: np.ndarray, after: Rows) -> Info:
        return {"reward_survive": (~fallen(after)).astype(np.int64)}  # (Gymnasium's is an int)

    reward = lambda before, actions, after: (~fallen(after)).astype(np.float64)  # noqa: E731
    return _parts(observe, reward, fallen, step, _no_info)


def inverted_double_pendulum(p: Mapping[str, Any], layout: Layout, dt: float) -> Tuple[Any, ...]:
    """InvertedDoublePendulum: observed are the cart's position, the sines and cosines of the two angles, qvel and
    the cart's qfrc_constraint (both clipped to +-10); the tip site's x and z (as the last step left them) give the
    distance penalty, z <= 1 ends the episode; reward: healthy_reward while not ended - distance - velocity penalty."""
    qpos, qvel = layout.qpos, layout.qvel
    tip, constraint = layout.data["site_xpos"], layout.data["qfrc_constraint"][:1]

    def observe(rows: Rows) -> np.ndarray:
        angles = rows[:, qpos[1:]]
        clipped = np.clip(rows[:, np.concatenate((qvel, constraint))], -10, 10)
        return np.concatenate((rows[:, qpos[:1]], np.sin(angles), np.cos(angles), clipped), axis=1)

    angles = [layout.names[i] for i in qpos[1:]]
    names = [layout.names[qpos[0]]] + [f"sin_{a}" for a in angles] + [f"cos_{a}" for a in angles]
    names += [layout.names[i] for i in qvel] + [layout.names[constraint[0]]]

    def fallen(rows: Rows) -> Any:
        return rows[:, tip[2]] <= 1

    @_shared
    def terms(before: Rows, actions: np.ndarray, after: Rows) -> Tuple[Any, ...]:
        x, y = after[:, tip[0]], after[:, tip[2]]
        v1, v2 = after[:, qvel[1]], after[:, qvel[2]]
        # Gymnasium squares numpy scalars, by C's pow: float_power is it for arrays (** 2 multiplies, not always
        # the same last bit)
        distance = 0.01 * np.float_power(x, 2) + np.float_power(y - 2, 2)
        velocity = 1e-3 * np.float_power(v1, 2) + 5e-3 * np.float_power(v2, 2)
        return p["healthy_reward"] * (~fallen(after)).astype(np.int64), distance, velocity

    def reward(before: Rows, actions: np.ndarray, after: Rows) -> Any:
        alive, distance, velocity = terms(before, actions, after)
        return alive - distance - velocity

    def step(before: Rows, actions: np.ndarray, after: Rows) -> Info:
        alive, distance, velocity = terms(before, actions, after)
        return {"reward_survive": alive, "distance_penalty": -distance, "velocity_penalty": -velocity}

    return _parts(_named(observe, tuple(names)), reward, fallen, step, _no_info)
