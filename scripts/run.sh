#!/usr/bin/env bash
# Set up, build, and run the chapter's simulation: scripts/run.sh --seed 0
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
# SIMLOOP_MUJOCO=pypi: on the PyPI mujoco package, from build-pypi/ (scripts/setup.sh).
bash scripts/setup.sh >&2
if [[ ${SIMLOOP_MUJOCO:-system} == pypi ]]; then exec build-pypi/sim_loop "$@"; fi
exec build/sim_loop "$@"
