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
# Then the arm64 lane (runtime/cpp/scripts/test-arm64.sh): the PubBroker and the units
# cross-built for aarch64 (build/cpp-arm64 kept: only what changed is rebuilt), the
# units run under qemu-user.
ARM64_LINK=tests/subbroker/test_arm64_link.py
if [ -x runtime/cpp/scripts/test.sh ]; then
  (JOBS=1 nice -n 10 runtime/cpp/scripts/test.sh &&
   JOBS=1 nice -n 10 runtime/cpp/scripts/test-arm64.sh) >"$cpp_log" 2>&1 &
  cpp_pid=$!
fi
step "pytest (cross-process and slow: what make check left out; the C++ suites beside it)"
py_rc=0
# the arm64 link test waits for the arm64 build: it runs after the C++ lane
# the install tests (7.5 min, need `make package`) run in `make package-test`
# Two workers (pytest-xdist), a test file each at a time: the tier mostly waits
# on windows and outages, so two files side by side take about half the time
# (30 min alone); `--dist loadfile` keeps a file's module fixtures in one worker.
pytest -q -n "${MODD_TEST_WORKERS:-2}" --dist loadfile -m "e2e or slow" \
  --ignore="$ARM64_LINK" --ignore=tests/subbroker/test_install_root.py \
  --ignore=tests/subbroker/test_install_pair.py --ignore=tests/subbroker/test_install_units.py || py_rc=$?
if [ -n "${cpp_pid:-}" ]; then
  wait "$cpp_pid" || cpp_rc=$?
  step "C++ runtime and its arm64 build (ran beside the cross-process tier)"
  cat "$cpp_log"
  if [ "$cpp_rc" -eq 0 ]; then
    step "the aarch64 PubBroker under qemu against the amd64 SubBroker"
    pytest -q "$ARM64_LINK" || py_rc=$?
  fi
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
  # the campaign's journey needs a backend joined to three drones from its start
  step "frontend: the campaign's browser journey (three simulated drones)"
  (cd frontend && MODD_E2E_ONLY=fleet npm run --silent test:e2e)
fi
