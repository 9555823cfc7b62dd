"""Processes that end and devices that are held: a device another process holds
(its exclusive lock, as an orphaned reader of an earlier run would) is reported
busy with that process's pid, never "silent", and read as soon as it is let go;
``modd-sensors`` exits within 2 s of SIGTERM with its PubBroker gone
(docs/sensors.md, "Busy devices and stopping")."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

from devices import PtyDevice, nmea, wait_until
from modd_model import parse_text
from test_sensors_faults import Reader

HOLD = """
import fcntl, os, sys, time
fd = os.open(sys.argv[1], os.O_RDWR | os.O_NOCTTY)
fcntl.flock(fd, fcntl.LOCK_EX)
print("held", flush=True)
time.sleep(60)
"""


def _model(tmp: Path) -> dict[str, object]:
    doc, _ = parse_text(f'''
Drone usv {{ Sensors {{
    Sensor sounder kind nmea on "{tmp}/sounder" measures {{ depth(METER) from sentence DPT.depth; }}
}} }}
PubBroker("127.0.0.1":7171, "/l"); SubBroker("127.0.0.1":7272, "/c");
Publishers {{ Publisher p(0.1, "usv.sounder.depth"); }}''')
    return doc


def test_a_held_device_is_busy_with_its_holder_then_read(tmp_path: Path) -> None:
    sounder = PtyDevice(tmp_path / "sounder")
    holder = subprocess.Popen(
        [sys.executable, "-c", HOLD, str(tmp_path / "sounder")], stdout=subprocess.PIPE, text=True
    )
    reader = None
    try:
        assert holder.stdout is not None and holder.stdout.readline().strip() == "held"
        reader = Reader(_model(tmp_path))
        wait_until(lambda: bool(reader.health("sounder")["busy"]), 5, "the device reported busy")
        busy = str(reader.health("sounder")["busy"])
        assert f"pid {holder.pid} " in busy, busy
        time.sleep(2.6)  # past the silence limit (2 s): busy is not silence
        h = reader.health("sounder")
        assert not h["silent"] and not h["connected"], h
        holder.kill()
        holder.wait(5)
        wait_until(lambda: reader.health("sounder")["connected"], 5, "opened once let go")
        assert reader.health("sounder")["busy"] == ""
        sounder.write(nmea("SDDPT,4.25,0.5"))
        wait_until(lambda: reader.out.values("depth") == [4.25], 5, "the value after the hold")
    finally:
        holder.kill()
        holder.wait(5)
        assert holder.stdout is not None
        holder.stdout.close()
        if reader is not None:
            reader.close()
        sounder.close()


def test_sigterm_with_the_pubbroker_gone_exits_within_2_s(tmp_path: Path) -> None:
    """Ten publishers, an ingress socket nobody listens on: each flush used to wait its
    own timeout, one after the other."""
    publishers = "\n".join(f'Publisher p{i}(0.1, "usv.s{i}.depth");' for i in range(10))
    sensors = "\n".join(
        f'Sensor s{i} kind nmea on "{tmp_path}/s{i}" measures '
        "{ depth(METER) from sentence DPT.depth; }"
        for i in range(10)
    )
    (tmp_path / "model.modd").write_text(f"""
Drone usv {{ Sensors {{ {sensors} }} }}
PubBroker("127.0.0.1":7171, "/l"); SubBroker("127.0.0.1":7272, "/c");
Publishers {{ {publishers} }}""")
    devices = [PtyDevice(tmp_path / f"s{i}") for i in range(10)]
    log = tmp_path / "sensors.log"
    with log.open("w") as out:
        proc = subprocess.Popen(
            [
                str(Path(sys.executable).parent / "modd-sensors"),
                "--model",
                str(tmp_path / "model.modd"),
                "--ingress",
                f"unix:{tmp_path}/gone.sock",  # no PubBroker there
            ],
            stdout=out,
            stderr=subprocess.STDOUT,
        )
    try:
        wait_until(lambda: "10 sensors" in log.read_text(), 20, "modd-sensors started")
        for d in devices:
            d.write(nmea("SDDPT,1.5,0.5"))  # queued for a broker that is not there
        time.sleep(0.5)
        t0 = time.monotonic()
        proc.send_signal(signal.SIGTERM)
        proc.wait(10)
        took = time.monotonic() - t0
        assert took < 2.0, (took, log.read_text())
        assert proc.returncode == 0, log.read_text()
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        for d in devices:
            d.close()
