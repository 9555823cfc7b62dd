"""The MoDD link over a radio, side by side in one run (issue 14's table):
real PubBroker and SubBroker over udp and over serial, the publisher load at
the sensors' rates, the link emulator (modd-radio) in the path counting what
it carries: UDP payloads (+ 28 B of IPv4 + UDP headers per datagram) or the
bytes through the pseudo-terminals (serial framing included).

Rows: scenario 1 and 2 over udp, scenario 1 over serial, base -> drone while
nothing is lost, windows delivered at 5 % and 20 % random loss (and how many
within 3 x the accepted delay), against the on-board archive; then MAVLink 2
streaming of the same values (pymavlink, one NAMED_VALUE_FLOAT per value at
the subscription rates) through the same emulator. Asserts nothing.

    .venv/bin/python tests/bench/bench_radio.py [--seconds 30] [--json F]
"""

from __future__ import annotations

import argparse
import json
import re
import sys
import time
from pathlib import Path
from tempfile import TemporaryDirectory
from typing import Any

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "subbroker"))
sys.path.insert(0, str(HERE))

from modd.ports import free_port  # noqa: E402
from modd_model import load_model  # noqa: E402
from radio_harness import (  # noqa: E402
    start_pubbroker_dgram,
    start_radio_serial,
    start_radio_udp,
    subbroker_dgram_config,
)
from subbroker_harness import (  # noqa: E402
    Proc,
    model_copy,
    processes,
    read_archive,
    start_load,
    start_subbroker,
    wait_port,
)

UDP_IP = 28
LINE = re.compile(
    r"radio: base->drone passed (\d+) \((\d+) B\).*?; drone->base passed (\d+) "
    r"\((\d+) B\)"
)
TARGETS = {"s1_udp": 110.0, "s2_udp": 110.0, "s1_serial": 85.0, "up": 5.0}


def _counts(radio: Proc) -> list[tuple[float, tuple[int, int, int, int]]]:
    out = []
    for ln in radio.log().splitlines():
        m = LINE.search(ln)
        if m:
            out.append((0.0, tuple(int(x) for x in m.groups())))
    return out  # type: ignore[return-value]


def _snapshot(radio: Proc) -> tuple[int, int, int, int]:
    c = _counts(radio)
    return c[-1][1] if c else (0, 0, 0, 0)


def _watch(zport: int) -> Any:
    from modd.zenoh_session import client_settings, open_session, wait_connected
    from subbroker_harness import shared_credentials

    from conftest import Collector

    wait_port(zport, 60)
    session = open_session(
        client_settings(f"tcp/127.0.0.1:{zport}", shared_credentials().cred_file("backend"))
    )
    assert wait_connected(session)
    got = Collector()
    session.declare_subscriber("modd/*/sub/*", got.on_sample)
    return session, got


def run_link(tmp: Path, scenario: str, transport: str, spec: str, seconds: float) -> dict[str, Any]:
    """One run; bytes/s each way as the emulator counted them, and delivery."""
    model = model_copy(tmp, scenario)
    zport, ingress = free_port(), free_port()
    radio_spec = spec or "seed=1"
    if transport == "udp":
        port, relay = free_port("udp"), free_port("udp")
        pb = start_pubbroker_dgram(tmp, model, {"transport": "udp", "port": port}, ingress)
        radio = start_radio_udp(tmp, port, radio_spec, relay=relay)[0]
        cfg = subbroker_dgram_config(tmp, model, f"127.0.0.1:{relay}", zport, "udp")
    else:
        radio, base, drone = start_radio_serial(tmp, radio_spec)
        pb = start_pubbroker_dgram(
            tmp, model, {"transport": "serial", "device": drone, "port": 1}, ingress
        )
        cfg = subbroker_dgram_config(tmp, model, "127.0.0.1:1", zport, "serial", device=base)
    sb = start_subbroker(tmp, cfg)
    session = None
    try:
        session, got = _watch(zport)
        if not sb.wait_log("running", 60):
            raise RuntimeError(sb.log()[-2000:])
        load = start_load(tmp, model, ingress, seconds + 4)
        time.sleep(3.0)
        t0, c0 = time.monotonic(), _snapshot(radio)
        time.sleep(seconds)
        t1, c1 = time.monotonic(), _snapshot(radio)
        load.p.wait(30)
        time.sleep(4.0)  # the last NACKs
        values = got.snapshot()
        with processes(load):
            pass
    finally:
        with processes(radio, pb, sb):
            pass
        if session is not None:
            session.close()
    span = t1 - t0
    up_pkts, up_b, down_pkts, down_b = (b - a for a, b in zip(c0, c1, strict=True))
    header = UDP_IP if transport == "udp" else 0
    archive = read_archive(tmp / "archive", model)
    delivered, expected, prompt = delivery(values, archive)
    return {
        "scenario": scenario,
        "transport": transport,
        "radio": spec,
        "down_Bps": round((down_b + header * down_pkts) / span, 1),
        "up_Bps": round((up_b + header * up_pkts) / span, 1),
        "down_packets_per_s": round(down_pkts / span, 3),
        "delivered": delivered,
        "expected": expected,
        "within_3_delays": prompt,
    }


def delivery(
    values: dict[str, list[Any]], archive: dict[str, list[tuple[int, Any]]]
) -> tuple[int, int, int]:
    """(windows delivered, windows expected, delivered within 3 s) over the
    subscribers' windows that hold archived samples, away from the run's edges."""
    delivered = expected = prompt = 0
    for vals in values.values():
        if not vals:
            continue
        period = int(float(vals[0].period_s) * 1e9)
        if period > 1_000_000_000:
            continue
        stamps = sorted(t for t, _ in archive.get(vals[0].topic, []))
        if not stamps:
            continue
        got = {v.end_ns: v for v in vals if v.value is not None}
        lo, hi = stamps[0] + 2 * 10**9, stamps[-1] - 2 * 10**9
        end = min(got) if got else lo
        while end < lo:
            end += period
        import bisect

        while end <= hi:
            i = bisect.bisect_left(stamps, end - period)
            if i < len(stamps) and stamps[i] < end:
                expected += 1
                v = got.get(end)
                if v is not None:
                    delivered += 1
                    prompt += (v.delivered_ns - v.end_ns) <= 3 * 10**9
            end += period
    return delivered, expected, prompt


def run_mavlink(tmp: Path, scenario: str, spec: str, seconds: float) -> dict[str, Any]:
    """MAVLink 2 streaming of the same values: one NAMED_VALUE_FLOAT per value a
    subscription needs, at its rate, over UDP through the same emulator."""
    import socket

    from pymavlink.dialects.v20 import common as mavlink2  # type: ignore[import-untyped]

    model = load_model(model_copy(tmp, scenario))
    # one message per value a subscription receives, at its rate
    periods = [float(s["periodS"]) for s in model["subscribers"]]
    sink = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sink.bind(("127.0.0.1", 0))
    relay = free_port("udp")
    radio = start_radio_udp(tmp, sink.getsockname()[1], spec or "seed=1", "mavradio", relay=relay)[
        0
    ]
    # the drone sends to the relay's far side: here the "base" sends, the "drone" receives,
    # so the relay's base->drone direction carries the stream
    out = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    mav = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
    mav.robust_parsing = True
    time.sleep(0.5)
    due = [0.0] * len(periods)
    start = time.monotonic()
    sent = received = 0
    sink.setblocking(False)
    c0: tuple[int, int, int, int] | None = None
    t0 = start
    try:
        while (now := time.monotonic()) - start < seconds + 2:
            if c0 is None and now - start >= 2:
                t0, c0 = now, _snapshot(radio)
            for i, p in enumerate(periods):
                if now >= due[i]:
                    due[i] = (due[i] or now) + p
                    msg = mavlink2.MAVLink_named_value_float_message(
                        int((now - start) * 1000), f"v{i}".encode(), float(i)
                    )
                    out.sendto(msg.pack(mav), ("127.0.0.1", relay))
                    sent += 1
            while True:
                try:
                    sink.recv(512)
                    received += 1
                except BlockingIOError:
                    break
            time.sleep(0.005)
        time.sleep(1.2)
        t1, c1 = time.monotonic(), _snapshot(radio)
    finally:
        with processes(radio):
            pass
        out.close()
        sink.close()
    c0 = c0 or (0, 0, 0, 0)
    pkts, b = c1[0] - c0[0], c1[1] - c0[1]
    return {
        "scenario": scenario,
        "transport": "udp (MAVLink 2)",
        "radio": spec,
        "down_Bps": round((b + UDP_IP * pkts) / (t1 - t0), 1),
        "up_Bps": 0.0,
        "down_packets_per_s": round(pkts / (t1 - t0), 3),
        "delivered": received,
        "expected": sent,
        "within_3_delays": received,
    }


def run_zenoh(tmp: Path, number: int, spec: str, seconds: float) -> dict[str, Any]:
    """zenoh over UDP through the same emulator: a drone-side router with egress
    downsampling per subscriber key at the subscription's rate (it drops
    samples, it does not aggregate), a base-side peer subscribing to every key."""
    import struct

    from benchkit.scenario import load
    from modd.zenoh_session import ZenohSettings, open_session

    sc = load(number)
    port, relay = free_port("udp"), free_port("udp")
    keys: list[tuple[str, str, float]] = [
        (f"bench/{sc.drone}/sub/{s.name}", s.topic, 1 / float(s.period_s)) for s in sc.subscriptions
    ]
    plan = {"publishers": [[float(p), ts] for p, ts in sc.publishers], "keys": keys}
    drone = Proc(
        "zenoh-drone",
        [
            sys.executable,
            str(HERE / "benchkit" / "zenoh_drone.py"),
            "--listen",
            f"udp/127.0.0.1:{port}",
            "--plan",
            json.dumps(plan),
            "--seconds",
            str(seconds + 30),
        ],
        tmp / "zenoh-drone.log",
    )
    radio = start_radio_udp(tmp, port, spec or "seed=1", "zradio", relay=relay)[0]
    received = [0]
    session = None
    try:
        if not drone.wait_log("ready", 30):
            raise RuntimeError(drone.log()[-2000:])
        session = open_session(ZenohSettings(mode="peer", connect=(f"udp/127.0.0.1:{relay}",)))

        def on_sample(sample: Any) -> None:
            struct.unpack("<qfI", sample.payload.to_bytes())
            received[0] += 1

        subs = [session.declare_subscriber(k, on_sample) for k, _, _ in keys]
        time.sleep(3.0)
        t0, c0, r0 = time.monotonic(), _snapshot(radio), received[0]
        time.sleep(seconds)
        t1, c1, r1 = time.monotonic(), _snapshot(radio), received[0]
        for sub in subs:
            sub.undeclare()  # type: ignore[no-untyped-call]
    finally:
        if session is not None:
            session.close()  # type: ignore[no-untyped-call]
        with processes(radio, drone):
            pass
    span = t1 - t0
    wanted = sum(span / float(s.period_s) for s in sc.subscriptions)
    return {
        "scenario": f"scenario{number}.modd",
        "transport": "udp (zenoh, downsampling)",
        "radio": spec,
        "down_Bps": round((c1[3] - c0[3] + UDP_IP * (c1[2] - c0[2])) / span, 1),
        "up_Bps": round((c1[1] - c0[1] + UDP_IP * (c1[0] - c0[0])) / span, 1),
        "down_packets_per_s": round((c1[2] - c0[2]) / span, 3),
        "delivered": r1 - r0,
        "expected": round(wanted),
        "within_3_delays": r1 - r0,
    }


def main() -> int:
    p = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    p.add_argument("--seconds", type=float, default=30.0)
    p.add_argument("--json", type=Path)
    args = p.parse_args()
    rows: list[dict[str, Any]] = []
    plan = [
        ("scenario1.modd", "udp", ""),
        ("scenario2.modd", "udp", ""),
        ("scenario1.modd", "serial", "packet=252"),
        ("scenario2.modd", "serial", "packet=252"),
        ("scenario1.modd", "udp", "loss=0.05,latency_ms=80,jitter_ms=20,seed=5"),
        ("scenario1.modd", "udp", "loss=0.20,latency_ms=80,jitter_ms=20,seed=6"),
    ]
    for scenario, transport, spec in plan:
        with TemporaryDirectory(prefix="modd-bench-radio-") as d:
            rows.append(run_link(Path(d), scenario, transport, spec, args.seconds))
            print(json.dumps(rows[-1]), flush=True)
    for scenario, spec in (
        ("scenario1.modd", ""),
        ("scenario2.modd", ""),
        ("scenario1.modd", "loss=0.05,seed=5"),
        ("scenario1.modd", "loss=0.20,seed=6"),
    ):
        with TemporaryDirectory(prefix="modd-bench-mav-") as d:
            try:
                rows.append(run_mavlink(Path(d), scenario, spec, args.seconds))
            except Exception as exc:  # a comparison row must not hide the others
                rows.append(
                    {
                        "scenario": scenario,
                        "transport": "udp (MAVLink 2)",
                        "radio": spec,
                        "error": str(exc),
                    }
                )
            print(json.dumps(rows[-1]), flush=True)
    for number, spec in ((1, ""), (2, ""), (1, "loss=0.05,seed=5"), (1, "loss=0.20,seed=6")):
        with TemporaryDirectory(prefix="modd-bench-zenoh-") as d:
            try:
                rows.append(run_zenoh(Path(d), number, spec, args.seconds))
            except Exception as exc:
                rows.append(
                    {
                        "scenario": f"scenario{number}.modd",
                        "transport": "udp (zenoh, downsampling)",
                        "radio": spec,
                        "error": str(exc),
                    }
                )
            print(json.dumps(rows[-1]), flush=True)
    print()
    print(
        "| scenario | transport | radio | drone→base B/s | base→drone B/s | packets/s | "
        "delivered | within 3× delay |"
    )
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for r in rows:
        if "error" in r:
            print(f"| {r['scenario']} | {r['transport']} | {r['radio']} | error: {r['error']} |")
            continue
        share = f"{100 * r['delivered'] / r['expected']:.2f} %" if r["expected"] else "—"
        prompt = f"{100 * r['within_3_delays'] / r['expected']:.2f} %" if r["expected"] else "—"
        print(
            f"| {r['scenario']} | {r['transport']} | {r['radio'] or '—'} | {r['down_Bps']} | "
            f"{r['up_Bps']} | {r['down_packets_per_s']} | {share} ({r['delivered']}/"
            f"{r['expected']}) | {prompt} |"
        )
    print(
        f"\ntargets: scenario 1 and 2 over udp <= {TARGETS['s1_udp']} B/s, scenario 1 over "
        f"serial <= {TARGETS['s1_serial']} B/s, base->drone <= {TARGETS['up']} B/s while "
        "nothing is lost, delivered >= 99.9 % / 99 % at 5 % / 20 % loss within 3 s"
    )
    if args.json:
        args.json.write_text(json.dumps(rows, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
