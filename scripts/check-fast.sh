#!/usr/bin/env bash
# The fast tier (`make check`, under 2 minutes): formatters, linters, types
# (tests included) and the unit tests of every component. `make test`
# (scripts/check.sh) runs this first, then the cross-process suites.
# Two lanes run side by side, one per core, of about the same CPU time: the
# static checks (formatters, linters, types), then the frontend's and the C++
# unit tests; and the Python unit tests (the longest step, alone in its lane).
# Each lane stops at its first failing step; the script prints both lanes'
# output, then says which step failed.
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH="$PWD/.venv/bin:$PATH"

step() { printf '\n== %s\n' "$*"; }

static_checks() {
  step "ruff check"
  ruff check --quiet .
  step "formatters, whole tree (scripts/format-all.sh --check)"
  scripts/format-all.sh --check
  step "generated files up to date (python -m modd_contracts.typegen --check)"
  python -m modd_contracts.typegen --check
  step "mypy (strict: sources, component tests, cross-process tests and benchmarks)"
  mypy --no-error-summary metamodel/src backend/src generators/src runtime/python/src launcher/src
  mypy --no-error-summary --explicit-package-bases \
    metamodel/tests generators/tests runtime/python/tests backend/tests
  # The cross-process tests and benchmarks import their harnesses by bare name
  # (each tree's conftest.py puts its folder on sys.path): the same folders are
  # mypy's bases here. The conftest.py files share one module name, so one run each.
  local tests_path=tests/subbroker:tests/runtime:tests/mavlink:tests/ecosystem:tests/bench:tests/sensors
  tests_path+=:tests/deploy:tests/twodrones:tests/dataset:tests:backend/tests
  MYPYPATH=$tests_path mypy --no-error-summary --explicit-package-bases \
    --exclude '/conftest\.py$' tests
  for c in tests/*/conftest.py; do
    MYPYPATH=$tests_path mypy --no-error-summary --explicit-package-bases "$c"
  done
  if [ -f frontend/package.json ]; then
    step "eslint, tsc"
    (cd frontend && npx --no-install eslint --max-warnings=0 src &&
      npx --no-install tsc --noEmit -p tsconfig.json)
  fi
}

# C++ and frontend unit tests: after the static checks, in their lane.
component_tests() {
  if [ -f build/cpp/build.ninja ]; then
    step "C++ unit tests (build/cpp, after make build)"
    cmake --build build/cpp --target modd_unit_tests >/dev/null
    build/cpp/modd_unit_tests --gtest_brief=1
  fi
  if [ -f frontend/package.json ]; then
    step "frontend unit tests (vitest)"
    (cd frontend && npx --no-install vitest run --silent)
  fi
}

# The Python unit tests of every component (~1,600; the longest step).
unit_tests() {
  step "unit tests (pytest -m 'not e2e and not slow')"
  pytest -q -m "not e2e and not slow" metamodel/tests generators/tests runtime/python/tests \
    backend/tests
}

logs=$(mktemp -d)
trap 'rm -rf "$logs"' EXIT
echo "make check: static checks and unit tests side by side (output when both end)"
# Background jobs, not the left side of ||: there errexit would be ignored in them.
(set -e; static_checks; component_tests) >"$logs/static" 2>&1 &
static_pid=$!
(set -e; unit_tests) >"$logs/unit" 2>&1 &
unit_pid=$!
static_rc=0
unit_rc=0
wait "$static_pid" || static_rc=$?
wait "$unit_pid" || unit_rc=$?
cat "$logs/static" "$logs/unit"
last_step() { grep '^== ' "$1" | tail -1 | cut -c4-; }
if [ "$static_rc" -ne 0 ]; then echo "make check: FAILED in: $(last_step "$logs/static")" >&2; fi
if [ "$unit_rc" -ne 0 ]; then echo "make check: FAILED in: $(last_step "$logs/unit")" >&2; fi
[ "$static_rc" -eq 0 ] && [ "$unit_rc" -eq 0 ]
