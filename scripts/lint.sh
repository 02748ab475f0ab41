#!/usr/bin/env bash
# The formatters and the linter, checking without changing anything:
# clang-format (Debian's, .clang-format) on the C++ tree, ruff (the version
# pyproject.toml's test extra pins, in .venv) for lint and format on the
# Python tree. Exits non-zero on the first difference. To apply them:
#   clang-format -i $(git ls-files '*.cc' '*.hpp' '*.h')
#   .venv/bin/ruff check --fix . && .venv/bin/ruff format .
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
venv=${SIMLOOP_VENV:-.venv}
git ls-files -z '*.cc' '*.hpp' '*.h' | xargs -0 clang-format --dry-run -Werror
"$venv/bin/ruff" check --quiet .
"$venv/bin/ruff" format --check --quiet .
echo "lint: clang-format and ruff found nothing to change"
