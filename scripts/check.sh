#!/usr/bin/env bash
# Every check of the project, used by developers and CI alike (via `make test`):
# the fast tier first (scripts/check-fast.sh: formatters, lint, types, unit
# tests), then the cross-process Python suites with the C++ suites beside them,
# then the browser journeys. Exits non-zero if a suite fails, after saying which.
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH="$PWD/.venv/bin:$PATH"

step() { printf '\n== %s\n' "$*"; }

scripts/check-fast.sh
# The cross-process tier mostly waits (windows, outages, restarts): the C++ suites
# (sanitizer and fuzzer builds, then their runs) take the other core meanwhile,
# one compile job at a time and niced, so the timing tests keep a core.
cpp_rc=0
cpp_log=$(mktemp)
trap 'rm -f "$cpp_log"' EXIT
if [ -x runtime/cpp/scripts/test.sh ]; then
  (JOBS=1 nice -n 10 runtime/cpp/scripts/test.sh) >"$cpp_log" 2>&1 &
  cpp_pid=$!
fi
step "pytest (cross-process and slow: what make check left out; the C++ suites beside it)"
py_rc=0
pytest -q -m "e2e or slow" || py_rc=$?
if [ -n "${cpp_pid:-}" ]; then
  wait "$cpp_pid" || cpp_rc=$?
  step "C++ runtime (ran beside the cross-process tier)"
  cat "$cpp_log"
fi
if [ "$py_rc" -ne 0 ] || [ "$cpp_rc" -ne 0 ]; then
  [ "$py_rc" -eq 0 ] || echo "make test: FAILED in: pytest (cross-process and slow)" >&2
  [ "$cpp_rc" -eq 0 ] || echo "make test: FAILED in: C++ runtime" >&2
  exit 1
fi
if [ -f frontend/package.json ]; then
  # typecheck and the unit tests ran in the fast tier; the browser journeys are left
  step "frontend: browser journeys"
  (cd frontend && npm run --silent test:e2e)
fi
