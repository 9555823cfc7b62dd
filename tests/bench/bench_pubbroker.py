"""PubBroker benchmarks: ingest throughput with the archive on, CPU and RSS at the scenario 2
load, and the link's bytes on the wire for scenarios 1 and 2 measured with tshark on lo
(IP and TCP headers included), printed beside the paper's figures and the planner's
prediction. Asserts nothing; prints the issue's targets beside the figures.

    .venv/bin/python tests/bench/bench_pubbroker.py [--seconds 30] [--ingest-samples 20000000]
                                                    [--json build/bench/pubbroker.json]

The base station is played by the Python link codec (tests/runtime/pubbroker_harness.py),
the load by the Python publisher client at 25 Hz. Needs tshark and the right to capture on
lo (root here); without them the wire figures are skipped, with a message.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import socket
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[2]
sys.path[:0] = [
    str(REPO / "tests" / "runtime"),
    str(REPO / "tests" / "subbroker"),
    str(REPO / "tests" / "bench"),
]

import numpy as np  # noqa: E402
from benchkit.capture import Capture, Wire  # noqa: E402
from benchkit.footprint import cpu_seconds  # noqa: E402
from modd.link.codec import varint  # noqa: E402
from modd.link.frames import ValueType  # noqa: E402
from modd.publisher import encode_hello, encode_register  # noqa: E402
from pubbroker_harness import (  # noqa: E402
    SCENARIOS,
    BaseStation,
    PubBroker,
    run_load,
    scenario_config,
)


def rss_kb(pid: int) -> tuple[int, int]:
    status = Path(f"/proc/{pid}/status").read_text()
    get = {ln.split(":")[0]: ln.split()[1] for ln in status.splitlines() if ln.startswith("Vm")}
    return int(get["VmRSS"]), int(get["VmHWM"])


def threads(pid: int) -> list[int]:
    return sorted(int(t) for t in os.listdir(f"/proc/{pid}/task"))


# ---- ingest ------------------------------------------------------------------------------


def ingest(tmp: Path, total: int, topics: int = 19, batch: int = 4096) -> dict[str, Any]:
    """Blasts pre-encoded SAMPLES frames over the Unix socket as fast as the broker reads them
    (archive on: zstd chunks, fsync per chunk); every sample is accepted and archived."""
    names = [f"usv.ins.t{i}" for i in range(topics)]
    b = PubBroker(
        tmp,
        [(n, "float32") for n in names],
        archive={"queue_limit_samples": 50_000_000, "fsync": "chunk", "flush_interval_ms": 1000},
        default_buffer_size=1000,
        log_period_s=1,
    ).start()
    assert b.proc is not None
    pid = b.proc.pid
    rec = np.dtype([("id", "u1"), ("ts", "<i8"), ("v", "<f4")])
    arr = np.zeros(batch, dtype=rec)
    arr["id"] = np.arange(batch) % topics
    arr["v"] = np.sin(np.arange(batch) * 0.01).astype(np.float32)
    head = bytes([0x03]) + varint(batch)
    frame_len = varint(len(head) + batch * rec.itemsize)
    s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    s.connect(b.unix_path)
    s.sendall(
        encode_hello("bench")
        + b"".join(encode_register(i, ValueType.FLOAT32, n) for i, n in enumerate(names))
    )
    main_tid = threads(pid)[0]
    cpu0, tcpu0 = cpu_seconds(pid), cpu_seconds(pid, main_tid)
    t0 = time.monotonic()
    ts0 = time.time_ns()
    sent = 0
    while sent < total:
        arr["ts"] = ts0 + np.arange(sent, sent + batch) // topics
        s.sendall(frame_len + head + arr.tobytes())
        sent += batch
    s.close()
    t_sent = time.monotonic() - t0
    ingest_cpu = cpu_seconds(pid, main_tid) - tcpu0
    # Wait until the writer has written every sample (the log line counts written chunks),
    # then the process's CPU covers ingest and archive: samples per CPU-second.
    deadline = time.monotonic() + 120
    while f"samples_archived={sent} " not in b.log() and time.monotonic() < deadline:
        time.sleep(0.05)
    t_archived = time.monotonic() - t0
    cpu = cpu_seconds(pid)
    rss, hwm = rss_kb(pid)
    b.stop()
    t_all = time.monotonic() - t0
    files = list(b.archive_dir.glob("*.mcap"))
    size = sum(f.stat().st_size for f in files)
    return {
        "samples": sent,
        "seconds_to_ingest": round(t_sent, 3),
        "samples_per_s_wall": round(sent / t_sent),
        "ingest_thread_cpu_s": round(ingest_cpu, 3),
        "samples_per_s_ingest_core": round(sent / ingest_cpu) if ingest_cpu else None,
        "seconds_until_archived_and_closed": round(t_all, 3),
        "samples_per_s_archived": round(sent / t_all),
        "seconds_until_archived": round(t_archived, 3),
        "process_cpu_s": round(cpu - cpu0, 3),
        "samples_per_cpu_s_archive_on": round(sent / (cpu - cpu0)),
        "rss_kb": rss,
        "peak_rss_kb": hwm,
        "archive_bytes": size,
        "archive_bytes_per_sample": round(size / sent, 2),
    }


# ---- a scenario on the wire ----------------------------------------------------------------


def wire_figures(wire: Wire) -> dict[str, Any]:
    rates = wire.rates()
    return {
        d: {
            "bytes_per_s": round(r["bytes_per_s"], 1),
            "packets_per_s": round(r["packets_per_s"], 2),
            "data_packets_per_s": round(r["data_packets_per_s"], 2),
            "pure_ack_bytes_per_s": round(r["ack_bytes_per_s"], 1),
            "seconds": round(span, 2),
        }
        for (d, r), span in zip(rates.items(), (wire.down_span, wire.up_span), strict=True)
    }


def start_steady(
    tmp: Path, config: Any, seconds: float, status_period_s: int, value: Any = None
) -> tuple[PubBroker, BaseStation, threading.Event, threading.Thread]:
    """The PubBroker with ``config`` from the Python base station, the 25 Hz load on every
    topic for ``seconds`` + 6 s (stopped by the event), after 2 s of warm-up; ``value(i, k)``:
    topic i's k-th sample (the harness's varied signal when None)."""
    names = [t.name for t in config.topics]
    b = PubBroker(
        tmp, [(t, "float32") for t in names], status_period_s=status_period_s, log_period_s=0
    ).start()
    base = BaseStation(b.link_port)
    base.configure(config)
    base.start()
    stop = threading.Event()
    loader = threading.Thread(
        target=run_load,
        args=(f"unix:{b.unix_path}", names, 25.0, seconds + 6.0),
        kwargs={"stop": stop} | ({"value": value} if value is not None else {}),
    )
    loader.start()
    time.sleep(2.0)  # steady state
    return b, base, stop, loader


def scenario(tmp: Path, n: int, seconds: float, status_period_s: int) -> dict[str, Any]:
    from modd_model import load_model
    from modd_plan import make_plan

    plan = make_plan(load_model(SCENARIOS / f"scenario{n}.modd")).to_json()
    config = scenario_config(n, status_period_s=status_period_s)
    b, base, stop, loader = start_steady(tmp, config, seconds, status_period_s)
    assert b.proc is not None
    pid = b.proc.pid
    result: dict[str, Any] = {
        "scenario": n,
        "seconds": seconds,
        "planner_drone_to_base_bytes_per_s": plan["predicted_link_bytes_per_s"]["drone_to_base"],
    }
    have_tshark = shutil.which("tshark") is not None and os.geteuid() == 0
    cap = Capture(tmp, b.link_port, seconds) if have_tshark else None
    cpu0, t0 = cpu_seconds(pid), time.monotonic()
    time.sleep(seconds)
    cpu1, t1 = cpu_seconds(pid), time.monotonic()
    rss, hwm = rss_kb(pid)
    if cap is not None:
        result["wire"] = wire_figures(cap.wait())
    else:
        result["wire"] = "skipped: tshark missing or no capture rights"
    stop.set()
    loader.join()
    got = base.snapshot()
    base.close()
    b.stop()
    result.update(
        {
            "cpu_percent": round(100 * (cpu1 - cpu0) / (t1 - t0), 3),
            "rss_kb": rss,
            "peak_rss_kb": hwm,
            "data_frames": got.data_frames,
            "mean_data_frame_bytes": round(got.data_bytes / max(got.data_frames, 1), 2),
        }
    )
    return result


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--seconds", type=float, default=30.0)
    ap.add_argument("--ingest-samples", type=int, default=20_000_000)
    ap.add_argument("--status-period", type=int, default=30)
    ap.add_argument("--json", type=Path, default=REPO / "build" / "bench" / "pubbroker.json")
    args = ap.parse_args()
    expected = json.loads((SCENARIOS / "expected.json").read_text())
    results: dict[str, Any] = {}
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        (tmp / "ingest").mkdir()
        r = ingest(tmp / "ingest", args.ingest_samples)
        results["ingest"] = r
        print(
            "\n== PubBroker ingest (archive on: zstd chunks, fsync every flush tick;"
            " 19 float32 topics, batches of 4096 over the Unix socket)"
        )
        print(
            f"  {r['samples']:,} samples in {r['seconds_to_ingest']} s: "
            f"{r['samples_per_s_wall']:,} samples/s wall; ingest thread CPU "
            f"{r['ingest_thread_cpu_s']} s -> {r['samples_per_s_ingest_core']:,} samples/s "
            f"per core (target >= 2,000,000)"
        )
        print(
            f"  all ingest + archive work: {r['process_cpu_s']} CPU-s ->"
            f" {r['samples_per_cpu_s_archive_on']:,} samples per CPU-second, archive on"
        )
        print(
            f"  archived and closed after {r['seconds_until_archived_and_closed']} s "
            f"({r['samples_per_s_archived']:,} samples/s end to end), "
            f"{r['archive_bytes_per_sample']} B/sample on disk, peak RSS {r['peak_rss_kb']} kB"
        )
        for n in (1, 2):
            (tmp / f"s{n}").mkdir()
            s = scenario(tmp / f"s{n}", n, args.seconds, args.status_period)
            results[f"scenario{n}"] = s
            paper = expected[f"scenario{n}"]["paper_bytes_per_s"]["drone_to_base_modd"]
            target = 300 if n == 1 else 140
            print(
                f"\n== Scenario {n}, {args.seconds:.0f} s steady state (25 Hz publisher,"
                f" STATUS every {args.status_period} s)"
            )
            w = s["wire"]
            if isinstance(w, dict):
                d2b, b2d = w["drone_to_base"], w["base_to_drone"]
                print(
                    f"  drone->base {d2b['bytes_per_s']} B/s ({d2b['packets_per_s']} pkt/s)"
                    f" | planner {s['planner_drone_to_base_bytes_per_s']} B/s"
                    f" | paper MoDD {paper} B/s | target <= {target} B/s"
                    f" | {paper / d2b['bytes_per_s']:.1f}x less than the paper"
                )
                print(
                    f"  base->drone {b2d['bytes_per_s']} B/s ({b2d['packets_per_s']} pkt/s,"
                    f" pure ACKs {b2d['pure_ack_bytes_per_s']} B/s)"
                )
            else:
                print(f"  wire: {w}")
            print(
                f"  mean DATA frame {s['mean_data_frame_bytes']} B; PubBroker CPU"
                f" {s['cpu_percent']} % of a core, RSS {s['rss_kb']} kB"
                f" (peak {s['peak_rss_kb']} kB)" + ("  [targets < 1 %, < 10 MB]" if n == 2 else "")
            )
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(results, indent=1))
    print(f"\nfigures written to {args.json}")


if __name__ == "__main__":
    main()
