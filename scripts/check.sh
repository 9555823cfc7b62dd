#!/usr/bin/env bash
# Every check of the project, used by developers and CI alike (via `make test`):
# lint and types, the Python suites, the C++ suites, the frontend suites.
# Exits non-zero on the first failing suite, after saying which.
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH="$PWD/.venv/bin:$PATH"

step() { printf '\n== %s\n' "$*"; }

step "ruff"
ruff check --quiet .
step "mypy (strict)"
mypy --no-error-summary metamodel/src backend/src generators/src runtime/python/src
step "pytest"
pytest -q
if [ -x runtime/cpp/scripts/test.sh ]; then
  step "C++ runtime"
  runtime/cpp/scripts/test.sh
fi
if [ -f frontend/package.json ]; then
  step "frontend"
  (cd frontend && npm test --silent)
fi
