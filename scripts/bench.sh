#!/usr/bin/env bash
# Every benchmark of tests/bench, one after the other, each printing its tables
# (`make bench`, after `make build`, which runs scripts/setup.sh). Asserts no time.
# Figures go in docs/benchmarks.md with the command that printed them.
# Takes about 35 minutes on a 2-core machine. LINK_SECONDS etc. shorten it.
set -euo pipefail
cd "$(dirname "$0")/.."
PY=.venv/bin/python

missing=()
command -v mosquitto >/dev/null 2>&1 || [ -x /usr/sbin/mosquitto ] || missing+=(mosquitto)
command -v tshark >/dev/null 2>&1 || missing+=(tshark)
command -v taskset >/dev/null 2>&1 || missing+=(util-linux)
if [ ${#missing[@]} -gt 0 ]; then
  echo "bench: missing ${missing[*]}: install with" >&2
  echo "  sudo apt-get install -y ${missing[*]}   (or run scripts/setup.sh, which does)" >&2
  exit 2
fi
if [ "$(id -u)" -ne 0 ]; then
  echo "bench: tshark must capture on lo: run as root (or give dumpcap CAP_NET_RAW)" >&2
  exit 2
fi
if [ ! -x build/bin/modd-pubbroker ] || [ ! -x "$PY" ]; then
  echo "bench: build/bin/modd-pubbroker or .venv missing: run make build" >&2
  exit 2
fi

run() { printf '\n===== %s\n\n' "$*"; "$PY" "$@"; }
start=$(date +%s)
echo "bench: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(date -u +%Y-%m-%dT%H:%MZ)"
run tests/bench/bench_link.py --seconds "${LINK_SECONDS:-60}"
run tests/bench/bench_radio.py --seconds "${RADIO_SECONDS:-30}"
run tests/bench/bench_resolution.py --seconds "${RADIO_SECONDS:-30}"
run tests/bench/bench_airtime.py --seconds "${AIRTIME_SECONDS:-60}"  # planned about / at most vs measured
run tests/bench/bench_ingest.py
run tests/bench/bench_latency.py --seconds "${LATENCY_SECONDS:-20}"
run tests/bench/bench_footprint.py --seconds "${FOOTPRINT_SECONDS:-30}"
run tests/bench/bench_pubbroker.py --seconds "${PUBBROKER_SECONDS:-10}" --ingest-samples 10000000
run tests/bench/bench_aggregations.py --seconds "${AGGREGATIONS_SECONDS:-20}"  # MEDIAN, STDDEV, PERCENTILE(95) vs AVERAGE
run tests/bench/bench_events.py --seconds "${EVENTS_SECONDS:-30}"  # ON_CHANGE vs LAST, flapping worst case
run tests/bench/bench_planner.py --quick
run tests/bench/bench_plan_cpu.py
run tests/bench/bench_backend_plan.py --runs 30
printf '\n===== %s\n\n' "frontend/tests/bench/live-plan-latency.mjs --edits 20"
(cd frontend && node tests/bench/live-plan-latency.mjs --edits 20)  # the live plan in the browser
run tests/bench/bench_subbroker.py --seconds "${SUBBROKER_SECONDS:-10}" --profile
run tests/bench/bench_fleet.py --drones "${FLEET_DRONES:-20}" --seconds "${FLEET_SECONDS:-60}"
# issue 44: 50 drones across 3 stations in network namespaces (root), a handover
run tests/bench/bench_fleet_stations.py --drones "${STATIONS_DRONES:-50}" --seconds "${STATIONS_SECONDS:-60}"
run tests/bench/bench_health_ws.py --ops 20000
run tests/bench/bench_sensors.py --seconds "${SENSORS_SECONDS:-20}"
run tests/bench/bench_health_csv.py --clients 70 --seconds "${HEALTH_CSV_SECONDS:-20}"
run tests/bench/bench_health_editing.py --seconds "${HEALTH_EDITING_SECONDS:-20}"
run tests/bench/bench_health_editing.py --seconds "${HEALTH_EDITING_SECONDS:-20}" --sockets 1000
# issue 41's load, SQLite and PostgreSQL, beside a bare app on the same cores
run tests/bench/bench_health_load.py --seconds "${HEALTH_LOAD_SECONDS:-180}" --runs "${HEALTH_LOAD_RUNS:-3}"
run tests/bench/bench_backfill.py --minutes "${BACKFILL_MINUTES:-10}" --rate 3600
run tests/bench/bench_dataset.py --samples "${DATASET_SAMPLES:-10000000}" --json build/bench/dataset.json
run tests/bench/flap_windows.py "${FLAP_SECONDS:-60}" 2
if [ -n "${SOAK:-}" ]; then  # make bench SOAK=1: the 30-minute soak with faults (docs/reliability.md)
  run tests/bench/soak.py --seconds "${SOAK_SECONDS:-1800}"
  # and the one-hour serial soak at 10 % loss: windows, archive, flat memory (issue 38)
  run tests/bench/soak_serial.py --seconds "${SOAK_SERIAL_SECONDS:-3600}"
fi
echo
echo "bench: all done in $(( $(date +%s) - start )) s"
