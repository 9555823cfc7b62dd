#!/usr/bin/env bash
# The screenshots of docs/ecosystem.md: the demo mission of `make run` opened in
# Lichtblick (live through the backend's Foxglove server, with the project's
# generated layout; then the drone's archive opened as a file). Not part of `make test`: it needs a built Lichtblick web app, which
# the project neither ships nor builds (Lichtblick's own README says how).
#
#   LICHTBLICK_DIST=/path/to/lichtblick/web/.webpack scripts/ecosystem-screenshots.sh
#
# Environment: LICHTBLICK_DIST (required: the directory holding the web app's
# index.html), OUT (default docs/images), RECORD_S (seconds of mission recorded
# before the screenshots, default 75), MODD_CHROMIUM (default /usr/bin/chromium).
# Everything runs on 127.0.0.1 on free ports, in a temporary data directory;
# everything started is stopped by PID at the end.
set -euo pipefail
cd "$(dirname "$0")/.."
: "${LICHTBLICK_DIST:?set LICHTBLICK_DIST to the built Lichtblick web app (its index.html directory)}"
[ -f "$LICHTBLICK_DIST/index.html" ] || { echo "no index.html in $LICHTBLICK_DIST" >&2; exit 1; }
OUT="${OUT:-docs/images}"
RECORD_S="${RECORD_S:-75}"
PY=.venv/bin/python
mkdir -p "$OUT"

free() { "$PY" -c 'from modd.ports import free_port; print(free_port())'; }
WORK="$(mktemp -d /tmp/modd-eco-shots.XXXXXX)"
export MODD_DATA="$WORK/data" MODD_PORT="$(free)" MODD_FOXGLOVE_PORT="$(free)" \
  MODD_FOXGLOVE_REPLAY_PORT="$(free)" MODD_ZENOH_PORT="$(free)" MODD_PUB_PORT="$(free)" \
  MODD_SUB_PORT="$(free)" MODD_APP_PORT="$(free)"
# Lichtblick's page (served by the .cjs on MODD_APP_PORT) may open the backend's
# WebSockets (/foxglove/live and /foxglove/replay check the Origin).
export MODD_VIEWER_ORIGINS="http://127.0.0.1:$MODD_APP_PORT"
BASE="http://127.0.0.1:$MODD_PORT"

RUN_PID=""
cleanup() {
  local rc=$?
  if [ "$rc" != 0 ] && [ -f "$MODD_DATA/backend.log" ]; then
    echo "ecosystem-screenshots: failed ($rc); the end of the backend's log:" >&2
    tail -30 "$MODD_DATA/backend.log" >&2
  fi
  if [ -n "$RUN_PID" ]; then kill -TERM "$RUN_PID" 2>/dev/null || true; wait "$RUN_PID" 2>/dev/null || true; fi
  rm -rf "$WORK"
}
trap cleanup EXIT INT TERM

scripts/run.sh >"$WORK/run.log" 2>&1 &
RUN_PID=$!
for _ in $(seq 300); do
  grep -q "Ctrl-C to stop" "$WORK/run.log" && break
  kill -0 "$RUN_PID" 2>/dev/null || { cat "$WORK/run.log" >&2; exit 1; }
  sleep 0.5
done
grep -q "Ctrl-C to stop" "$WORK/run.log" || { cat "$WORK/run.log" >&2; exit 1; }
echo "ecosystem-screenshots: make run is up at $BASE; recording ${RECORD_S} s of mission"
sleep "$RECORD_S"

# The scientist's layout download and the replay request, through the workbench's API.
"$PY" - "$BASE" "$(cat "$MODD_DATA/admin-password")" "$WORK" <<'EOF' || { tail -20 "$WORK/run.log" >&2; exit 1; }
import json, sys, urllib.request
base, password, work = sys.argv[1:4]

def call(path, body=None, method=None):
    req = urllib.request.Request(base + path, method=method,
                                 data=None if body is None else json.dumps(body).encode())
    req.add_header("Content-Type", "application/json")
    if token:
        req.add_header("Authorization", f"Bearer {token}")
    with urllib.request.urlopen(req, timeout=30) as r:
        return json.loads(r.read() or b"null")

token = None
token = call("/api/auth/login", {"username": "admin", "password": password})["token"]
projects = call("/api/projects")
if not projects:
    sys.exit("ecosystem-screenshots: make run loaded no project (see its log above)")
project = projects[0]["id"]
with open(f"{work}/modd-layout.json", "w") as f:
    json.dump(call(f"/api/projects/{project}/foxglove-layout"), f)
archive = call("/api/drones/usv/archives")[0]
with open(f"{work}/archive-name", "w") as f:
    f.write(archive["name"])
# A layout of the archive's raw topics: a plot per sensor.
topics = sorted(t["topic"] for t in archive["topics"])
groups = {}
for t in topics:
    groups.setdefault(t.rsplit(".", 1)[0], []).append(t)
config, ids = {}, []
for group, members in sorted(groups.items()):
    pid = f"Plot!{group}"
    ids.append(pid)
    config[pid] = {"title": group, "showLegend": True, "legendDisplay": "floating",
                   "xAxisVal": "timestamp", "isSynced": True,
                   "paths": [{"value": f'"{t}".value', "enabled": True,
                              "timestampMethod": "receiveTime", "label": t.rsplit(".", 1)[1]}
                             for t in members]}
def tree(ids):
    if len(ids) == 1:
        return ids[0]
    h = len(ids) // 2
    return {"direction": "column", "first": tree(ids[:h]), "second": tree(ids[h:]),
            "splitPercentage": round(100 * h / len(ids), 1)}
with open(f"{work}/modd-archive-layout.json", "w") as f:
    json.dump({"configById": config, "globalVariables": {}, "userNodes": {},
               "playbackConfig": {"speed": 1}, "layout": tree(ids)}, f)
# Replay in Foxglove with "play at once": Lichtblick has no playback controls.
replay = call(f"/api/drones/usv/archives/{archive['name']}/replay", {"autoplay": True}, "POST")
with open(f"{work}/replay-url", "w") as f:
    f.write(replay["url"])
# The live URL with its single-use ticket (the Downloads panel's "Foxglove link").
with open(f"{work}/live-url", "w") as f:
    f.write(call("/api/foxglove/links", {}, "POST")["live"])
EOF
# The archive the drone is writing, as a closed and indexed copy (what a
# scientist downloads from the Archives panel, recovered).
.venv/bin/modd archive recover "$MODD_DATA/run/archive/$(cat "$WORK/archive-name")" -o "$WORK/archive.mcap"

NODE_PATH="$PWD/frontend/node_modules" node scripts/ecosystem-screenshots.cjs \
  "$LICHTBLICK_DIST" "$WORK" "$OUT" "$(cat "$WORK/live-url")"
