#!/usr/bin/env bash
# Set up, build the command (only it: scripts/test.sh builds the rest), and
# run the chapter's simulation: scripts/run.sh --seed 0
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
# SIMLOOP_MUJOCO=pypi: on the PyPI mujoco package, from build-pypi/ (scripts/setup.sh).
bash scripts/setup.sh --command >&2
if [[ ${SIMLOOP_MUJOCO:-system} == pypi ]]; then exec build-pypi/sim_loop "$@"; fi
exec build/sim_loop "$@"
