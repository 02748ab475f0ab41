"""Figures the tests expect that depend on the MuJoCo version.

One table per version, tests/expected/mujoco-<version>.toml, shared with the
C++ tests (tests/cpp/expected.hpp). expected("break_it.final_y_max") gives a
figure for the MuJoCo simloop runs on, or skips the test, saying which file
lacks it, on a version without one.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
import simloop
import tomllib

TABLES = Path(__file__).resolve().parents[1] / "expected"
VERSION = simloop.MUJOCO_VERSION.removeprefix("MuJoCo ")  # "2.2.2", "4.0.0"


def table_path() -> Path:
    return TABLES / f"mujoco-{VERSION}.toml"


def expected(key: str) -> Any:
    path = table_path()
    if not path.exists():
        pytest.skip(f"no figures for MuJoCo {VERSION}: {path} does not exist")
    value: Any = tomllib.loads(path.read_text())
    for part in key.split("."):
        if not isinstance(value, dict) or part not in value:
            pytest.skip(f"no figure '{key}' for MuJoCo {VERSION} in {path}")
        value = value[part]
    return value


def stepping_error_scene(model: str = "falls") -> tuple[str, str]:
    """Two boxes that fall onto a floor, with MuJoCo's stack or arena too
    small for their contacts (this version's <size> from the table): a MuJoCo
    error while stepping, once they land (step ~100 of 0.004 s). Returns the
    scene's XML and what the error says."""
    size = expected("errors.stepping_error_size")
    return (
        f"""<mujoco model="{model}">
  <option timestep="0.004"/>
  {size}
  <worldbody>
    <geom name="floor" type="plane" size="2 2 0.1"/>
    <body name="b1" pos="0 0 0.5"><freejoint/><geom type="box" size="0.05 0.05 0.05"/></body>
    <body name="b2" pos="0.3 0 0.5"><freejoint/><geom type="box" size="0.05 0.05 0.05"/></body>
  </worldbody>
</mujoco>
""",
        expected("errors.stepping_error_says"),
    )
