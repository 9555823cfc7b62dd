#!/usr/bin/env bash
# The whole tree under the formatters, with the configs `make check` uses:
# - Python: ruff's import order, then `ruff format` (pyproject.toml [tool.ruff]:
#   generated modules and the generators' golden outputs are excluded);
# - C++: clang-format with the root .clang-format, on every tracked C++ file of
#   the runtime but the generated *.gen.hpp (typegen writes them; a reformat
#   would make them stale).
# The frontend has no formatter configured (eslint only), so nothing is done there.
#
#   scripts/format-all.sh          rewrite the files (one reformat commit)
#   scripts/format-all.sh --check  change nothing; exit 1 if a file would change
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH="$PWD/.venv/bin:$PATH"

check=0
case "${1:-}" in
  --check) check=1 ;;
  "") ;;
  *) echo "usage: scripts/format-all.sh [--check]" >&2; exit 2 ;;
esac

cxx_files() {
  git ls-files -- 'runtime/cpp/*.cpp' 'runtime/cpp/*.hpp' 'runtime/cpp/*.h' | grep -v '\.gen\.hpp$'
}

if [ "$check" -eq 1 ]; then
  ruff check --quiet --select I .
  ruff format --check --quiet .
else
  ruff check --quiet --fix --select I .
  ruff format --quiet .
fi

if command -v clang-format >/dev/null 2>&1; then
  mapfile -t cxx < <(cxx_files)
  if [ "$check" -eq 1 ]; then
    clang-format --dry-run --Werror --style=file "${cxx[@]}"
  else
    clang-format -i --style=file "${cxx[@]}"
  fi
else
  echo "format-all: clang-format not installed; C++ left as it is" >&2
fi
