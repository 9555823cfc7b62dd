#!/usr/bin/env bash
# Every check of the project, used by developers and CI alike (via `make test`):
# the fast tier first (scripts/check-fast.sh: formatters, lint, types, unit
# tests), then the cross-process Python suites, the C++ suites, the frontend suites.
# Exits non-zero on the first failing suite, after saying which.
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH="$PWD/.venv/bin:$PATH"

step() { printf '\n== %s\n' "$*"; }

scripts/check-fast.sh
step "pytest (cross-process and slow: what make check left out)"
pytest -q -m "e2e or slow"
if [ -x runtime/cpp/scripts/test.sh ]; then
  step "C++ runtime"
  runtime/cpp/scripts/test.sh
fi
if [ -f frontend/package.json ]; then
  # typecheck and the unit tests ran in the fast tier; the browser journeys are left
  step "frontend: browser journeys"
  (cd frontend && npm run --silent test:e2e)
fi
