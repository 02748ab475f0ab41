"""A Sim's named objects: a body, joint, actuator or sensor of its scene, by
name or index (Sim.body("torso"), Sim.joint(0), ...), each reading its own
slices of the Sim's arrays.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Dict, Mapping, Optional, Tuple

from . import _core

if TYPE_CHECKING:  # (importing numpy would cost every `import simloop` ~50 ms)
    import numpy as np
    from numpy.typing import NDArray


class _Named:
    """One named object of a Sim's scene (base of the body, joint, actuator and sensor views)."""

    __slots__ = ("_sim", "_arrays", "id", "name")
    _kind = ""

    def __init__(self, sim: "_core.Sim", arrays: Mapping[str, NDArray[np.float64]], id: int, name: str) -> None:
        self._sim = sim  # the compiled Sim: a view keeps it alive
        self._arrays = arrays  # the Sim's numpy views into its mjData, by name
        self.id = id
        self.name = name

    def _info(self) -> Dict[str, Any]:
        return self._sim.model.object_info(self._kind, self.id)

    def __repr__(self) -> str:
        return f"<simloop.Sim {self._kind} {self.id} {self.name!r}{self._details()}>"

    def _details(self) -> str:
        return ""


class BodyView(_Named):
    """A body: pose and velocity (world frame, as of the last step or
    Sim.forward(): MuJoCo derives them before integrating), mass, and the
    force/torque applied to it (a writable view of its xfrc_applied row)."""

    __slots__ = ()
    _kind = "body"

    @property
    def xpos(self) -> NDArray[np.float64]:
        """Position of the body's frame, world, m (a copy)."""
        xpos: NDArray[np.float64] = self._arrays["xpos"][self.id].copy()
        return xpos

    @property
    def xquat(self) -> NDArray[np.float64]:
        """Orientation (w, x, y, z), world (a copy)."""
        xquat: NDArray[np.float64] = self._arrays["xquat"][self.id].copy()
        return xquat

    @property
    def angular_velocity(self) -> NDArray[np.float64]:
        """rad/s, world frame (from cvel, mj_objectVelocity)."""
        return self._sim.body_velocity(self.id)[:3]

    @property
    def linear_velocity(self) -> NDArray[np.float64]:
        """m/s of the body's origin, world frame (from cvel, mj_objectVelocity)."""
        return self._sim.body_velocity(self.id)[3:]

    @property
    def mass(self) -> float:
        mass: float = self._info()["mass"]
        return mass

    @property
    def xfrc_applied(self) -> NDArray[np.float64]:
        """(fx, fy, fz, tx, ty, tz) applied on this body: a writable view; it persists."""
        row: NDArray[np.float64] = self._arrays["xfrc_applied"][self.id]
        return row

    def _details(self) -> str:
        return f" mass={self.mass!r}"


class JointView(_Named):
    """A joint: its type and its slices of qpos and qvel (writable views)."""

    __slots__ = ()
    _kind = "joint"

    @property
    def type(self) -> str:
        """'free', 'ball', 'slide' or 'hinge'."""
        kind: str = self._info()["type"]
        return kind

    @property
    def qpos(self) -> NDArray[np.float64]:
        info = self._info()
        return self._arrays["qpos"][info["qposadr"] : info["qposadr"] + info["nq"]]

    @property
    def qvel(self) -> NDArray[np.float64]:
        info = self._info()
        return self._arrays["qvel"][info["dofadr"] : info["dofadr"] + info["nv"]]

    def _details(self) -> str:
        return f" type={self.type}"


class ActuatorView(_Named):
    """An actuator: its ctrl (a writable view of one value), the force it
    produced in the last step, and its ctrlrange."""

    __slots__ = ()
    _kind = "actuator"

    @property
    def ctrl(self) -> NDArray[np.float64]:
        return self._arrays["ctrl"][self.id : self.id + 1]

    @property
    def force(self) -> float:
        """actuator_force: its scalar force in the last step, before the gear (a motor: ctrl)."""
        return float(self._arrays["actuator_force"][self.id])

    @property
    def ctrlrange(self) -> Optional[Tuple[float, float]]:
        """(low, high) MuJoCo clamps ctrl to, or None if unlimited."""
        info = self._info()
        return info["ctrlrange"] if info["ctrllimited"] else None

    def _details(self) -> str:
        return f" ctrlrange={self.ctrlrange}"


class SensorView(_Named):
    """A sensor: its readings (a read-only view into sensordata)."""

    __slots__ = ()
    _kind = "sensor"

    @property
    def data(self) -> NDArray[np.float64]:
        info = self._info()
        return self._arrays["sensordata"][info["adr"] : info["adr"] + info["dim"]]
