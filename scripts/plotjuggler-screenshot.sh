#!/usr/bin/env bash
# The PlotJuggler screenshot of docs/ecosystem.md: the demo mission of `make run`
# plotted live by a real PlotJuggler, fed by `modd-plotjuggler` through its
# "UDP Server" streamer (JSON). Not part of `make test`: it needs a PlotJuggler
# binary, which the project neither ships nor builds (docs/ecosystem.md says how
# it was built), and Xvfb, xdotool and ImageMagick (Debian: xvfb xdotool imagemagick).
#
#   PLOTJUGGLER_BIN=/path/to/plotjuggler scripts/plotjuggler-screenshot.sh
#
# Environment: PLOTJUGGLER_BIN (required), OUT (default docs/images),
# PLOT_S (seconds of plotting before the screenshot, default 40).
# PlotJuggler runs with its own settings in a temporary directory
# (XDG_CONFIG_HOME): UDP Server on a free loopback port, protocol JSON, the
# field `timestamp` as time, a 30 s streaming buffer. It starts with its UDP
# Server (--start_streamer; its dialog accepted with Return); once MoDD's
# values arrive, the layout naming the series to plot is loaded through the
# Layout panel's load button, as a user would (xdotool). Everything runs on
# 127.0.0.1 on free ports; everything started is stopped by PID at the end.
set -euo pipefail
cd "$(dirname "$0")/.."
: "${PLOTJUGGLER_BIN:?set PLOTJUGGLER_BIN to a PlotJuggler executable (with its UDP Server plugin)}"
[ -x "$PLOTJUGGLER_BIN" ] || { echo "not executable: $PLOTJUGGLER_BIN" >&2; exit 1; }
for tool in Xvfb xdotool import; do
  command -v "$tool" >/dev/null || { echo "missing $tool (apt-get install xvfb xdotool imagemagick)" >&2; exit 1; }
done
OUT="${OUT:-docs/images}"
PLOT_S="${PLOT_S:-40}"
PY=.venv/bin/python
mkdir -p "$OUT"

free() { "$PY" -c 'from modd.ports import free_port; print(free_port())'; }
WORK="$(mktemp -d /tmp/modd-pj-shot.XXXXXX)"
export MODD_DATA="$WORK/data" MODD_PORT="$(free)" MODD_FOXGLOVE_PORT="$(free)" \
  MODD_FOXGLOVE_REPLAY_PORT="$(free)" MODD_ZENOH_PORT="$(free)" MODD_PUB_PORT="$(free)" \
  MODD_SUB_PORT="$(free)"
PJ_PORT="$(free)"

RUN_PID="" XVFB_PID="" PJ_PID="" OUT_PID=""
stop() { [ -n "$1" ] || return 0; kill -TERM "$1" 2>/dev/null || true; wait "$1" 2>/dev/null || true; }
cleanup() {
  local rc=$?
  if [ "$rc" != 0 ]; then
    echo "plotjuggler-screenshot: failed ($rc)" >&2
    for log in "$WORK/plotjuggler.log" "$WORK/modd-plotjuggler.log" "$WORK/run.log"; do
      [ -f "$log" ] && { echo "--- $log" >&2; tail -15 "$log" >&2; }
    done
  fi
  stop "$OUT_PID"; stop "$PJ_PID"; stop "$XVFB_PID"; stop "$RUN_PID"
  rm -rf "$WORK"
}
trap cleanup EXIT INT TERM

# 1. make run, on free ports in the temporary data directory.
scripts/run.sh >"$WORK/run.log" 2>&1 &
RUN_PID=$!
for _ in $(seq 300); do
  grep -q "Ctrl-C to stop" "$WORK/run.log" && break
  kill -0 "$RUN_PID" 2>/dev/null || exit 1
  sleep 0.5
done
grep -q "Ctrl-C to stop" "$WORK/run.log" || exit 1
echo "plotjuggler-screenshot: make run is up (zenoh tcp/127.0.0.1:$MODD_ZENOH_PORT)"

# 2. An X server of its own (the first free display from :90).
D=90
while [ -e "/tmp/.X11-unix/X$D" ] || [ -e "/tmp/.X$D-lock" ]; do D=$((D + 1)); done
Xvfb ":$D" -screen 0 1600x900x24 -nolisten tcp >"$WORK/xvfb.log" 2>&1 &
XVFB_PID=$!
export DISPLAY=":$D"
for _ in $(seq 50); do xdotool getmouselocation >/dev/null 2>&1 && break; sleep 0.2; done

# 3. PlotJuggler's settings and layout: what a user sets once in its dialogs.
export XDG_CONFIG_HOME="$WORK/config"
mkdir -p "$XDG_CONFIG_HOME/PlotJuggler"
cat >"$XDG_CONFIG_HOME/PlotJuggler/PlotJuggler-3.ini" <<EOF
[General]
UDP_Server%3A%3Aprotocol=json
UDP_Server%3A%3Aaddress=127.0.0.1
UDP_Server%3A%3Aport=$PJ_PORT
NlohmannParser.json.timestampEnabled=true
NlohmannParser.json.timestampFieldName=timestamp
MainWindow.streamingBufferValue=30
MainWindow.previousStreamingPlugin=UDP Server
MainWindow.lastLayoutDirectory=$WORK

[Changelog]
first=false
dont=true
EOF
curve() { printf '        <curve name="%s" color="%s"/>\n' "$1" "$2"; }
{
  cat <<'EOF'
<?xml version='1.0' encoding='UTF-8'?>
<root>
 <tabbed_widget name="Main Window" parent="main_window">
  <Tab tab_name="usv (MoDD demo)" containers="1">
   <Container>
    <DockSplitter orientation="-" count="2" sizes="0.5;0.5">
     <DockArea name="usv.accelerometer.accel_x: sub_1 AVERAGE 2 s, sub_3 AVERAGE 0.25 s">
      <plot mode="TimeSeries" style="LinesAndDots" flip_x="false" flip_y="false">
EOF
  curve /usv/sub_1/value "#1f77b4"
  curve /usv/sub_3/value "#d62728"
  cat <<'EOF'
      </plot>
     </DockArea>
     <DockArea name="usv.accelerometer.accel_z: sub_5 MIN, sub_6 MAX (0.25 s)">
      <plot mode="TimeSeries" style="LinesAndDots" flip_x="false" flip_y="false">
EOF
  curve /usv/sub_5/value "#2ca02c"
  curve /usv/sub_6/value "#9467bd"
  cat <<'EOF'
      </plot>
     </DockArea>
    </DockSplitter>
   </Container>
  </Tab>
  <currentTabIndex index="0"/>
 </tabbed_widget>
 <use_relative_time_offset enabled="1"/>
 <Plugins>
  <plugin ID="UDP Server"/>
 </Plugins>
</root>
EOF
} >"$WORK/layout.xml"

"$PLOTJUGGLER_BIN" --nosplash --window_title "PlotJuggler: MoDD demo" \
  --start_streamer libDataStreamUDP >"$WORK/plotjuggler.log" 2>&1 &
PJ_PID=$!
# The UDP Server's dialog (its options as set above): OK, with Return.
main_window() { xdotool search --onlyvisible --pid "$PJ_PID" --name 'MoDD demo' 2>/dev/null | head -1; }
listening() { ss -Huln "sport = :$PJ_PORT" | grep -q .; }
for _ in $(seq 120); do
  kill -0 "$PJ_PID" 2>/dev/null || exit 1
  for w in $(xdotool search --onlyvisible --pid "$PJ_PID" --name '^UDP Server$' 2>/dev/null); do
    xdotool windowfocus --sync "$w" 2>/dev/null && xdotool key --clearmodifiers Return || true
    sleep 0.5
  done
  [ -n "$(main_window)" ] && listening && break
  sleep 0.5
done
listening && [ -n "$(main_window)" ] || { echo "PlotJuggler's UDP server did not start" >&2; exit 1; }
echo "plotjuggler-screenshot: PlotJuggler's UDP Server listens on 127.0.0.1:$PJ_PORT"
MAIN="$(main_window)"
xdotool windowmove "$MAIN" 0 0 windowsize "$MAIN" 1600 900

# 4. MoDD's delivered values to PlotJuggler, as a viewer of the base station.
.venv/bin/modd-plotjuggler --udp "127.0.0.1:$PJ_PORT" --drone usv \
  --modd-connect "tcp/127.0.0.1:$MODD_ZENOH_PORT" \
  --credentials "$MODD_DATA/credentials/viewer.cred" >"$WORK/modd-plotjuggler.log" 2>&1 &
OUT_PID=$!

# 5. Once the series exist (PlotJuggler 3.9 drops a layout's curves it has not
# received yet), the layout: the Layout panel's load button, then its path in
# the file dialog.
sleep 8
xdotool mousemove 77 143 click 1
for _ in $(seq 40); do
  w="$(xdotool search --onlyvisible --pid "$PJ_PID" --name 'Open Layout' 2>/dev/null | head -1)"
  [ -n "$w" ] && break
  sleep 0.25
done
[ -n "$w" ] || { echo "PlotJuggler's Open Layout dialog did not open" >&2; exit 1; }
for _ in 1 2 3; do  # the dialog takes its keys once it has listed the directory
  sleep 1.5
  # its File name field (the dialog is centred on the 1600x900 main window)
  xdotool mousemove 791 559 click 1 sleep 0.3 type --delay 20 "$WORK/layout.xml"
  xdotool key Return
  sleep 1.5
  [ -z "$(xdotool search --onlyvisible --pid "$PJ_PID" --name 'Open Layout' 2>/dev/null)" ] && break
done
# Any question the layout asks (curves not received yet): the default answer.
for w in $(xdotool search --onlyvisible --pid "$PJ_PID" --name 'Warning' 2>/dev/null); do
  xdotool windowfocus --sync "$w" 2>/dev/null && xdotool key --clearmodifiers Return || true
done
sleep "$PLOT_S"
kill -0 "$OUT_PID" 2>/dev/null || exit 1
kill -0 "$PJ_PID" 2>/dev/null || exit 1
import -window root "$OUT/ecosystem-plotjuggler.png"
echo "plotjuggler-screenshot: wrote $OUT/ecosystem-plotjuggler.png"
