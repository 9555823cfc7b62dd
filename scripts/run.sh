#!/usr/bin/env bash
# `make run`: the main job on embedded defaults — the demo drone run locally
# (`modd up`: PubBroker, SubBroker, and simulated sensors once the simulator is
# installed) and the workbench (backend serving the built frontend) on
# http://127.0.0.1:${MODD_PORT:-8080}/. Ctrl-C stops everything it started.
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH="$PWD/.venv/bin:$PATH"
MODEL="${MODEL:-metamodel/examples/demo.modd}"
PORT="${MODD_PORT:-8080}"
DATA="${MODD_DATA:-$PWD/data}"
mkdir -p "$DATA"

modd validate -q "$MODEL"
if [ -f frontend/package.json ]; then
  echo "modd: building the frontend"
  (cd frontend && npm run build --silent >/dev/null) || echo "modd: the frontend did not build; serving the API only" >&2
fi

pids=()
stop() {
  trap - INT TERM EXIT
  for ((i=${#pids[@]}-1; i>=0; i--)); do kill -TERM "${pids[$i]}" 2>/dev/null || true; done
  wait 2>/dev/null || true
  echo "modd: stopped"
}
trap stop INT TERM EXIT

simulate=()
if [ -x .venv/bin/modd-sim ]; then simulate=(--simulate); fi
modd up "$MODEL" --workdir "$DATA/run" "${simulate[@]}" &
pids+=($!)

modd-backend --host 127.0.0.1 --port "$PORT" --data "$DATA/backend" \
  --frontend "$PWD/frontend/dist" --archives "$DATA/run/archive" >"$DATA/backend.log" 2>&1 &
pids+=($!)

for _ in $(seq 50); do grep -q "Uvicorn running" "$DATA/backend.log" 2>/dev/null && break; sleep 0.2; done
grep "first user" "$DATA/backend.log" || true
echo
echo "modd: workbench at http://127.0.0.1:$PORT/  (API docs: http://127.0.0.1:$PORT/docs)"
echo "modd: login 'admin'; its password was printed at the first start (see $DATA/backend.log)"
echo "modd: drone $(modd convert "$MODEL" --to json | python3 -c 'import json,sys; print(json.load(sys.stdin)["drone"]["name"])') running locally: archive in $DATA/run/archive, logs in $DATA/run/logs"
[ ${#simulate[@]} -gt 0 ] || echo "modd: no simulated sensors yet (modd-sim is not installed): the brokers run, no values flow"
echo "modd: Ctrl-C to stop"
wait -n "${pids[@]}" || true
