#!/usr/bin/env bash
# `make run`: the main job on embedded defaults — the demo drone run locally
# (`modd up --simulate`: PubBroker, SubBroker, simulated autopilot and sensors,
# MAVLink bridge) and the workbench (backend serving the built frontend) on
# http://127.0.0.1:${MODD_PORT:-8080}/, with the demo project loaded (only
# when it does not exist: a restart keeps the user's revisions) and deployed. Ctrl-C (or SIGTERM) stops everything it started, by PID.
# The SubBroker's zenoh router authenticates every client and applies access
# control (docs/security.md): the credentials (subbroker/backend/viewer .cred)
# and the deploy key are made once in $DATA/credentials (0600) and kept.
# Environment: MODEL, MODD_PORT, MODD_ZENOH_PORT, MODD_DATA, MODD_PROJECT,
# MODD_PUB_PORT and MODD_SUB_PORT (the drone's link ends),
# MODD_FOXGLOVE_PORT (Foxglove/Lichtblick live server on loopback, reached through the
# workbench's /foxglove/live; 0: none; docs/ecosystem.md),
# MODD_FOXGLOVE_REPLAY_PORT (its replay of an archive chosen in the workbench, 0: none).
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH="$PWD/.venv/bin:$PATH"
MODEL="${MODEL:-metamodel/examples/demo.modd}"
PORT="${MODD_PORT:-8080}"
# Two instances side by side: MODD_PORT=8081 alone moves every other default
# port by the same offset (zenoh 7448, Foxglove 8766 and 8866, the drone's link ends
# 7172/7273) and the data directory (data-8081, which holds the run's ingress
# socket and archive); each can still be set on its own.
OFFSET=$((PORT - 8080))
FOXGLOVE_PORT="${MODD_FOXGLOVE_PORT:-$((8765 + OFFSET))}"
REPLAY_PORT="${MODD_FOXGLOVE_REPLAY_PORT:-$((8865 + OFFSET))}"
ZENOH_PORT="${MODD_ZENOH_PORT:-$((7447 + OFFSET))}"
if [ "$OFFSET" = 0 ]; then DATA="${MODD_DATA:-$PWD/data}"; else DATA="${MODD_DATA:-$PWD/data-$PORT}"; fi
# The data directory holds the credentials, the run, the store and the logs:
# the user's alone (docs/security.md), as is everything made from here on.
mkdir -p "$DATA"
chmod 700 "$DATA"
# What the terminal shows: scripts/run-lines.sh (paths relative to the checkout).
. scripts/run-lines.sh

modd validate -q "$MODEL"
# The drone's link ends (PubBroker and SubBroker ports): the model's, unless moved.
if [ -n "${MODD_PUB_PORT:-}" ] || [ -n "${MODD_SUB_PORT:-}" ] || [ "$OFFSET" != 0 ]; then
  modd convert "$MODEL" --to json | python3 -c '
import json, sys
m = json.load(sys.stdin)
for part, var in (("pubBroker", sys.argv[1]), ("subBroker", sys.argv[2])):
    m[part]["endpoint"]["port"] = int(var) if var else m[part]["endpoint"]["port"] + int(sys.argv[3])
json.dump(m, open(sys.argv[4], "w"), indent=1)' "${MODD_PUB_PORT:-}" "${MODD_SUB_PORT:-}" "$OFFSET" "$DATA/model.json"
  MODEL="$DATA/model.json"
fi

# The frontend is rebuilt only when a source is newer than the last build.
if [ -f frontend/package.json ]; then
  if [ -f frontend/dist/index.html ] && [ -z "$(find frontend/src frontend/index.html frontend/package.json \
       frontend/vite.config.ts metamodel/modd.schema.json -newer frontend/dist/index.html -print -quit 2>/dev/null)" ]; then
    :
  else
    echo "modd: building the frontend (log in $(rel "$DATA")/frontend-build.log)"
    (cd frontend && npm run build --silent >"$DATA/frontend-build.log" 2>&1) \
      || echo "modd: the frontend did not build; serving the API only (see $(rel "$DATA")/frontend-build.log)" >&2
  fi
fi

# The first admin's password: drawn once per data directory and kept beside it
# (0600), so the login stays the same from one `make run` to the next.
PWFILE="$DATA/admin-password"
if [ ! -s "$PWFILE" ]; then
  if [ -f "$DATA/backend/modd.sqlite3" ]; then
    echo "modd: $(rel "$DATA")/backend was made by an older run without $(rel "$PWFILE");" \
         "its admin password is in $(rel "$DATA")/backend.log (or remove $(rel "$DATA") to start afresh)" >&2
  else
    (umask 077; python3 -c 'import secrets; print(secrets.token_urlsafe(12))' >"$PWFILE")
  fi
fi
export MODD_ADMIN_PASSWORD="$(cat "$PWFILE" 2>/dev/null || true)"

umask 077  # the logs and files of every process started below: 0600
[ ! -f "$DATA/backend.log" ] || chmod 600 "$DATA/backend.log"  # made by an older run
pids=()
stop() {
  trap - INT TERM EXIT
  for ((i=${#pids[@]}-1; i>=0; i--)); do kill -TERM "${pids[$i]}" 2>/dev/null || true; done
  wait 2>/dev/null || true
  echo "modd: stopped"
}
trap stop INT TERM EXIT

ZENOH="tcp/127.0.0.1:$ZENOH_PORT"
CREDS="$DATA/credentials"
python3 -c 'import sys; from modd.zenoh_auth import CredentialStore; CredentialStore(sys.argv[1]).ensure()' "$CREDS"
# modd up's own lines (every process started, its log, the kept deployment) go
# to its log: the terminal shows the few lines a user needs first.
modd up "$MODEL" --workdir "$DATA/run" --credentials "$CREDS" --simulate --zenoh-listen "$ZENOH" \
  >>"$DATA/up.log" &
pids+=($!)
DRONE="$(modd convert "$MODEL" --to json | python3 -c 'import json,sys; print(json.load(sys.stdin)["drone"]["name"])')"

modd-backend --host 127.0.0.1 --port "$PORT" --data "$DATA/backend" --zenoh-connect "$ZENOH" \
  --zenoh-credentials "$CREDS/backend.cred" --deploy-key "$CREDS/deploy.key" \
  --frontend "$PWD/frontend/dist" --archives "$DATA/run/archive" --records "$DATA/run/records" \
  --foxglove-port "$FOXGLOVE_PORT" --foxglove-replay-port "$REPLAY_PORT" >>"$DATA/backend.log" 2>&1 &
pids+=($!)

URL="http://127.0.0.1:$PORT"
answers() { python3 -c "import urllib.request as u; u.urlopen('$URL/api/health', timeout=2)" 2>/dev/null; }
up=0
for _ in $(seq 150); do
  answers && { up=1; break; }
  kill -0 "${pids[1]}" 2>/dev/null || { echo "modd: the backend stopped; see $(rel "$DATA")/backend.log" >&2; exit 1; }
  sleep 0.2
done
if [ "$up" != 1 ]; then
  echo "modd: the workbench does not answer at $URL/api/health after 30 s; see $(rel "$DATA")/backend.log" >&2
  exit 1
fi
# First, as soon as it answers: where the workbench is and how to log in.
say_workbench "$URL" "$MODD_ADMIN_PASSWORD" "$PWFILE" "$DATA"

# The demo project, loaded and deployed through the workbench's own API.
PROJECT="${MODD_PROJECT:-demo}"
if [ -n "$MODD_ADMIN_PASSWORD" ]; then
  MODD_PASSWORD="$MODD_ADMIN_PASSWORD" modd push "$MODEL" --server "$URL" --project "$PROJECT" \
    --message "loaded by make run" --if-new --deploy --wait 60 \
    || echo "modd: the demo project was not deployed (see above); the workbench still runs" >&2
fi

say_running "$PROJECT" "$DRONE" "$DATA" "$ZENOH" "$CREDS/viewer.cred" "$FOXGLOVE_PORT" "$REPLAY_PORT" "$PORT"
# Only a workbench that answers is announced as running.
if answers; then
  echo "modd: Ctrl-C to stop"
else
  echo "modd: the workbench stopped answering at $URL; see $(rel "$DATA")/backend.log" >&2
  exit 1
fi
wait -n "${pids[@]}" || true
