"""The bottom of the package: arguments turned into what the compiled core
takes, or a one-line TypeError (or ValueError) naming the argument.

Python checks types here, and that a value fits the C++ type it becomes (an
int64, a uint64, a path without NUL); the ranges of values (a positive
timestep, steps from 1, ...) are the C++ library's to check, in its words.
Every other module of the package may import this one; it imports none of
them (but _mujoco_check, which imports nothing of simloop's).
"""

from __future__ import annotations

import functools
import numbers
import os
from typing import TYPE_CHECKING, Any, Callable, Iterable, List, Mapping, Optional, Sequence, Union

if TYPE_CHECKING:  # (importing numpy would cost every `import simloop` ~50 ms)
    import numpy as np
    from numpy.typing import NDArray

from . import _core
from ._core import MUJOCO_VERSION, Model
from ._mujoco_check import is_mujoco_model, usable_mujoco_model

ModelLike = Union[None, Model, str, "os.PathLike[str]"]
PathLike = Union[str, bytes, "os.PathLike[str]"]
Progress = Optional[Callable[[int, int], object]]

# The C++ integer types an argument becomes (pybind11 refuses an int outside
# them with a several-line TypeError).
U64_MAX = 2**64 - 1
I64_MIN, I64_MAX = -(2**63), 2**63 - 1
# The ranges sim_loop's --steps and --record-every accept, 1 to 2**62-1
# (simloop::kMaxSteps, kMaxRecordEvery): steps + record_every fits in int64.
MAX_STEPS = _core.MAX_STEPS
MAX_RECORD_EVERY = _core.MAX_RECORD_EVERY
# threads: None (or 0) is one per core, else 1 to this many (simloop::kMaxThreads).
MAX_THREADS = _core.MAX_THREADS
# chunk_size (an executor's runs per chunk, the batch command's --chunk-size): 1 to this many
# (simloop::cli::kMaxChunkRuns).
MAX_CHUNK_RUNS = _core.MAX_CHUNK_RUNS

# One wording for an argument's type, the compiled methods' and the
# package's (python/bindings_args.cc): repr on one line, with the type's name;
# a path (str, bytes, os.PathLike), text (str or bytes), a real number.
_show = _core._show
_describe = _core._describe
_check_path = _core._check_path
_check_text = _core._check_text
_check_real = _core._check_real


def _check_int(name: str, value: object, minimum: int = I64_MIN, maximum: int = I64_MAX) -> int:
    """An int (numpy's too, not a bool) from minimum to maximum: by default
    the int64 the core takes, whose own range checks then apply."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(f"{name} must be an int, got {_describe(value)}")
    number = int(value)
    if not minimum <= number <= maximum:
        raise ValueError(f"{name} must be an integer from {minimum} to {maximum}, got {_show(number)}")
    return number


def _did_you_mean(name: str, names: "Iterable[str]") -> str:
    """ " (did you mean 'x'?)" for the closest of names to a mistyped name, or "" (the C++ side's rule)."""
    close = _core._did_you_mean(name, list(names))
    return f" (did you mean {close!r}?)" if close else ""


def _check_keys(name: str, mapping: "Mapping[Any, Any]", known: Sequence[str]) -> None:
    """A dict's keys, all known: never silently ignored."""
    unknown = sorted(str(k) for k in mapping if k not in known)
    if unknown:
        raise ValueError(
            f"{name}: unknown key{'s' if len(unknown) > 1 else ''} {', '.join(map(repr, unknown))} "
            f"(known: {', '.join(map(repr, known)) if known else 'none'})"
        )


def _check_seed(name: str, value: object) -> int:
    """A seed: any uint64."""
    return _check_int(name, value, 0, U64_MAX)


def _check_threads(threads: object) -> int:
    """threads for the core: None is 0 (one per core), else an int the
    library checks (1 to MAX_THREADS, or 0)."""
    if threads is None:
        return 0
    number = _check_int("threads", threads)
    _core.check_threads(number)
    return number


def _check_bool(name: str, value: object) -> bool:
    if type(value).__name__ not in ("bool", "bool_"):  # Python's bool or numpy's
        raise TypeError(f"{name} must be a bool, got {_describe(value)}")
    return bool(value)


def _check_str(name: str, value: object) -> str:
    if not isinstance(value, str):
        raise TypeError(f"{name} must be a str, got {_describe(value)}")
    return value


def _check_progress(progress: object) -> Progress:
    if progress is not None and not callable(progress):
        raise TypeError(
            f"progress must be None or a callable progress(steps_done, steps_total), got {_describe(progress)}"
        )
    return progress


def _sequence(name: str, values: object) -> List[Any]:
    if isinstance(values, (str, bytes)) or not isinstance(values, Iterable):
        raise TypeError(f"{name} must be a sequence, got {_describe(values)}")
    return list(values)


def _reals(name: str, values: object) -> List[float]:
    """A sequence of numbers, each checked as _check_real (name[i])."""
    return [_check_real("%s[%d]" % (name, i), v) for i, v in enumerate(_sequence(name, values))]


def _finite_vector(name: str, value: object, size: int, what: str) -> "Union[Sequence[float], NDArray[np.float64]]":
    """A vector of `size` finite numbers from a sequence or a numeric numpy array;
    TypeError or ValueError naming `name`, its shape and the size wanted. For
    what Python writes itself (a Sim's views), where no C++ check follows."""
    import numpy as np

    if (
        isinstance(value, np.ndarray)
        and value.dtype == np.float64
        and value.shape == (size,)
        and np.isfinite(value).all()
    ):
        return value  # the common case, kept cheap
    array = _float_array(name, value, size, what)
    if array.shape != (size,):
        raise ValueError(f"{name} must have shape ({size},) ({what}), got shape {array.shape}")
    bad = np.flatnonzero(~np.isfinite(array))
    if bad.size:
        raise ValueError(f"{name}[{bad[0]}] must be finite, got {float(array[bad[0]])!r}")
    values: List[float] = array.tolist()
    return values


def _float_array(name: str, value: object, size: int, what: str) -> "NDArray[np.float64]":
    """A sequence or numeric numpy array (meant to hold `size` numbers, `what`)
    as a float64 array of any shape, its elements checked as numbers."""
    import numpy as np

    if isinstance(value, np.ndarray):
        if value.dtype.kind not in "biuf":
            raise TypeError(f"{name} must hold numbers ({what}), got an array of dtype {value.dtype}")
        return value.astype(np.float64)
    if isinstance(value, Sequence) and not isinstance(value, (str, bytes)):
        return np.array([_check_real("%s[%d]" % (name, i), v) for i, v in enumerate(value)], dtype=np.float64)
    raise TypeError(f"{name} must be a sequence or numpy array of {size} numbers ({what}), got {_describe(value)}")


@functools.lru_cache(maxsize=1)
def _pusher_scene() -> Model:
    return Model.pusher_scene()


def load_model(model: ModelLike = None) -> Model:
    """The model to run: None for the chapter's scene, a Model, an MJCF path,
    or a mujoco.MjModel or MjSpec (compiled; copied; on simloop built on the
    same PyPI mujoco).

    A file that is missing raises OSError; one MuJoCo cannot parse raises
    simloop.MujocoError with MuJoCo's message; one without a body "box" on a
    free joint or an actuator 0 on a slide or hinge joint raises ValueError.
    """
    if model is None:
        return _pusher_scene()
    if isinstance(model, Model):
        return model
    if isinstance(model, (str, bytes, os.PathLike)):
        return Model.from_file(_check_path("model", model, "an MJCF file"))
    if is_mujoco_model(model):
        kind = f"mujoco.{type(model).__name__}"
        compiled = usable_mujoco_model(model, MUJOCO_VERSION)  # held while its mjModel is copied
        return Model._copy_of_address(compiled._address, kind)
    raise TypeError(
        "model must be None, a simloop.Model, a mujoco.MjModel or MjSpec, or a path to an MJCF file, "
        f"got {_describe(model)}"
    )
