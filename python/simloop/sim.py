"""simloop.Sim: the loop's rhythm, one call at a time, on any scene: write
ctrl, write forces, step, look (numpy views into MuJoCo's mjData, and the
scene's objects by name: _views).
"""

from __future__ import annotations

import numbers
from typing import TYPE_CHECKING, Any, Dict, List, Optional, Sequence, Union, cast

if TYPE_CHECKING:  # (importing numpy would cost every `import simloop` ~50 ms)
    import numpy as np
    from numpy.typing import NDArray

from . import _core
from ._checks import (
    I64_MAX,
    I64_MIN,
    ModelLike,
    Progress,
    _check_int,
    _check_progress,
    _check_real,
    _check_text,
    _describe,
    _finite_vector,
    _float_array,
    _sequence,
    _show,
    load_model,
)
from ._core import Model
from ._views import ActuatorView, BodyView, JointView, SensorView
from .named import Named
from .scenario import Scenario


def _view_property(name: str, doc: str, settable: bool = False) -> property:
    """A Sim property giving its view `name`; settable: assigning writes into the view (checked)."""

    def get(self: "Sim") -> NDArray[np.float64]:
        return self._views[name]

    def set(self: "Sim", value: object) -> None:
        self._set_array(name, value)

    return property(get, set if settable else None, doc=doc)


_ARRAYS = (
    "qpos",
    "qvel",
    "ctrl",
    "act",
    "qfrc_applied",
    "xfrc_applied",
    "mocap_pos",
    "mocap_quat",
    "sensordata",
    "actuator_force",
    "xpos",
    "xquat",
)


class Sim:
    """The loop's rhythm, one call at a time, on any scene: write ctrl, write forces, step, look.

        sim = simloop.Sim("tests/scenes/walker.xml")      # a Model, an MJCF path, a Scenario
        sim.ctrl[:] = 0.3                                   # or sim.step(100, ctrl=[...])
        sim.apply_force(body="torso", force=[0, 0, 20])     # persists until clear_forces()
        sim.step(100)
        sim.body("torso").xpos, sim.joint("hip").qpos, sim.sensor(0).data
        saved = sim.get_state(); ...; sim.set_state(saved)  # bit for bit

    Arrays. qpos, qvel, ctrl, act, qfrc_applied, xfrc_applied (nbody x 6), mocap_pos and mocap_quat
    are numpy VIEWS into MuJoCo's mjData, writable: a write takes effect at
    the next step, and what you hold changes when the Sim steps (copy it to
    keep it). sensordata is a read-only view. A view keeps its Sim alive, and
    the mjData never moves, so a view never dangles. Derived quantities (a
    body's xpos, xquat, velocity) are copies, as of the last step: MuJoCo
    computes them before integrating (under RK4, at its last stage);
    forward() brings them up to date without changing the run's bits.

    Threads. Each method call (step, reads, get/set_state, apply_force...)
    holds the Sim's lock, so calls from several threads take turns. The
    views do NOT take the lock: reading or writing one while another thread
    steps the Sim sees a half-written state. Share a Sim across threads
    through its methods, or give each thread its own copy (copy.copy(sim)).

    IMPORTANT: like MuJoCo's xfrc_applied, a force set with apply_force()
    PERSISTS. MuJoCo never clears it: it pushes on every following step until
    you clear it. ctrl persists the same way. Forgetting this is the
    chapter's classic bug (exercise 2).

    Sim(scenario) takes the scenario's scene and timestep only: you drive
    the loop (ctrl, forces); its controls and disturbances are not applied
    (run_scenario does that).

    The chapter's accessors (box_position, pusher_x, apply_force(force),
    clear_force, ...) need the chapter's layout (a body "box" on a free
    joint, actuator 0 on a slide or hinge joint); on another scene they
    raise ValueError saying what it lacks.

    copy.copy / copy.deepcopy give an independent Sim (its own data, the
    same read-only model); pickle carries the model, the full state and
    steps_taken (not MuJoCo's warnings).
    """

    def __init__(self, model: Union[ModelLike, "object"] = None, timestep: Optional[float] = None) -> None:
        if isinstance(model, Scenario):
            if timestep is None:
                timestep = model.timestep
            model = model.model()
        # load_model checks what model is at runtime (TypeError naming it).
        self._sim = _core.Sim(load_model(cast(ModelLike, model)))
        self._make_views()
        if timestep is not None:
            self.timestep = timestep

    def _make_views(self) -> None:
        self._views = {name: self._sim.array(name) for name in _ARRAYS}
        self._named: Optional[Named] = None
        self._layout: Optional[Dict[str, int]] = None  # the chapter's, found at its first use

    @classmethod
    def _wrapping(cls, core: "_core.Sim") -> "Sim":
        sim = cls.__new__(cls)
        sim._sim = core
        sim._make_views()
        return sim

    def __copy__(self) -> "Sim":
        return Sim._wrapping(self._sim.copy())

    def __deepcopy__(self, memo: Dict[int, Any]) -> "Sim":
        return Sim._wrapping(self._sim.copy())

    def __getstate__(self) -> Dict[str, Any]:
        return {"sim": self._sim}

    def __setstate__(self, state: Dict[str, Any]) -> None:
        self._sim = state["sim"]
        self._make_views()

    @property
    def model(self) -> Model:
        """This Sim's model (its own copy when the timestep was changed)."""
        return self._sim.model

    @property
    def timestep(self) -> float:
        """Sim seconds per step (this Sim's own copy of the model)."""
        return self._sim.timestep

    @timestep.setter
    def timestep(self, value: float) -> None:
        self._sim.set_timestep(_check_real("timestep", value))

    # --- The arrays (views; see the class docstring).

    def _set_array(self, name: str, value: object) -> None:
        view = self._views[name]
        view[:] = _finite_vector(name, value, view.size, f"{name} has {view.size} values")

    qpos = _view_property("qpos", "Joint positions (nq), a writable view.", settable=True)
    qvel = _view_property("qvel", "Joint velocities (nv), a writable view.", settable=True)

    @property
    def ctrl(self) -> Union[float, NDArray[np.float64]]:
        """The chapter's scene: the motor command ctrl[0], a float (MuJoCo clamps it to
        [-1, 1]). Any other scene: every actuator's ctrl (nu), a writable view."""
        if self.model.has_chapter_layout:
            return self._sim.ctrl
        return self._views["ctrl"]

    @ctrl.setter
    def ctrl(self, value: object) -> None:
        if isinstance(value, numbers.Real) and not isinstance(value, bool):
            nu = self.model.nu
            if nu != 1:  # one number for several actuators would set only the first
                raise ValueError(
                    f"ctrl must be {nu} numbers, one per actuator (a single number is for a scene "
                    f"with one actuator, as the chapter's), got {_show(value)}"
                )
            self._sim.set_ctrl(_check_real("ctrl", value))
        else:
            self._sim.set_ctrl_vector(self._vector("ctrl", value, self.model.nu, "one per actuator"))

    ctrl_array = _view_property("ctrl", "Every actuator's ctrl (nu), a writable view, on any scene.")
    act = _view_property("act", "Actuator activations (na), a writable view.")
    qfrc_applied = _view_property("qfrc_applied", "Generalized forces applied (nv), a writable view; it persists.")
    xfrc_applied = _view_property(
        "xfrc_applied", "Force and torque on each body, world frame (nbody x 6), a writable view; it persists."
    )
    mocap_pos = _view_property(
        "mocap_pos",
        "Where each mocap body is (nmocap x 3; row i is the body whose "
        "body_mocapid is i), a writable view: MuJoCo moves it there, no force.",
    )
    mocap_quat = _view_property("mocap_quat", "Each mocap body's orientation (nmocap x 4, w x y z), a writable view.")
    sensordata = _view_property(
        "sensordata", "Every sensor's reading (nsensordata), a read-only view, as of the last step."
    )

    # --- Named access.

    @property
    def named(self) -> Named:
        """Every array of MuJoCo's mjModel and mjData, rows by name:
        sim.named.data.xpos["box"], sim.named.model.geom_friction["floor"]
        (see simloop.named)."""
        if self._named is None:
            self._named = Named(self._sim, self._views)
        return self._named

    def _lookup(self, kind: str, key: object) -> "tuple[int, str]":
        if isinstance(key, str):
            name = _check_text(kind, key)  # ValueError for text UTF-8 cannot hold
            if b"\0" in name:
                raise ValueError(f"{kind} must not contain a NUL character, got {_show(key)}")
            # _check_text gives UTF-8 bytes, which pybind11's std::string takes as well as str.
            index = self._sim.id(kind, name)  # type: ignore[arg-type]
        elif isinstance(key, numbers.Integral) and not isinstance(key, bool):
            number = int(key)
            if not -(2**63) <= number < 2**63:
                plural = "bodies" if kind == "body" else kind + "s"
                raise ValueError(
                    f"{kind} index {_show(number)} is out of range: the scene has "
                    f"{len(self.model.names(kind))} {plural}"
                )
            index = self._sim.checked_index(kind, number)
        else:
            raise TypeError(f"{kind} must be a name (str) or an index (int), got {_describe(key)}")
        return index, self.model.names(kind)[index]

    def body(self, key: Union[str, int]) -> BodyView:
        """A body by name or index: xpos, xquat, linear/angular_velocity, mass, id."""
        return BodyView(self._sim, self._views, *self._lookup("body", key))

    def joint(self, key: Union[str, int]) -> JointView:
        """A joint by name or index: type, qpos and qvel (writable views)."""
        return JointView(self._sim, self._views, *self._lookup("joint", key))

    def actuator(self, key: Union[str, int]) -> ActuatorView:
        """An actuator by name or index: ctrl (a writable view), force, ctrlrange."""
        return ActuatorView(self._sim, self._views, *self._lookup("actuator", key))

    def sensor(self, key: Union[str, int]) -> SensorView:
        """A sensor by name or index: data (a read-only view)."""
        return SensorView(self._sim, self._views, *self._lookup("sensor", key))

    # --- Stepping.

    def step(self, n: int = 1, ctrl: Optional[object] = None, *, progress: Progress = None) -> None:
        """Advances n steps (1 to 2**62-1); with ctrl given, writes it first (it then persists).

        ctrl: a number (ctrl[0], the chapter's motor) or a vector of nu
        numbers (every actuator). Ctrl-C stops a long step promptly
        (KeyboardInterrupt; the steps taken stay taken). progress: as for run().
        """
        if ctrl is None:
            try:  # one call: the C++ Sim checks n's value
                return self._sim.step(n, progress)
            except TypeError:  # n or progress refused as given, or progress's own TypeError
                if type(n) is int and I64_MIN <= n <= I64_MAX and (progress is None or callable(progress)):
                    raise
        # n or progress to convert or name in one line (outside the except: no pybind11 message chained)
        count = _check_int("n", n)
        if ctrl is not None:
            self._sim.check_steps(count)  # before ctrl is written: a refused call changes nothing
            self.ctrl = ctrl
        self._sim.step(count, _check_progress(progress))

    def forward(self) -> None:
        """Brings xpos, xquat, velocities, sensordata and contacts up to the current
        qpos/qvel (mj_forward) without changing the next step's bits."""
        self._sim.forward()

    # --- Forces.

    def apply_force(
        self,
        force: Optional[Sequence[float]] = None,
        *,
        body: Union[str, int, None] = None,
        torque: Optional[Sequence[float]] = None,
    ) -> None:
        """Pushes with (fx, fy, fz) newtons and/or twists with (tx, ty, tz) N m, world
        frame, at the body's origin, from now on.

        body: a name or index; None is the chapter's box (force only). A part
        not given is left as it was. It PERSISTS until clear_forces() (or
        clear_force() for the box): MuJoCo does not reset it after a step.
        """
        if body is None:
            if torque is not None:
                raise ValueError("torque needs body=...: the chapter's apply_force(force) pushes the box only")
            if force is None:
                raise TypeError("apply_force needs a force (and body=... for a body other than the chapter's box)")
            components = self._force_components("force", force)
            self._sim.apply_wrench(self._chapter("box_body"), components, None)
            return
        index, _ = self._lookup("body", body)
        if force is None and torque is None:
            raise ValueError("apply_force needs force=..., torque=... or both")
        self._sim.apply_wrench(
            index,
            None if force is None else self._force_components("force", force),
            None if torque is None else self._force_components("torque", torque),
        )

    @staticmethod
    def _force_components(name: str, value: object) -> "list[float]":
        values = _sequence(name, value)
        if len(values) != 3:
            axes = "(fx, fy, fz)" if name == "force" else "(tx, ty, tz)"
            raise ValueError(f"{name} must have 3 components {axes}, got {len(values)}")
        return [_check_real("%s[%d]" % (name, i), v) for i, v in enumerate(values)]  # finite: the C++ Sim's check

    @staticmethod
    def _vector(name: str, value: object, size: int, what: str) -> NDArray[np.float64]:
        """A vector for the C++ Sim, which checks its length and values: a
        sequence or numeric numpy array, one-dimensional."""
        array = _float_array(name, value, size, what)
        if array.ndim != 1:
            raise ValueError(f"{name} must have shape ({size},) ({what}), got shape {array.shape}")
        return array

    def clear_force(self) -> None:
        """Stops pushing the chapter's box: writes zero into its xfrc_applied force."""
        self._sim.apply_wrench(self._chapter("box_body"), [0.0, 0.0, 0.0], None)

    def clear_forces(self) -> None:
        """Zeros every body's xfrc_applied (forces and torques)."""
        self._sim.clear_forces()

    @property
    def applied_force(self) -> NDArray[np.float64]:
        """The force now written on the chapter's box (a copy), N."""
        return self._sim.read("xfrc_applied", 6 * self._chapter("box_body"), 3)

    # --- State.

    def get_state(self, layout: str = "simloop") -> NDArray[np.float64]:
        """The full physics state as a flat float64 array (a copy), in simloop's
        layout (state_layout()); layout="mujoco": MuJoCo's own,
        mj_getState(m, d, s, mjSTATE_INTEGRATION) (MuJoCo 3.3 and later).
        set_state() of either continues bit for bit, here or in another Sim."""
        if layout not in ("simloop", "mujoco"):
            raise ValueError(f"layout must be 'simloop' or 'mujoco', got {layout!r}")
        return self._sim.get_state(layout == "mujoco")

    def set_state(self, state: object) -> None:
        """Restores a state: get_state()'s, or a buffer of MuJoCo's own
        mj_getState(m, d, s, mjSTATE_INTEGRATION), told apart by length (see
        docs/python.md). steps_taken and warnings are left as they are."""
        import numpy as np

        if not isinstance(state, np.ndarray):
            raise TypeError(f"state must be a numpy float64 array (from get_state()), got {_describe(state)}")
        if state.dtype != np.float64:
            raise ValueError(f"state must have dtype float64, got {state.dtype}")
        if state.ndim != 1:  # its length: the C++ Sim's check
            raise ValueError(f"state must be one-dimensional (state_size values), got shape {state.shape}")
        bad = np.flatnonzero(~np.isfinite(state))  # a check the C++ Sim does not make
        if bad.size:
            raise ValueError(f"state must be finite, got {float(state[bad[0]])!r} at index {int(bad[0])}")
        self._sim.set_state(np.ascontiguousarray(state))

    def state_layout(self) -> "list[tuple[str, int]]":
        """The state's parts in order with their sizes: [('time', 1), ('qpos', nq), ...]."""
        return [(name, int(size)) for name, size in self._sim.state_layout]

    @property
    def state_size(self) -> int:
        return sum(n for _, n in self.state_layout())

    def reset(self, keyframe: Union[str, int, None] = None) -> None:
        """Back to t = 0, or to a keyframe of the scene (a name or index): state,
        ctrl, forces, steps_taken and warnings reset (timestep kept)."""
        if keyframe is None:
            self._sim.reset()
        else:
            self._sim.reset_to_keyframe(self._lookup("keyframe", keyframe)[0])

    @property
    def time(self) -> float:
        return self._sim.time

    @property
    def steps_taken(self) -> int:
        return self._sim.steps_taken

    # --- The chapter's scene: its box's free joint and its pusher's joint, read
    # from the state now (qpos, qvel) in one locked call each.

    def _chapter(self, part: str) -> int:
        """Where a part of the chapter's scene is (Model.chapter_layout): ValueError
        naming what another scene lacks."""
        if self._layout is None:
            self._layout = self.model.chapter_layout
        return self._layout[part]

    @property
    def box_position(self) -> NDArray[np.float64]:
        """The box's position now (x, y, z), m: a copy."""
        return self._sim.read("qpos", self._chapter("box_qposadr"), 3)

    @property
    def box_quaternion(self) -> NDArray[np.float64]:
        """The box's orientation now, (w, x, y, z) as MuJoCo stores it: a copy."""
        return self._sim.read("qpos", self._chapter("box_qposadr") + 3, 4)

    @property
    def box_velocity(self) -> NDArray[np.float64]:
        """The box's linear velocity now, m/s, world frame: a copy."""
        return self._sim.read("qvel", self._chapter("box_dofadr"), 3)

    @property
    def pusher_x(self) -> float:
        """The pusher's slide-joint position, m."""
        return float(self._sim.read("qpos", self._chapter("pusher_qposadr"), 1)[0])

    @property
    def pusher_velocity(self) -> float:
        return float(self._sim.read("qvel", self._chapter("pusher_dofadr"), 1)[0])

    @property
    def contacts(self) -> List[_core.Contact]:
        """The contacts of MuJoCo's last collision pass: geom1, geom2 (an unnamed
        one as "geom12"), their ids, their bodies' names and ids, dist, pos, frame, force."""
        return self._sim.contacts

    @property
    def warnings(self) -> List[_core.MujocoWarning]:
        """Warnings MuJoCo raised since construction or reset."""
        return self._sim.warnings

    def __repr__(self) -> str:
        model = self.model
        scene = repr(model.name) if model.name else "(unnamed)"
        return (
            f"<simloop.Sim {scene} t={self.time!r} steps_taken={self.steps_taken} timestep={self.timestep!r} "
            f"nq={model.nq} nv={model.nv} nu={model.nu} nbody={model.nbody}>"
        )
