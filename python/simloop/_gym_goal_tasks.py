"""Gymnasium's v5 goal tasks, Reacher and Pusher, as arithmetic on a batch of recorded rows (as _gym_task_families
for the others): observe, reward and info keys from the rows, the bodies' xpos they record (as the last step left
them, where Gymnasium's get_body_com reads them), and the on_reset hook that draws each episode's start and goal
from the hook's generator, in the shapes and distributions of Gymnasium's reset_model (not its np_random stream)."""

from __future__ import annotations

from typing import Any, Callable, Mapping, Tuple

import numpy as np

from . import _core
from ._gym_task_families import Data, Info, Layout, Rows, _named, _parts, _shared, _sum_of_squares
from .physics import StartPhysics

Hook = Callable[[np.random.Generator, StartPhysics], None]


def _bodies(model: _core.Model, *names: str) -> Data:
    bodies = model.names("body")
    return [("xpos", str(bodies.index(name)), 3) for name in names]


def _distance(rows: Rows, a: np.ndarray, b: np.ndarray) -> Any:
    """Each row's norm of xpos[a] - xpos[b], as np.linalg.norm takes it (a BLAS dot product: vecdot's, of
    contiguous rows)."""
    vec = rows[:, a] - rows[:, b]
    return np.sqrt(np.vecdot(vec, vec))


def _no_info(rows: Rows) -> Info:
    return {}  # (Gymnasium's reset info is empty for both)


def reacher(p: Mapping[str, Any], layout: Layout, dt: float) -> Tuple[Any, ...]:
    """Reacher: cos and sin of the two arm angles, the target's qpos, the arm's qvel, fingertip - target (x, y);
    reward -|fingertip - target| * weight - sum(action^2) * weight, both from the state after the step (Gymnasium's
    v5 order: do_simulation, then the observation and the reward); never terminated."""
    qpos, qvel = layout.qpos, layout.qvel
    xpos = layout.data["xpos"]
    tip, target = xpos[:3], xpos[3:6]

    def observe(rows: Rows) -> np.ndarray:
        angles = rows[:, qpos[:2]]
        offset = rows[:, tip[:2]] - rows[:, target[:2]]
        return np.concatenate((np.cos(angles), np.sin(angles), rows[:, qpos[2:]], rows[:, qvel[:2]], offset), axis=1)

    arm = [layout.names[i] for i in qpos[:2]]
    names = [f"cos_{a}" for a in arm] + [f"sin_{a}" for a in arm] + [layout.names[i] for i in qpos[2:]]
    names += [layout.names[i] for i in qvel[:2]] + ["fingertip_to_target_x", "fingertip_to_target_y"]

    @_shared
    def terms(before: Rows, actions: np.ndarray, after: Rows) -> Tuple[Any, ...]:
        dist = -_distance(after, tip, target) * p["reward_dist_weight"]
        return dist, -_sum_of_squares(actions) * p["reward_control_weight"]

    def reward(before: Rows, actions: np.ndarray, after: Rows) -> Any:
        dist, ctrl = terms(before, actions, after)
        return dist + ctrl

    def step(before: Rows, actions: np.ndarray, after: Rows) -> Info:
        dist, ctrl = terms(before, actions, after)
        return {"reward_dist": dist, "reward_ctrl": ctrl}

    return _parts(_named(observe, tuple(names)), reward, None, step, _no_info)


def reacher_data(p: Mapping[str, Any], model: _core.Model) -> Data:
    return _bodies(model, "fingertip", "target")


def reacher_reset(p: Mapping[str, Any]) -> Hook:
    """The arm's qpos off the XML's by uniform(-0.1, 0.1), the target (the last two qpos) drawn uniform in
    +-0.2 until inside the disc of radius 0.2; qvel uniform(-0.005, 0.005), the target's 0."""
    qpos0 = p["_qpos0"]

    def on_reset(rng: np.random.Generator, physics: StartPhysics) -> None:
        qpos = rng.uniform(-0.1, 0.1, len(qpos0)) + qpos0
        while True:
            goal = rng.uniform(-0.2, 0.2, 2)
            if np.linalg.norm(goal) < 0.2:
                break
        qpos[-2:] = goal
        qvel = rng.uniform(-0.005, 0.005, p["_nv"])
        qvel[-2:] = 0
        physics.named.data.qpos[:] = qpos
        physics.named.data.qvel[:] = qvel

    return on_reset


def pusher(p: Mapping[str, Any], layout: Layout, dt: float) -> Tuple[Any, ...]:
    """Pusher: the arm's 7 qpos and qvel, then the xpos of tips_arm, object and goal; reward (dist + ctrl) + near,
    dist and near the object's distance to the goal and to the arm's tip, from the state after the step; never
    terminated."""
    qpos, qvel, xpos = layout.qpos[:7], layout.qvel[:7], layout.data["xpos"]
    tips, cylinder, goal = xpos[:3], xpos[3:6], xpos[6:9]
    observed = np.concatenate((qpos, qvel, xpos))

    @_shared
    def terms(before: Rows, actions: np.ndarray, after: Rows) -> Tuple[Any, ...]:
        near = -_distance(after, cylinder, tips) * p["reward_near_weight"]
        dist = -_distance(after, cylinder, goal) * p["reward_dist_weight"]
        return near, dist, -_sum_of_squares(actions) * p["reward_control_weight"]

    def reward(before: Rows, actions: np.ndarray, after: Rows) -> Any:
        near, dist, ctrl = terms(before, actions, after)
        return dist + ctrl + near

    def step(before: Rows, actions: np.ndarray, after: Rows) -> Info:
        near, dist, ctrl = terms(before, actions, after)
        return {"reward_dist": dist, "reward_ctrl": ctrl, "reward_near": near}

    observe = _named(lambda rows: rows[:, observed], tuple(layout.names[i] for i in observed))
    return _parts(observe, reward, None, step, _no_info)


def pusher_data(p: Mapping[str, Any], model: _core.Model) -> Data:
    return _bodies(model, "tips_arm", "object", "goal")


def pusher_reset(p: Mapping[str, Any]) -> Hook:
    """qpos the XML's but the object's (qpos[-4:-2], drawn x in [-0.3, 0) and y in [-0.2, 0.2) until farther than
    0.17 from the goal) and the goal's (qpos[-2:], 0 0); qvel uniform(-0.005, 0.005), the object's and goal's 0."""
    qpos0, goal = p["_qpos0"], np.zeros(2)

    def on_reset(rng: np.random.Generator, physics: StartPhysics) -> None:
        qpos = qpos0.copy()
        while True:
            cylinder = np.concatenate((rng.uniform(-0.3, 0, 1), rng.uniform(-0.2, 0.2, 1)))
            if np.linalg.norm(cylinder - goal) > 0.17:
                break
        qpos[-4:-2], qpos[-2:] = cylinder, goal
        qvel = rng.uniform(-0.005, 0.005, p["_nv"])
        qvel[-4:] = 0
        physics.named.data.qpos[:] = qpos
        physics.named.data.qvel[:] = qvel

    return on_reset
