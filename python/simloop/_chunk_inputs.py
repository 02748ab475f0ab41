"""What a chunk of a distributed batch reads, as it travels and as a worker
makes it: the scene and the scenario as plain data (an MJCF path, a TOML
text), compiled or parsed once per worker process and content, and checked
against the sha256 the client took of every file they read (input_files).
"""

from __future__ import annotations

import collections
import functools
import os
import socket
import threading
from typing import Any, Callable, Dict, List, Tuple, TypeVar, cast

from . import _core, input_files
from ._checks import _check_path

# A scene parameter as it travels: ("friction" | "mass" | "damping", name or "", value).
SceneParam = Tuple[str, str, float]


def scene_source(model: object) -> Tuple[str, str]:
    """How a model travels: ("chapter", "") or ("path", absolute MJCF path)."""
    if model is None:
        return ("chapter", "")
    if isinstance(model, (str, bytes, os.PathLike)):
        return ("path", os.path.abspath(_check_path("model", model, "an MJCF file")))
    raise TypeError(
        "model must be None (the chapter's scene) or an MJCF file's path when work goes to an executor "
        f"(a compiled simloop.Model does not travel to workers), got {type(model).__name__}"
    )


def scene_inputs(source: Tuple[str, str]) -> Dict[str, str]:
    """The digests of the files a scene from scene_source reads (input_files), as the client reads them now."""
    return input_files.digests(input_files.scene_files(source[1])) if source[0] == "path" else {}


def scenario_source(scenario: Any) -> Tuple[str, str, str, str]:
    """How a simloop.Scenario travels: ("chapter", "", "", "") or ("toml", its text, the folder its paths resolve
    against, its name): a file's scenario is named for the file unless its text names it, and may be empty."""
    if scenario._chapter:
        return ("chapter", "", "", "")
    if scenario._compiled is not None:
        raise TypeError(
            "a scenario whose scene was given compiled (a simloop.Model, mujoco.MjModel or MjSpec) does not "
            "travel to an executor's workers, as model= does not: give the scene's MJCF path"
        )
    return ("toml", scenario.toml, scenario._base, scenario.name)


class InputMismatch(RuntimeError):
    """A file a chunk reads is not, on its worker, the file the client read when the batch started."""


# Compiled scenes and parsed scenarios, kept for the life of the worker's
# process, each under its source and the client's digests of the files it
# read (input_files): used only while the files here still have that content.
_MADE: "collections.OrderedDict[Any, Any]" = collections.OrderedDict()
_MADE_LOCK = threading.Lock()  # a ThreadPoolExecutor's workers share the process
_MADE_KEPT = 8
Made = TypeVar("Made")


def _check_inputs(expected: Dict[str, str], here: Dict[str, str]) -> None:
    differ = input_files.changed(expected, here)
    if differ:
        more = f" (and {len(differ) - 1} more)" if len(differ) > 1 else ""
        raise InputMismatch(
            f"worker {socket.gethostname()}: {differ[0]}{more} is not the file the batch started with "
            "(edited since, or another copy on this machine): every chunk must read the same files"
        )


def _made(source: Any, expected: Dict[str, str], make: Callable[[], Tuple[Made, List[str]]]) -> Made:
    """make()'s value (it returns the value and the files it read), made once per source and content:
    InputMismatch when the files here are not those the client digested (`expected`)."""
    key = (source, tuple(sorted(expected.items())))
    with _MADE_LOCK:
        kept = _MADE.get(key)
    if kept is not None:
        _check_inputs(expected, input_files.digests(expected))
        return cast(Made, kept)
    value, files = make()
    # Digested after the make: content changed before or during it differs here from what the client saw.
    _check_inputs(expected, input_files.digests(files))
    with _MADE_LOCK:
        _MADE[key] = value
        while len(_MADE) > _MADE_KEPT:
            _MADE.popitem(last=False)
    return value


def _scene(source: Tuple[str, str], expected: Dict[str, str]) -> "_core.Model":
    kind, text = source
    if kind == "chapter":
        return _made(source, expected, lambda: (_core.Model.pusher_scene(), []))
    return _made(source, expected, lambda: (_core.Model.from_file(text), input_files.scene_files(text)))


def _scenario(source: Tuple[str, str, str, str], expected: Dict[str, str]) -> Tuple["_core.Scenario", "_core.Model"]:
    def make() -> Tuple[Tuple["_core.Scenario", "_core.Model"], List[str]]:
        kind, text, base, name = source
        scenario = (
            _core.Scenario.chapter()
            if kind == "chapter"
            else _core.Scenario.from_toml(text, "scenario", base, default_name=name)
        )
        return (scenario, _core.load_scene(scenario)), input_files.scenario_files(scenario)

    return _made(source, expected, make)


@functools.lru_cache(maxsize=16)
def _with_params(model: "_core.Model", params: Tuple[SceneParam, ...]) -> "_core.Model":
    return _core.with_scene_params(model, list(params)) if params else model
