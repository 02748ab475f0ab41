#!/usr/bin/env bash
# Set up, build, and run every test: the C++ tests (ctest), then the Python
# tests (pytest, against the package installed in .venv and build/sim_loop).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
# SIMLOOP_MUJOCO=pypi: the same on the PyPI mujoco package, in build-pypi/
# and .venv-pypi (scripts/setup.sh).
bash scripts/setup.sh --python
if [[ ${SIMLOOP_MUJOCO:-system} == pypi ]]; then build=build-pypi venv=.venv-pypi; else build=build venv=.venv; fi
ctest --test-dir "$build" --output-on-failure -j "$(nproc)"
SIMLOOP_SIM_LOOP="$PWD/$build/sim_loop" "$venv/bin/python" -m pytest
