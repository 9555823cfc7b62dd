"""Backfill pacing and the SiK budget (issue 15; docs/benchmarks.md, "Backfill").

An archive holding MINUTES of one 25 Hz float32 topic (written beside the
PubBroker in its own file format with the official `mcap` writer, so the run
need not last that long), the real PubBroker (build/bin/modd-pubbroker), and a
link client that authenticates and asks for every raw sample (ALL, 1 s
windows) at RATE bytes/s (the emulated SiK budget with ECC, 3,600 B/s). Prints:

* the backfill's duration against the time the budget allows (bytes on the
  wire, IP and TCP headers included, / RATE), and the samples received;
* the largest number of wire bytes drone -> base in any 1 s interval (tshark on
  lo) against the cap plus one frame.

With ``--live``, then: scenario 1 over the emulated radio, live latency (window end ->
delivery) in phases without and with a running backfill, side by side
(benchkit/backfill_live.py): p50/p99 per pair, the median p99 of each, their ratio and
the machine's load.

    .venv/bin/python tests/bench/bench_backfill.py [--minutes 10] [--rate 3600]
    .venv/bin/python tests/bench/bench_backfill.py --live [--live-rate 600] [--outage 80]
"""

from __future__ import annotations

import argparse
import json
import os
import socket
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "subbroker"))
sys.path.insert(0, str(Path(__file__).parent))

from benchkit.capture import check_capture, tcp_packets  # noqa: E402
from benchkit.report import table  # noqa: E402
from modd.link import backfill as bf  # noqa: E402
from modd.link.auth import client_handshake  # noqa: E402
from modd.link.frames import Aggregation, ValueType  # noqa: E402
from subbroker_harness import KEY, PUBBROKER, Proc, free_port, wait_port  # noqa: E402

TOPIC = "usv.imu.accel_x"
HZ = 25


def write_archive(directory: Path, start_ns: int, seconds: int) -> int:
    """A closed MCAP like the PubBroker's: one channel, {"value": v} JSON messages."""
    from mcap.writer import CompressionType, Writer

    directory.mkdir(parents=True, exist_ok=True)
    n = seconds * HZ
    with (directory / "modd-20000101T000000Z-0000.mcap").open("wb") as f:
        w = Writer(f, compression=CompressionType.ZSTD, chunk_size=256 * 1024)
        w.start(profile="", library="bench")
        sid = w.register_schema("modd.sample.float32", "jsonschema", b"{}")
        ch = w.register_channel(TOPIC, "json", sid)
        for i in range(n):
            t = start_ns + i * (1_000_000_000 // HZ)
            w.add_message(ch, t, json.dumps({"value": float(i % 1000) / 8}).encode(), t, i)
        w.finish()  # type: ignore[no-untyped-call]
    return n


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--minutes", type=float, default=10.0)
    ap.add_argument("--rate", type=int, default=3600, help="pace in bytes/s (SiK with ECC)")
    ap.add_argument(
        "--live", action="store_true", help="also live latency with vs without a running backfill"
    )
    ap.add_argument("--live-only", action="store_true", help="only the --live part")
    ap.add_argument("--live-rate", type=int, default=600, help="the radio's bytes/s (--live)")
    ap.add_argument("--outage", type=float, default=80.0, help="outage to fill, s (< 90) (--live)")
    ap.add_argument(
        "--phase", type=float, default=6.0, help="seconds of a phase without backfill (--live)"
    )
    ap.add_argument("--pairs", type=int, default=5, help="at most 5 pairs (--live)")
    args = ap.parse_args()
    pacing = 0 if args.live_only else pace(args)
    if not (args.live or args.live_only):
        return pacing
    return max(pacing, live(args))


def live(args: argparse.Namespace) -> int:
    from benchkit.backfill_live import report, run

    with tempfile.TemporaryDirectory(prefix="modd-bench-backfill-live-") as d:
        pairs, facts = run(Path(d), args.live_rate, args.outage, args.phase, args.pairs)
    if not pairs:
        print("live latency: no pair measured (nothing to backfill)")
        return 1
    rows, ratio = report(pairs, facts)
    print(
        f"\nlive latency (window end -> delivery, ms), scenario 1 over udp through the radio "
        f"emulator at {args.live_rate} B/s, after a {args.outage:g} s outage; phases of "
        f"{args.phase:g} s without a backfill / with one subscriber's gaps filled\n"
    )
    print(
        table(
            [
                "pair (gap of)",
                "values",
                "p50",
                "p99",
                "values (bf)",
                "p50 (bf)",
                "p99 (bf)",
                "windows filled",
                "backfill B/s",
                "radio B/s down",
                "radio queue drops",
            ],
            rows,
        )
    )
    before, after = facts["load_before"], facts.get("load_after", (0, 0, 0))
    print(
        f"\np99 with / without backfill (medians of {len(pairs)} pairs): {ratio:.3f} "
        f"({ratio - 1:+.1%}; target within +10%)"
    )
    print(
        f"load average (1 min) {before[0]:.1f} before, {after[0]:.1f} after, on "
        f"{os.cpu_count()} cores; {' '.join(facts.get('radio', []))}"
    )
    return 0


def pace(args: argparse.Namespace) -> int:
    check_capture()
    tmp = Path(tempfile.mkdtemp(prefix="modd-bench-backfill-"))
    seconds = int(args.minutes * 60)
    start_ns = (time.time_ns() // 1_000_000_000 - seconds - 60) * 1_000_000_000
    samples = write_archive(tmp / "archive", start_ns, seconds)
    link, ingress = free_port(), free_port()
    cfg = {
        "name": "usv",
        "link": {"host": "127.0.0.1", "port": link, "key": "env:MODD_LINK_KEY"},
        "ingress": {"host": "127.0.0.1", "port": ingress},
        "archive": {"dir": str(tmp / "archive"), "flush_interval_ms": 200},
        "topics": [{"name": TOPIC, "type": "float32"}],
        "status_period_s": 0,
    }
    (tmp / "pb.json").write_text(json.dumps(cfg))
    pb = Proc("pb", [str(PUBBROKER), "--config", str(tmp / "pb.json")], tmp / "pb.log")
    budget_s = 0.0
    try:
        wait_port(link)
        pcap = tmp / "bf.pcap"
        tshark = Proc(
            "tshark",
            ["tshark", "-q", "-i", "lo", "-f", f"tcp port {link}", "-w", str(pcap)],
            tmp / "tshark.log",
        )
        assert tshark.wait_log("Capture started", 15), tshark.log()
        time.sleep(0.5)
        sock = socket.create_connection(("127.0.0.1", link))
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        _, splitter = client_handshake(sock, KEY.encode())
        req = bf.BackfillRequest(
            1, TOPIC, ValueType.FLOAT32, Aggregation.ALL, 1_000_000, start_ns, seconds, 0, args.rate
        )
        began = time.monotonic()
        sock.sendall(bf.encode(req))
        got = frames = 0
        first_ns = last_ns = 0
        done = False
        while not done:
            data = sock.recv(65536)
            if not data:
                raise RuntimeError("the PubBroker closed the link")
            for f in splitter.feed(data):
                if f.type == bf.BackfillType.DATA:
                    d = bf.decode_data(f, req.kind())
                    got += sum(len(v.samples) for v in d.values)
                    frames += 1
                    last_ns = time.monotonic_ns()
                    first_ns = first_ns or last_ns
                elif f.type == bf.BackfillType.END:
                    done = True
        took = time.monotonic() - began
        sock.close()
        time.sleep(0.5)
        tshark.stop()
    finally:
        pb.stop()
    down = [(t, n, p) for t, s, n, p in tcp_packets(pcap) if s == link]
    segments = [(t, n) for t, n, p in down if p > 0]
    wire = sum(n for _, n in segments)
    biggest = max(n for _, n in segments)
    worst = 0
    for i, (t0, _) in enumerate(segments):
        worst = max(worst, sum(n for t, n in segments[i:] if t < t0 + 1.0))
    budget_s = wire / args.rate
    print(
        f"backfill: {args.minutes:g} min of one {HZ} Hz float32 topic, ALL in 1 s windows, "
        f"pace {args.rate} B/s\n"
    )
    print(
        table(
            ["figure", "value"],
            [
                ["samples in the archive / received", f"{samples} / {got}"],
                ["BACKFILL_DATA frames", frames],
                ["wire bytes drone->base (IP+TCP, data segments)", wire],
                ["time the budget allows (wire bytes / pace)", f"{budget_s:.1f} s"],
                ["backfill took (request -> END)", f"{took:.1f} s ({took / budget_s - 1:+.1%})"],
                ["largest data segment", f"{biggest} B"],
                [
                    "most wire bytes in any 1 s",
                    f"{worst} B (cap + one frame = {args.rate + biggest} B)",
                ],
            ],
        )
    )
    return 0 if got == samples and worst <= args.rate + biggest else 1


if __name__ == "__main__":
    sys.exit(main())
