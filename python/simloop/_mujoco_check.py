"""Why the compiled module cannot load, in one line, when the cause is MuJoCo.

A simloop built on the PyPI `mujoco` package loads site-packages/mujoco's
libmujoco.so.<version>, the very file `import mujoco` loads; its SONAME
carries the full version, so a different `mujoco` in the environment (or
none) leaves the loader with "libmujoco.so.X: cannot open shared object
file". This turns that into which versions are where and what to run.
Nothing here imports mujoco (it loads numpy and a renderer).
"""

from __future__ import annotations

import glob
import importlib
import importlib.util
import os
from typing import Any, cast

from ._build import MUJOCO_BUILD, MUJOCO_LIBRARY_VERSION


def installed_mujoco_library() -> str | None:
    """The version of the libmujoco the `mujoco` package here ships, or None."""
    spec = importlib.util.find_spec("mujoco")
    if spec is None or not spec.submodule_search_locations:
        return None
    for folder in spec.submodule_search_locations:
        for path in glob.glob(os.path.join(folder, "libmujoco.so.*")):
            return os.path.basename(path)[len("libmujoco.so.") :]
    return None


def load_failure_message(error: ImportError) -> str | None:
    """The one-line explanation for `error`, or None if MuJoCo is not its cause."""
    if "libmujoco" not in str(error):
        return None
    wanted = MUJOCO_LIBRARY_VERSION
    if MUJOCO_BUILD != "pypi":
        return (
            f"simloop was built on the system's MuJoCo {wanted} (libmujoco-dev), which cannot be loaded: "
            f"install it (apt-get install libmujoco-dev) or rebuild simloop ({error})"
        )
    found = installed_mujoco_library()
    if found == wanted:  # the right library, but not where simloop's RUNPATH looks ($ORIGIN/../mujoco)
        return (
            f"simloop was built on MuJoCo {wanted} from the mujoco package, which is installed, but its libmujoco "
            f"is not beside simloop: install simloop into the same environment (site-packages) as mujoco, "
            f"or import mujoco before simloop ({error})"
        )
    where = (
        "this environment has no mujoco package"
        if found is None
        else f"this environment's mujoco package ships MuJoCo {found}"
    )
    return (
        f"simloop was built on MuJoCo {wanted} from the mujoco package, but {where}: "
        f"pip install mujoco=={wanted}, or rebuild simloop against the mujoco you have "
        f"(pip install --no-build-isolation . -C simloop.mujoco=pypi)"
    )


def is_mujoco_model(value: object) -> bool:
    """True for a mujoco.MjModel or mujoco.MjSpec (checked without importing mujoco)."""
    kind = type(value)
    return kind.__name__ in ("MjModel", "MjSpec") and kind.__module__.split(".")[0] == "mujoco"


def usable_mujoco_model(model: object, simloop_mujoco: str) -> Any:
    """A mujoco.MjModel that simloop can copy (its `_address` checked): the
    model itself, or a mujoco.MjSpec compiled by mujoco (its errors, a
    ValueError, as they are). Hold it while its mjModel is copied.

    simloop_mujoco is simloop's own MuJoCo ("MuJoCo 4.0.0"). The model must
    come from the very libmujoco simloop runs: the PyPI build, and the same
    version (then one library file serves both, see load_failure_message).
    """
    mujoco = importlib.import_module("mujoco")  # loaded already: the model is one of its objects

    theirs = f"MuJoCo {mujoco.mj_versionString()}"
    kind = f"mujoco.{type(model).__name__}"
    if MUJOCO_BUILD != "pypi":
        raise TypeError(
            f"a {kind} ({theirs}) cannot be run by this simloop, built on the system's {simloop_mujoco}: "
            "pass the scene's MJCF path, or build simloop on the mujoco package (SIMLOOP_MUJOCO=pypi)"
        )
    if theirs != simloop_mujoco:
        raise TypeError(
            f"a {kind} from {theirs} cannot be run by this simloop, built on {simloop_mujoco}: "
            f"pip install mujoco=={MUJOCO_LIBRARY_VERSION}, or rebuild simloop against {theirs}"
        )
    if kind == "mujoco.MjSpec":
        model = cast(Any, model).compile()
    address = getattr(model, "_address", None)
    if not isinstance(address, int) or address == 0:
        raise TypeError(f"this {kind} ({theirs}) does not give its address; simloop cannot copy it")
    return model
