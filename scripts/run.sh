#!/usr/bin/env bash
# `make run`: the main job on embedded defaults. It starts the parts of the
# system that exist and says what it started; parts still to come are named,
# not faked.
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH="$PWD/.venv/bin:$PATH"
SCENARIOS="$(cd .. && pwd)/shared/scenarios"
MODEL="${MODEL:-$SCENARIOS/scenario1.modd}"

echo "modd: command-line tool: .venv/bin/modd"
if [ ! -f "$MODEL" ]; then
  echo "modd: no model at $MODEL (set MODEL=path/to/mission.modd)" >&2
  exit 1
fi
modd validate "$MODEL"
if modd plan --help >/dev/null 2>&1; then
  echo "modd: plan of $MODEL:"
  modd plan "$MODEL"
fi
started=()
if [ -x build/bin/modd-pubbroker ]; then
  echo "modd: on-board PubBroker built at build/bin/modd-pubbroker"
fi
echo
echo "modd: not available yet: the workbench (backend + browser UI), the SubBroker"
echo "      and the simulated drone; 'make run' will start them as they land."
[ ${#started[@]} -eq 0 ] || printf 'started: %s\n' "${started[@]}"
