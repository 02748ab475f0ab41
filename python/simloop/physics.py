"""Physics: an environment's MuJoCo state by name, read-only, for its reward
and terminate hooks, as dm_control's physics.named reads it; StartPhysics:
an episode's start for its on_reset hook, its state writable.

    def reward(obs, action, next_obs, physics):
        return -float(np.linalg.norm(physics.named.data.site_xpos["tip"] - goal))

physics.named.data and physics.named.model are simloop.named's (every
mjData and mjModel array, rows by name: bodies, joints, sites, sensors...)
over that env's episode, at the moment the hook runs: the state next_obs
observes, everything MuJoCo derives from it current (the env then takes a
whole forward pass per decision instead of the first half of the next
step; the observations' bits are the same). cacc, cfrc_int, cfrc_ext,
subtree_linvel and subtree_angmom, which no step computes, are filled
(mj_rnePostConstraint, mj_subtreeVel) when taken. Each access reads the
state afresh: take what you need inside the hook, not across steps (the
contacts' and constraints' rows change). Writing raises ValueError: the
state is the episode's, changed only by its actions and its reset.

StartPhysics is the same over an episode's start while its on_reset hook
runs (after the scenario's [reset] and the reset options, before the first
observation): qpos, qvel, act, ctrl, mocap_pos and mocap_quat may be
written (START_WRITABLE); everything else, the model too, is read-only.
Derived arrays (xpos, ...) are the start's before the hook's writes: the
start is derived again (mj_forward) once the hook returns.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, NoReturn, Tuple

from . import _core
from .named import Named

if TYPE_CHECKING:
    from numpy.typing import NDArray


class _EpisodeSource:
    """What named reads, for episode i of an Episodes (staged: the start its on_reset hook is shaping)."""

    __slots__ = ("_episodes", "_i", "_staged")

    def __init__(self, episodes: _core.Episodes, i: int, staged: bool = False) -> None:
        self._episodes = episodes
        self._i = i
        self._staged = staged

    @property
    def model(self) -> _core.Model:
        return self._episodes.model_of(self._i, self._staged)

    def field_rows(self, owner: str, name: str) -> Tuple[str, str]:
        return self._episodes.field_rows(owner, name)

    def data_field(self, name: str) -> "NDArray[Any]":
        view = self._episodes.data_field(self._i, name, self._staged)
        if self._staged:  # (a staged start's is writable: the arrays to write are START_WRITABLE's views)
            view.flags.writeable = False
        return view

    def model_field(self, name: str, writable: bool) -> "NDArray[Any]":
        return self._episodes.model_field(self._i, name, self._staged)


# The arrays an on_reset hook may write: the start's state and inputs.
START_WRITABLE = ("qpos", "qvel", "act", "ctrl", "mocap_pos", "mocap_quat")


def _refuse_at_start(name: str) -> NoReturn:
    raise ValueError(
        f"physics in an on_reset hook may write {', '.join(START_WRITABLE)}: {name} is read-only "
        "(MuJoCo derives it from those, or it is the model's)"
    )


def _refuse(name: str) -> NoReturn:
    raise ValueError(
        f"physics is read-only in a reward or terminate hook: {name} is the env's state as it is "
        "(change it through the actions, or at reset)"
    )


class Physics:
    """One env's state by name, read-only: physics.named.data.xpos["box"],
    physics.named.model.body_mass["box"] (see the module's documentation)."""

    __slots__ = ("named",)

    def __init__(self, episodes: _core.Episodes, i: int) -> None:
        self.named = Named(_EpisodeSource(episodes, i), {}, _refuse)


class StartPhysics:
    """Episode i's start by name, for its on_reset hook: START_WRITABLE's
    arrays writable, the rest read-only (see the module's documentation).
    Valid while the hook runs."""

    __slots__ = ("named",)

    def __init__(self, episodes: _core.Episodes, i: int) -> None:
        views = {name: episodes.data_field(i, name, True) for name in START_WRITABLE}
        self.named = Named(_EpisodeSource(episodes, i, True), views, _refuse_at_start)
