"""Sim.named: every array of MuJoCo's mjModel and mjData, its rows by name,
as dm_control's physics.named does.

    sim.named.data.xpos["box"]                  # a body's position (a view)
    sim.named.data.qpos["pusher_slide"]         # a joint's slice of qpos
    sim.named.data.efc_force                    # the constraint forces, this step's rows
    sim.named.model.geom_friction["floor"]      # read-only...
    sim.named.model.geom_friction["floor"] = [0.5, 0.005, 0.0001]  # ...but randomisable: written

A NamedArray is a numpy view (np.asarray(it), or .array) whose first index
also takes names: of the objects its rows are ("nbody" rows: bodies, "ngeom":
geoms, ...), of joints for the nq rows (a joint's positions) and the nv
rows (its velocities), and of sensors for sensordata (a sensor's values);
a list of names takes their rows in turn (qpos[["hip", "knee"]]).
Names are resolved once per array, so a named read costs about what a numpy
one does.

What can be written: mjData's inputs and state (qpos, qvel, ctrl, act,
qfrc_applied, xfrc_applied); of mjModel, the parameters a trainer randomises
(masses, inertias, friction, contact softness, margins, damping, armature,
stiffness, actuator gears, gains, biases and ranges, colours): the first
write gives the Sim a model of its own (other Sims and runs keep theirs).
The rest is read-only (MuJoCo derives it, or changing it would leave the
model inconsistent). The contacts' and constraints' arrays (efc_*) hold
this step's rows: take them again after stepping. cacc, cfrc_int and
cfrc_ext (mj_rnePostConstraint), subtree_linvel and subtree_angmom
(mj_subtreeVel), which no step computes, are filled each time they are
taken: take them again after stepping too.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Callable, Dict, List, Mapping, Optional, Protocol, Sequence, Tuple, Union

from . import _core
from ._checks import _describe, _did_you_mean

if TYPE_CHECKING:
    from numpy.typing import NDArray

# mjData's arrays a Sim lets a caller write (its views, Sim.qpos and the like).
_WRITABLE_DATA = ("qpos", "qvel", "ctrl", "act", "qfrc_applied", "xfrc_applied", "mocap_pos", "mocap_quat")
Key = Union[str, int, slice, Sequence[Union[str, int]], Tuple[Any, ...]]


class NamedArray:
    """One of MuJoCo's arrays with its rows by name; see the module's documentation."""

    __slots__ = ("name", "_view", "_rows", "_write")

    def __init__(
        self, name: str, view: "NDArray[Any]", rows: Mapping[str, Union[int, slice]], write: Optional[Any] = None
    ) -> None:
        self.name = name
        self._view = view
        self._rows = rows  # a row's name -> its index (or its slice of nq / nv rows)
        self._write = write  # for a randomisable model array: gets the writable view

    @property
    def array(self) -> "NDArray[Any]":
        """The whole array: a numpy view."""
        return self._view

    @property
    def names(self) -> Tuple[str, ...]:
        """The names its rows may be indexed by."""
        return tuple(self._rows)

    def __array__(self, dtype: Any = None, copy: Optional[bool] = None) -> "NDArray[Any]":
        import numpy as np

        return np.asarray(self._view, dtype=dtype) if copy is None else np.array(self._view, dtype=dtype, copy=copy)

    def __len__(self) -> int:
        return len(self._view)

    @property
    def shape(self) -> Tuple[int, ...]:
        return tuple(self._view.shape)

    def _index(self, key: Any) -> Any:
        if isinstance(key, tuple):
            return (self._index(key[0]),) + key[1:] if key else key
        if isinstance(key, str):
            try:
                return self._rows[key]
            except KeyError:
                raise KeyError(self._unknown(key)) from None
        if isinstance(key, list) and any(isinstance(k, str) for k in key):
            return [row for k in key for row in self._rows_of(k)]
        return key

    def _rows_of(self, key: Union[str, int]) -> List[int]:
        """A list's item as rows: a name's row, or all its rows in order (a
        joint's of qpos, a sensor's of sensordata), as dm_control's named does."""
        row = self._index(key)
        if isinstance(row, slice):
            return list(range(len(self._view))[row])
        return [int(row)]

    def _unknown(self, key: str) -> str:
        if not self._rows:
            return f"{self.name}'s rows have no names: index them by number (0 to {len(self._view) - 1})"
        shown = ", ".join(list(self._rows)[:20]) + (", ..." if len(self._rows) > 20 else "")
        return f"{self.name} has no row named {key!r}{_did_you_mean(key, self._rows)}; its rows: {shown}"

    def __getitem__(self, key: Key) -> Any:
        return self._view[self._index(key)]

    def __setitem__(self, key: Key, value: object) -> None:
        import numpy as np

        if self._write is None:
            raise ValueError(f"{self.name} is read-only here (see simloop.named: what can be written)")
        view = self._write()
        index = self._index(key)
        values = np.asarray(value, dtype=view.dtype)
        if values.dtype.kind == "f" and not np.isfinite(values).all():
            raise ValueError(f"{self.name}[{key!r}] must be finite, got {_describe(value)}")
        if self.name in _core.NONNEGATIVE_MODEL_FIELDS and (values < 0).any():  # (the C++ rule's list)
            raise ValueError(f"{self.name}[{key!r}] must be >= 0, got {_describe(value)}")
        view[index] = values
        self._view = view

    def __repr__(self) -> str:
        return f"<NamedArray {self.name} {self._view.dtype}{list(self._view.shape)}>"


def _rows_by_name(model: _core.Model, rows_count: str, kind: str) -> Dict[str, Union[int, slice]]:
    """Each named row: the objects of `kind`, a joint's slice of the nq / nv rows, a sensor's of sensordata's, or a
    mocap body's row of mocap_pos and mocap_quat."""
    if kind:
        return {name: i for i, name in enumerate(model.names(kind)) if name}
    if rows_count == "nsensordata":
        sensors = [model.object_info("sensor", s) for s in range(model.nsensor)]
        return {name: slice(s["adr"], s["adr"] + s["dim"]) for name, s in zip(model.names("sensor"), sensors) if name}
    if rows_count in ("nq", "nv"):
        rows: Dict[str, Union[int, slice]] = {}
        for j, name in enumerate(model.names("joint")):
            if not name:
                continue
            info = model.object_info("joint", j)
            start, count = (info["qposadr"], info["nq"]) if rows_count == "nq" else (info["dofadr"], info["nv"])
            rows[name] = slice(start, start + count)
        return rows
    if rows_count == "nmocap":  # mocap_pos, mocap_quat: a row per mocap body, in body_mocapid's order
        bodies = [(name, model.object_info("body", b)["mocapid"]) for b, name in enumerate(model.names("body"))]
        return {name: mocap for name, mocap in bodies if name and mocap >= 0}
    return {}


class _Source(Protocol):
    """What named reads: a Sim (_core.Sim), or an environment's episode (simloop.physics)."""

    @property
    def model(self) -> _core.Model: ...
    def field_rows(self, owner: str, name: str) -> Tuple[str, str]: ...
    def data_field(self, name: str) -> "NDArray[Any]": ...
    def model_field(self, name: str, writable: bool) -> "NDArray[Any]": ...


class _Owner:
    """sim.named.model or sim.named.data: its arrays as attributes."""

    def __init__(
        self,
        sim: _Source,
        views: Mapping[str, "NDArray[Any]"],
        owner: str,
        names: Sequence[str],
        refuse: Optional[Callable[[str], Any]] = None,
    ) -> None:
        self._sim = sim
        self._views = views
        self._owner = owner
        self._names = names
        self._refuse = refuse  # a read-only state's (a hook's physics): raises for a write to the array named
        self._rows: Dict[str, Dict[str, Union[int, slice]]] = {}  # resolved once per array

    def __dir__(self) -> List[str]:
        return list(self._names)

    def _refusal(self, name: str) -> Optional[Callable[[], Any]]:
        refuse = self._refuse
        return None if refuse is None else lambda: refuse(name)

    def __getattr__(self, name: str) -> NamedArray:
        if name.startswith("_") or name not in self._names:
            raise AttributeError(
                f"mj{self._owner.capitalize()} has no array named {name!r}{_did_you_mean(name, self._names)}"
            )
        sim = self._sim
        if name not in self._rows:
            rows_count, kind = sim.field_rows(self._owner, name)
            self._rows[name] = _rows_by_name(sim.model, rows_count, kind)
        rows = self._rows[name]
        if self._owner == "data":
            if name in _WRITABLE_DATA and name in self._views:
                return NamedArray(name, self._views[name], rows, lambda: self._views[name])
            return NamedArray(name, sim.data_field(name), rows, self._refusal(name))
        if self._refuse is None and name in _core.WRITABLE_MODEL_FIELDS:
            return NamedArray(name, sim.model_field(name, False), rows, lambda: sim.model_field(name, True))
        return NamedArray(name, sim.model_field(name, False), rows, self._refusal(name))


class Named:
    """sim.named: .model and .data, MuJoCo's arrays with rows by name. views:
    the writable mjData arrays (a Sim's); refuse: for a read-only state, what
    a write to an array raises (given its name)."""

    def __init__(
        self, sim: _Source, views: Mapping[str, "NDArray[Any]"], refuse: Optional[Callable[[str], Any]] = None
    ) -> None:
        self.model = _Owner(sim, views, "model", _core.MODEL_FIELD_NAMES, refuse)
        self.data = _Owner(sim, views, "data", _core.DATA_FIELD_NAMES, refuse)
