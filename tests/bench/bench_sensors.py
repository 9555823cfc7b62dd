"""modd-sensors under the issue's load, side by side with a hand-written driver
(pynmea2 parsing, pymodbus's client polling the sondes, the Python publisher
client the generated stub uses) in the same run: 20 NMEA devices at 10 Hz and 4
Modbus devices at 1 Hz, each on a pseudo-terminal the bench writes (Modbus:
answers read requests).

Each reader publishes to a stand-in ingress in this process (the real
protocol: HELLO, CATALOGUE, REGISTER, SAMPLES, ACK), which notes when each
sample arrives. An NMEA device's HDT heading carries a sequence number, so
receive-to-ingress latency is the sample's arrival at the ingress minus the
time its line was written. CPU (% of one core) and RSS are the reader
process's, from /proc, over the measured seconds. With ``--runs N`` the two
readers take turns N times and each figure is the median of its N runs (the
machine is shared: one run says little).

    .venv/bin/python tests/bench/bench_sensors.py [--seconds 20] [--runs 1]

Goal (issue 32): modd-sensors CPU <= 3 % of one core, RSS <= 60 MB,
latency p99 <= 5 ms. Asserts nothing.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import statistics
import subprocess
import sys
import tempfile
import textwrap
import threading
import time
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
sys.path[:0] = [str(HERE), str(HERE.parent / "sensors")]

from benchkit.footprint import Sampler  # noqa: E402
from benchkit.report import table  # noqa: E402
from ingress_stub import RecordingIngress  # noqa: E402
from modd.sensors.nmea import sentence  # noqa: E402
from modd.sensors.plan import plan_sensors  # noqa: E402
from modd.sim.instruments import open_device  # noqa: E402
from modd.sim.wire import modbus_reply, registers  # noqa: E402

NMEA_DEVICES, MODBUS_DEVICES, NMEA_HZ = 20, 4, 10


def model_text(devices: Path) -> str:
    nmea = "\n".join(
        f'Sensor g{i} kind nmea on "{devices}/g{i}" measures {{ seq(NONE, float64) from '
        f'sentence HDT.heading; lat("deg", float64) from sentence GGA.lat; }}'
        for i in range(NMEA_DEVICES)
    )
    sondes = "\n".join(
        f'Sensor s{i} kind modbus on "{devices}/s{i}" measures {{ ph(NONE) from register 0 '
        f"float32; o2(NONE) from register 2 uint16 scale 0.01; }}"
        for i in range(MODBUS_DEVICES)
    )
    fast = ", ".join(f'"b.g{i}.seq", "b.g{i}.lat"' for i in range(NMEA_DEVICES))
    slow = ", ".join(f'"b.s{i}.ph", "b.s{i}.o2"' for i in range(MODBUS_DEVICES))
    return textwrap.dedent(f"""
        Drone b {{ Sensors {{ {nmea} {sondes} }} }}
        PubBroker("127.0.0.1":7171, "/tmp/unused"); SubBroker("127.0.0.1":7272, "/tmp/unused");
        Publishers {{ Publisher nav(0.1, {fast}); Publisher water(1.0, {slow}); }}""")


class Ingress(RecordingIngress):
    """The PubBroker's ingress as far as a publisher sees it; notes each sample's arrival."""

    def __init__(self, path: Path) -> None:
        self.arrivals: list[tuple[float, int]] = []  # (arrival monotonic_ns, seq)
        self.count = 0
        super().__init__(path, "b")

    def received(self, samples: list[tuple[str, int, float]]) -> None:
        now = time.monotonic_ns()
        with self.lock:
            self.arrivals += [(now, int(v)) for t, _, v in samples if t.endswith(".seq")]
            self.count += len(samples)


class Devices:
    """The instruments: NMEA at 10 Hz (HDT with a sequence number, and a GGA), Modbus
    answering reads. ``written[seq]`` is when each HDT was written (monotonic ns)."""

    def __init__(self, model: dict[str, Any]) -> None:
        self.plans = plan_sensors(model)
        self.masters = {p.name: open_device(Path(p.device.path)) for p in self.plans}
        self.written: dict[int, int] = {}
        self.stop = threading.Event()
        self.threads = [
            threading.Thread(target=self._nmea, daemon=True),
            threading.Thread(target=self._modbus, daemon=True),
        ]
        for th in self.threads:
            th.start()

    def _nmea(self) -> None:
        seq, tick, first = 0, 0, time.monotonic()
        gga = sentence(
            "GN",
            "GGA",
            [
                "101500.00",
                "4742.0000",
                "N",
                "00321.0000",
                "W",
                "1",
                "09",
                "0.9",
                "4.2",
                "M",
                "50.1",
                "M",
                "",
                "",
            ],
        )
        while not self.stop.wait(max(0.0, first + tick / NMEA_HZ - time.monotonic())):
            for p in self.plans:
                if p.kind != "nmea":
                    continue
                seq += 1
                line = f"{sentence('HE', 'HDT', [str(seq), 'T'])}\r\n{gga}\r\n".encode()
                self.written[seq] = time.monotonic_ns()
                with contextlib.suppress(BlockingIOError):  # nobody reads: talk anyway
                    os.write(self.masters[p.name], line)
            tick += 1

    def _modbus(self) -> None:
        import select

        sondes = {self.masters[p.name]: p for p in self.plans if p.kind == "modbus"}
        regs = {fd: registers(p, {m.topic: 7.25 for m in p.mappings}) for fd, p in sondes.items()}
        while not self.stop.is_set():
            ready, _, _ = select.select(list(sondes), [], [], 0.1)
            for fd in ready:
                request = os.read(fd, 256)
                reply = modbus_reply(request[:8], regs[fd]) if len(request) >= 8 else None
                if reply:
                    os.write(fd, reply)

    def close(self) -> None:
        self.stop.set()
        for th in self.threads:
            th.join(5)
        for fd in self.masters.values():
            os.close(fd)


HAND_DRIVER = r"""
import sys, threading, time, serial, pynmea2
from modd.publisher import Publisher
pub = Publisher("nav", sys.argv[1])
def read(path, name):
    port = serial.Serial(path, 9600, timeout=0.1)
    buf = b""
    while True:
        buf += port.read(port.in_waiting or 1)
        *lines, buf = buf.split(b"\n")
        for line in lines:
            try:
                msg = pynmea2.parse(line.decode().strip(), check=True)
            except (pynmea2.ParseError, UnicodeDecodeError):
                continue
            now = time.time_ns()
            if msg.sentence_type == "HDT":
                pub.publish(f"b.{name}.seq", now, float(msg.heading))
            elif msg.sentence_type == "GGA":
                pub.publish(f"b.{name}.lat", now, msg.latitude)
def poll(path, name):
    from pymodbus.client import ModbusSerialClient as Client
    client = Client(path, baudrate=9600, timeout=0.5, retries=0)
    client.connect()
    while True:
        due = time.monotonic() + 1.0
        r = client.read_holding_registers(0, count=3, device_id=1)
        now = time.time_ns()
        if not r.isError():
            ph = client.convert_from_registers(r.registers[:2], Client.DATATYPE.FLOAT32)
            water.publish(f"b.{name}.ph", now, ph)
            water.publish(f"b.{name}.o2", now, r.registers[2] * 0.01)
        time.sleep(max(0.0, due - time.monotonic()))
water = Publisher("water", sys.argv[1])
for path in sys.argv[2:]:
    name = path.rsplit("/", 1)[1]
    worker = poll if name.startswith("s") else read
    threading.Thread(target=worker, args=(path, name), daemon=True).start()
threading.Event().wait()
"""


def measure(
    name: str, argv: list[str], ingress: Ingress, devices: Devices, seconds: float
) -> list[object]:
    proc = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        time.sleep(3.0)  # devices opened, publishers connected
        with ingress.lock:
            ingress.arrivals.clear()
            before = ingress.count
        sampler = Sampler(proc.pid).start()
        time.sleep(seconds)
        fp = sampler.stop()
        with ingress.lock:
            arrivals, samples = list(ingress.arrivals), ingress.count - before
    finally:
        proc.terminate()
        proc.wait(10)
    lat = sorted((t - devices.written[s]) / 1e6 for t, s in arrivals if s in devices.written)

    def p(q: float) -> float:
        return lat[min(len(lat) - 1, int(q * len(lat)))] if lat else float("nan")

    return [
        name,
        round(fp.cpu_percent, 2),
        round(fp.rss_peak_kb / 1024, 1),
        round(samples / seconds),
        *(round(p(q), 2) for q in (0.5, 0.9, 0.99)),
        round(lat[-1], 1) if lat else "—",
    ]


def median_rows(runs: list[list[list[object]]]) -> list[list[object]]:
    """Per reader, the median of each figure over the runs."""
    out = []
    for i, first in enumerate(runs[0]):
        row: list[object] = [first[0]]
        for col in range(1, len(first)):
            cells = [r[i][col] for r in runs]
            xs = sorted(float(c) for c in cells if isinstance(c, (int, float)))
            row.append(round(statistics.median(xs), 2) if xs else "—")
        out.append(row)
    return out


def one_run(root: Path, ingress: Ingress, devices: Devices, seconds: float) -> list[list[object]]:
    bin_dir = Path(sys.executable).parent
    address = f"unix:{root / 'ingress.sock'}"
    model = str(root / "model.json")
    sensors = [str(bin_dir / "modd-sensors"), "--model", model, "--ingress", address]
    hand = [sys.executable, "-c", HAND_DRIVER, address, *(p.device.path for p in devices.plans)]
    return [
        measure("modd-sensors", sensors, ingress, devices, seconds),
        measure("hand driver: pynmea2, pymodbus + Publisher", hand, ingress, devices, seconds),
    ]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seconds", type=float, default=20.0)
    ap.add_argument("--runs", type=int, default=1, help="turns per reader; medians reported")
    args = ap.parse_args()
    from modd_model import parse_text

    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        doc, _ = parse_text(model_text(root / "dev"))
        (root / "model.json").write_text(json.dumps(doc))
        ingress = Ingress(root / "ingress.sock")
        devices = Devices(doc)
        runs = [one_run(root, ingress, devices, args.seconds) for _ in range(args.runs)]
        devices.close()
        ingress.close()
    print(
        f"bench_sensors: {NMEA_DEVICES} NMEA devices at {NMEA_HZ} Hz + {MODBUS_DEVICES} Modbus "
        f"at 1 Hz; {args.seconds:g} s measured per reader, median of {args.runs} run(s), "
        f"{os.cpu_count()} cores"
    )
    heads = ["reader", "CPU % of a core", "RSS MB", "samples/s", "latency p50 ms", "p90 ms"]
    print(table([*heads, "p99 ms", "max ms"], median_rows(runs)))


if __name__ == "__main__":
    main()
