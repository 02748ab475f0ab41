#!/usr/bin/env bash
# Set up, build the Python command (only it: scripts/test.sh builds the C++
# tests, benchmarks and build/sim_loop), and run the chapter's simulation
# with its recording: scripts/run.sh --seed 0
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
# SIMLOOP_MUJOCO=pypi: on the PyPI mujoco package, in .venv-pypi (scripts/setup.sh).
bash scripts/setup.sh --package >&2
if [[ ${SIMLOOP_MUJOCO:-system} == pypi ]]; then exec .venv-pypi/bin/python -m simloop "$@"; fi
exec .venv/bin/python -m simloop "$@"
