"""Scenarios from Python: the chapter's loop on any scene, as data.

A scenario says what to run: the scene (an MJCF file, or the chapter's), the
timestep (the scene's own unless given), the length, the controls (intent),
the disturbances (interference) and what is recorded. It comes from a TOML
file, the same files sim_loop --scenario reads, or from keyword arguments,
which are written as such a file and read by the same (C++) parser, so both
are checked alike:

    >>> import simloop
    >>> s = simloop.Scenario(scene="tests/scenes/pusht.xml", steps=500,
    ...                      controls={"push_x": 0.8, "push_y": [(0.0, 0.0), (0.5, 0.4)]},
    ...                      disturbances=[dict(body="tblock", force=[0, 1, 0], start=0.6, duration=0.1)])
    >>> result = simloop.run_scenario(s, seed=0)
    >>> result.column("tblock_x")[-1]
"""

from __future__ import annotations

import math
import numbers
import os
from typing import Any, Dict, Iterable, Mapping, Optional, Sequence, Tuple, Union, cast

from . import _core
from ._checks import (
    ModelLike,
    _check_bool,
    _check_int,
    _check_keys,
    _check_path,
    _check_real,
    _check_seed,
    _check_str,
    _describe,
    load_model,
)

ScenarioResult = _core.ScenarioResult
ScenarioLike = Union["Scenario", str, "os.PathLike[str]"]


def _toml_string(name: str, text: str) -> str:
    """A TOML basic string. JSON's escapes are not all TOML's: JSON writes a
    character beyond U+FFFF as a surrogate pair, which TOML refuses."""
    out = ['"']
    for ch in text:
        code = ord(ch)
        if 0xD800 <= code <= 0xDFFF:  # a byte that was not UTF-8 (os.fsdecode's surrogateescape)
            raise ValueError(f"{name} must be text (UTF-8; a scenario file cannot hold other bytes), got {text!r}")
        if ch in '"\\':
            out.append("\\" + ch)
        elif code < 0x20 or code == 0x7F:
            out.append(f"\\u{code:04x}")
        else:
            out.append(ch)
    return "".join(out) + '"'


def _number(name: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name} must be a number, got {_describe(value)}")
    try:
        return float(value)
    except OverflowError:
        raise ValueError(f"{name} must be a finite number, got {_describe(value)}") from None


def _control_entry(actuator: object, value: object) -> Dict[str, object]:
    """{actuator, value} for a number, {actuator, schedule} for (seconds, value)
    pairs, {actuator, csv} for a CSV file (a path object), or the file's own
    keys from a dict ({"csv": ..., "column": ...})."""
    name = f"controls[{actuator!r}]"
    if isinstance(value, numbers.Real) and not isinstance(value, bool):
        return {"actuator": actuator, "value": _number(name, value)}
    if isinstance(value, os.PathLike):
        return {"actuator": actuator, "csv": value}  # a value per step, one row each
    if isinstance(value, Mapping):
        return {"actuator": actuator, **value}
    shape = (
        f"{name} must be a number, a list of (seconds, value) pairs, a path object naming a CSV file, "
        f"or {{'csv': ..., 'column': ...}}, got {_describe(value)}"
    )
    if isinstance(value, (str, bytes)) or not isinstance(value, Iterable):
        raise TypeError(shape)
    pairs = []
    for pair in value:
        try:
            if isinstance(pair, (str, bytes)):
                raise TypeError
            seconds, ctrl = pair  # a tuple, a list, a numpy row
        except (TypeError, ValueError):
            raise TypeError(shape) from None
        pairs.append([_number(name, seconds), _number(name, ctrl)])
    return {"actuator": actuator, "schedule": pairs}


# The deepest list a scenario holds is two ([[seconds, value], ...]); past this a "list" holds itself (UserString).
_MAX_NESTING = 8


def _toml_value(name: str, value: object, depth: int = 0) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    # int() and float(): a subclass (numpy's float64, an IntEnum) has a repr of its own, which TOML is not.
    if isinstance(value, int):
        return str(int(value))
    if isinstance(value, float):
        if not math.isfinite(value):
            raise ValueError(f"{name} must be finite, got {value!r}")
        return repr(float(value))
    if isinstance(value, _Inline):
        return str(value)
    if isinstance(value, (str, bytes, os.PathLike)):
        return _toml_string(name, os.fsdecode(value))
    if isinstance(value, Sequence) and depth < _MAX_NESTING:
        return "[" + ", ".join(_toml_value(name, v, depth + 1) for v in value) + "]"
    if hasattr(value, "tolist") and depth < _MAX_NESTING:  # numpy scalars and arrays
        return _toml_value(name, value.tolist(), depth + 1)
    raise TypeError(f"{name} must be a number, a string or a list of them, got {_describe(value)}")


def _toml_table(header: str, items: Mapping[str, object]) -> str:
    lines = [header] if header else []
    for key, value in items.items():
        if value is None:
            continue
        if not isinstance(key, str):
            raise TypeError(f"keys must be strings, got {_describe(key)}")
        lines.append(f"{_toml_string(key, key)} = {_toml_value(key, value)}")
    return "\n".join(lines) + "\n"


RESET_KEYS = (
    "qpos",
    "qvel",
    "qpos_noise",
    "qvel_noise",
    "qpos_noise_distribution",
    "qvel_noise_distribution",
    "keyframe",
    "goals",
    "params",
)


class _Inline(str):
    """TOML text written as it is (an inline table)."""


def _noise_value(key: str, value: object) -> object:
    """A noise by joint name ({joint: width}) as a TOML inline table; a width or a list of them as it is."""
    if not isinstance(value, Mapping):
        return value
    for joint in value:
        if not isinstance(joint, str):
            raise TypeError(f"{key} keys must be joint names, got {_describe(joint)}")
    return _Inline("{" + ", ".join(f"{_toml_string(key, j)} = {_toml_value(key, w)}" for j, w in value.items()) + "}")


def reset_toml(reset: Mapping[str, Any]) -> str:
    """A [reset] table from {qpos, qvel, qpos_noise, qvel_noise,
    qpos_noise_distribution, qvel_noise_distribution, params}: a noise is a
    width, a list of widths (one per coordinate) or {joint: width}; params is
    a list of dicts with the file's keys (kind, name, value or uniform = [low,
    high])."""
    if not isinstance(reset, Mapping):
        raise TypeError(f"reset must be a dict, got {_describe(reset)}")
    _check_keys("reset", reset, RESET_KEYS)
    own = {k: _noise_value(k, v) if k in ("qpos_noise", "qvel_noise") else v for k, v in reset.items()}
    text = _toml_table("[reset]", {k: v for k, v in own.items() if k not in ("params", "goals")})
    for key, table in (("params", "param"), ("goals", "goal")):
        entries = reset.get(key) or ()
        if isinstance(reset.get(key), (list, tuple)) and not entries:
            text += f"{table} = []\n"  # none: reset options that name them replace the scenario's
        if isinstance(entries, Mapping) or not isinstance(entries, Iterable):
            raise TypeError(f"reset {key} must be a list of dicts, got {_describe(entries)}")
        for entry in entries:
            if not isinstance(entry, Mapping):
                raise TypeError(f"each reset {key[:-1]} must be a dict ({_ENTRY_KEYS[key]}), got {_describe(entry)}")
            text += "\n" + _toml_table(f"[[reset.{table}]]", entry)
    return text


_ENTRY_KEYS = {"params": "kind, name, value or uniform", "goals": "body, pos or uniform"}


class Scenario:
    """A scenario. Scenario(...) builds one from keyword arguments;
    Scenario.from_file(path) reads a TOML file; Scenario.chapter() is the
    chapter's run.

    scene: an MJCF file (None: the chapter's scene), or a compiled scene: a
    simloop.Model, or on the PyPI build a mujoco.MjModel or MjSpec (copied
    when the Scenario is made, as Sim(model) copies it). timestep: seconds per
    step (None: the scene's own). steps or duration (seconds): the length
    (neither: 2000 steps).
    controls: {actuator: value} for a constant, {actuator: [(seconds,
    value), ...]} for a piecewise-constant schedule, or {actuator:
    Path("u.csv")} for a value per step from a CSV file's only column
    ({actuator: {"csv": ..., "column": ...}} to pick one); an actuator by
    name or index. disturbances: a list of dicts with the scenario file's keys (body,
    force, torque, newtons, direction, random_sign, start, start_step,
    start_fraction, duration, steps). record: a dict with bodies, joints,
    actuators, sensors, tendons (lists of names, or "all"), data ([array,
    object] pairs: any of mjData's arrays of numbers by object, as
    [("cfrc_ext", "torso"), ("site_xpos", "tip")]), contact_forces ([a, b]
    pairs of bodies or geoms: the force b gets from a, world frame, as
    [("pusher", "box")]), contacts (bool:
    the contacts of each row's state, default True) and ncon (bool: the
    chapter's count, as each step began) (None: every body on a free joint
    and every actuator). reset: how
    each run starts, a dict with qpos, qvel (the scene's nq / nv values),
    qpos_noise, qvel_noise (noise drawn from the run's seed: a width, a list
    of widths, one per coordinate, or {joint: width}; a uniform noise's
    half-width unless qpos_noise_distribution / qvel_noise_distribution is
    "normal", then its standard deviation), keyframe (a keyframe of the
    scene by name: the start the other keys apply over), goals (a list of
    dicts: body, a mocap body, and pos = [x, y, z] or uniform = [[x, y, z],
    [x, y, z]], its position drawn per run) and params (a list of dicts: kind "friction", "mass", "damping",
    "gravity" or "model", name, and value or uniform = [low, high]; a "model" value also field, one of
    _core.WRITABLE_MODEL_FIELDS, and index, its place in the row of the object `name`, or of every row).
    """

    def __init__(
        self,
        scene: Union[ModelLike, object] = None,
        *,
        name: str = "",
        timestep: Optional[float] = None,
        steps: Optional[int] = None,
        duration: Optional[float] = None,
        controls: Optional[Mapping[Union[str, int], Any]] = None,
        disturbances: Iterable[Mapping[str, Any]] = (),
        record: Optional[Mapping[str, Any]] = None,
        reset: Optional[Mapping[str, Any]] = None,
    ) -> None:
        for what, given in (("controls", controls), ("record", record)):
            if given is not None and not isinstance(given, Mapping):
                raise TypeError(f"{what} must be a dict or None, got {_describe(given)}")
        if isinstance(disturbances, (str, bytes, Mapping)) or not isinstance(disturbances, Iterable):
            raise TypeError(f"disturbances must be a list of dicts, got {_describe(disturbances)}")
        compiled = None  # a scene given compiled: the TOML names none (load_model: TypeError naming it)
        if scene is not None and not isinstance(scene, (str, bytes, os.PathLike)):
            compiled, scene = load_model(cast(ModelLike, scene)), None
        text = _toml_table(
            "", {"name": name or None, "scene": scene, "timestep": timestep, "steps": steps, "duration": duration}
        )
        for actuator, value in (controls or {}).items():
            text += "\n" + _toml_table("[[control]]", _control_entry(actuator, value))
        for d in disturbances:
            if not isinstance(d, Mapping):
                raise TypeError(f"each disturbance must be a dict, got {_describe(d)}")
            text += "\n" + _toml_table("[[disturbance]]", d)
        if record is not None:
            text += "\n" + _toml_table("[record]", record)
        if reset is not None:
            text += "\n" + reset_toml(reset)
        base = os.getcwd()  # where its relative paths resolve (sent along to workers)
        core = _core.Scenario.from_toml(text, "Scenario(...)", base)
        self._made(core, base, text, (_from_toml, (text, base, compiled)), compiled=compiled)

    def _made(
        self,
        core: _core.Scenario,
        base: str,
        toml: str,
        remake: Tuple[Any, ...],
        chapter: bool = False,
        compiled: Optional[_core.Model] = None,
    ) -> "Scenario":
        """Every way of making a Scenario ends here: its compiled form, the
        folder its relative paths resolve against, its TOML ("" for the
        chapter's, and for an empty file's), how a pickle makes it again,
        whether it is the chapter's (which travels as itself, not as TOML),
        and its scene when given compiled (a Model, which pickles)."""
        self._core, self._base, self.toml, self._remake, self._chapter = core, base, toml, remake, chapter
        self._compiled = compiled
        return self

    @classmethod
    def from_file(cls, path: Union[str, "os.PathLike[str]"]) -> "Scenario":
        """Reads a scenario file (TOML); a relative scene resolves against its folder."""
        path = _check_path("path", path, "a scenario file (TOML)")
        core = _core.Scenario.from_file(path)
        with open(path, encoding="utf-8") as f:
            toml = f.read()
        path = os.path.abspath(os.fspath(path))
        return cls.__new__(cls)._made(core, os.path.dirname(path), toml, (Scenario.from_file, (path,)))

    @classmethod
    def chapter(cls) -> "Scenario":
        """The chapter's run: its scene, push_motor at 1.0, the shove on the box."""
        return cls.__new__(cls)._made(_core.Scenario.chapter(), "", "", (Scenario.chapter, ()), chapter=True)

    # A Scenario does not change once made: copies are itself, and a pickle
    # makes it again the way it was made (Gymnasium deep-copies and pickles
    # an environment's arguments: env.spec.make(), AsyncVectorEnv).
    def __copy__(self) -> "Scenario":
        return self

    def __deepcopy__(self, memo: Dict[int, Any]) -> "Scenario":
        return self

    def __reduce__(self) -> Tuple[Any, ...]:
        return self._remake

    @property
    def name(self) -> str:
        return self._core.name

    @property
    def scene(self) -> str:
        """The scene's MJCF file ("" for the chapter's embedded scene, and for a scene given compiled)."""
        return self._core.scene

    @property
    def timestep(self) -> Optional[float]:
        return self._core.timestep

    def model(self) -> _core.Model:
        """The scene, compiled."""
        return self._compiled if self._compiled is not None else _core.load_scene(self._core)

    def __repr__(self) -> str:
        return repr(self._core)


def _from_toml(text: str, base: str, compiled: Optional[_core.Model] = None) -> Scenario:
    """A keyword Scenario made again (for pickling)."""
    core = _core.Scenario.from_toml(text, "Scenario(...)", base)
    return Scenario.__new__(Scenario)._made(core, base, text, (_from_toml, (text, base, compiled)), compiled=compiled)


def _scenario_and_scene(scenario: ScenarioLike, model: ModelLike) -> Tuple[Scenario, _core.Model]:
    if isinstance(scenario, (str, os.PathLike)):
        scenario = Scenario.from_file(scenario)
    if not isinstance(scenario, Scenario):
        raise TypeError(f"scenario must be a simloop.Scenario or a scenario file's path, got {_describe(scenario)}")
    # model: the scenario's own scene (None), or another (a Model, an MJCF path, a mujoco.MjModel).
    return scenario, scenario.model() if model is None else load_model(model)


def scenario_config(
    seed: object,
    rng: object,
    timestep: object,
    steps: object,
    perturb: object,
    record_every: object,
    audit_energy: object = False,
) -> _core.ScenarioConfig:
    """A scenario run's config: the types checked here; the values by the C++
    side (ScenarioConfig an unknown rng, the run the timestep, steps and
    record_every)."""
    return _core.ScenarioConfig(
        _check_seed("seed", seed),
        _check_str("rng", rng),
        None if timestep is None else _check_real("timestep", timestep),
        None if steps is None else _check_int("steps", steps),
        _check_bool("perturb", perturb),
        _check_int("record_every", record_every),
        _check_bool("audit_energy", audit_energy),
    )
