#!/usr/bin/env bash
# Set up, build, and run every test: the C++ tests (ctest), then the Python
# tests (pytest, against the package installed in .venv and build/sim_loop).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
bash scripts/setup.sh --python
ctest --test-dir build --output-on-failure -j "$(nproc)"
.venv/bin/python -m pytest
