#!/usr/bin/env bash
# `make run`: starts the main job on embedded defaults. Parts that do not exist
# yet are reported, not faked.
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH="$PWD/.venv/bin:$PATH"
echo "modd: command-line tool at .venv/bin/modd"
for f in ../shared/scenarios/scenario1.modd metamodel/examples/*.modd; do
  [ -f "$f" ] || continue
  modd validate "$f" && echo "modd: $f is valid"
done
