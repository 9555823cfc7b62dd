# What `make run` (scripts/run.sh, which sources this file) prints: the URL and
# the login first, as soon as the workbench answers, then one line per thing a
# user may want next; at most 8 lines in all, paths relative to the checkout.
# Everything else goes to the logs in the data directory.

# A path as the user types it from the checkout (run.sh runs there).
rel() {
  case "$1" in
    "$PWD") echo "." ;;
    "$PWD"/*) echo "${1#"$PWD"/}" ;;
    *) echo "$1" ;;
  esac
}

# say_workbench URL PASSWORD PASSWORD_FILE DATA
say_workbench() {
  echo "modd: workbench at $1/  (API docs: $1/docs)"
  if [ -n "$2" ]; then
    echo "modd: login 'admin', password '$2' (kept in $(rel "$3")); the drone starts and deploys now, logs in $(rel "$4")/"
  else
    echo "modd: login 'admin'; its password is in $(rel "$4")/backend.log"
  fi
}

# say_running PROJECT DRONE DATA ZENOH VIEWER_CRED FOXGLOVE_PORT REPLAY_PORT WORKBENCH_PORT
# The Foxglove servers listen on loopback behind the workbench: viewers connect
# through its /foxglove/live and /foxglove/replay with a ticket (docs/ecosystem.md).
say_running() {
  echo "modd: project '$1' runs on the simulated drone '$2'; viewers on zenoh $4 need credentials: $(rel "$5")"
  local base="ws://127.0.0.1:$8/foxglove"
  local live="live at $base/live" replay="replay at …/foxglove/replay"
  local how="with a ticket (Downloads panel)"
  if [ "$6" != 0 ] && [ "$7" != 0 ]; then
    echo "modd: Foxglove/Lichtblick $live, $replay, $how"
  elif [ "$6" != 0 ]; then
    echo "modd: Foxglove/Lichtblick $live $how"
  elif [ "$7" != 0 ]; then
    echo "modd: Foxglove/Lichtblick replay at $base/replay $how"
  fi
}
