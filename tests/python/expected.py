"""Figures the tests expect that depend on the MuJoCo version.

One table per version, tests/expected/mujoco-<version>.toml, shared with the
C++ tests (tests/cpp/expected.hpp). expected("break_it.final_y_max") gives a
figure for the MuJoCo simloop runs on, or skips the test, saying which file
lacks it, on a version without one.
"""

from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Any

import pytest

import simloop

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
