#!/usr/bin/env bash
# Set up, build, and run the chapter's simulation: scripts/run.sh --seed 0
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
bash scripts/setup.sh >&2
exec build/sim_loop "$@"
