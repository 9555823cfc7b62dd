"""The benchmarks, run for a couple of seconds each with tiny settings, so that they cannot
rot silently: each must produce figures that make sense (bytes on both directions of every
link, MQTT far above the MoDD link, delivered counts matching what was sent, every sample
archived). No time is asserted. Needs what `make bench` needs (tshark, mosquitto, root for
the capture, the PubBroker build): a missing piece fails with what to install."""

from __future__ import annotations

import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
for p in (HERE, HERE.parent / "subbroker", HERE.parent / "runtime"):
    if str(p) not in sys.path:
        sys.path.insert(0, str(p))

import bench_footprint  # noqa: E402
import bench_ingest  # noqa: E402
import bench_latency  # noqa: E402
import bench_link  # noqa: E402
from benchkit.run import Run  # noqa: E402

SECONDS = 2.0


def mqtt_contiguous(run: Run) -> None:
    """Every QoS 0 message published in the window reached every subscriber: sequence
    numbers without gaps, and over the whole run each subscriber got all that was sent."""
    for name, seqs in run.delivery.seqs.items():
        assert seqs, f"{name}: nothing delivered"
        assert sorted(seqs) == list(range(min(seqs), max(seqs) + 1)), f"{name}: gaps"
    sent, received = run.extra["sent"], run.extra["received"]
    by_topic = {s.name: s.topic.replace(".", "/") for s in run.scenario.subscriptions}
    assert received == {n: sent[t] for n, t in by_topic.items()}, (sent, received)


def test_link_bytes() -> None:
    results = bench_link.run([1], list(bench_link.SYSTEM_ORDER), SECONDS)
    sc, runs = results[0]
    by = {r.kind: r for r in runs}
    for r in runs:
        assert r.wire is not None
        assert r.wire.down.bytes > 0 and r.wire.up.bytes > 0, r.system
    modd, mqtt, zenoh = (by[k].wire for k in ("modd", "mosquitto", "zenoh"))
    assert modd and mqtt and zenoh
    assert mqtt.down.bytes > 10 * modd.down.bytes
    assert zenoh.down.bytes > modd.down.bytes
    # the MoDD link carries what the planner predicts (frames fall on the capture's edges)
    assert (
        0.6 * sc.planned_down < modd.rates()["drone_to_base"]["bytes_per_s"] < 1.6 * sc.planned_down
    )
    assert modd.up.data_bytes == 0  # base -> drone: pure ACKs while DATA flows
    mqtt_contiguous(by["mosquitto"])
    text = bench_link.render(results, SECONDS)
    assert "| MoDD link" in text and "information floor" in text and "does not aggregate" in text


def test_latency() -> None:
    results = bench_latency.run([2], SECONDS)
    for sc, r in results:
        d = r.delivery
        assert d.latencies_ns, r.system
        # a value is never received before its window ends (or before it is published)
        assert min(d.latencies_ns) > 0, r.system
        windows = len(sc.subscriptions) * d.seconds  # 1 s periods
        if r.kind == "mosquitto":
            mqtt_contiguous(r)
            assert len(d.latencies_ns) > 10 * windows
        else:
            assert 0.4 * windows <= len(d.latencies_ns) <= windows + 2 * len(sc.subscriptions)
    assert "p99 ms" in bench_latency.render(results, SECONDS)


def test_footprint() -> None:
    results = bench_footprint.run([2], SECONDS)
    for _, r in results:
        fp = r.footprint
        assert fp is not None
        assert fp.cpu_seconds >= 0 and fp.cpu_percent < 100 * 2
        assert 1024 < fp.rss_median_kb <= fp.rss_peak_kb < 1024 * 1024, r.system
        assert r.delivery.values_per_s > 0
    text = bench_footprint.render(results, SECONDS)
    assert "ratio PubBroker / Mosquitto" in text


def test_ingest() -> None:
    pb, mq = bench_ingest.run(400_000, 200_000)
    assert pb.confirmed == pb.count and pb.rejected == 0, pb
    assert mq.confirmed == mq.count, mq
    assert pb.rate > 0 and mq.rate > 0
    assert "goal ≥ 10×" in bench_ingest.render(pb, mq)


def test_fleet() -> None:
    """Two drones on one router, backend and WebSocket clients: every subscriber of both
    drones reached its client (checked before measuring), values arrive at about the rate
    the models ask, never before their window ends, and no SubBroker reports it is behind."""
    import bench_fleet

    result = bench_fleet.run(drones=2, seconds=4.0, extra=10)
    b = result.browser
    assert b.latencies_ns and min(b.latencies_ns) > 0
    assert 0.5 * result.asked_per_s < b.values / result.seconds < 1.5 * result.asked_per_s
    assert b.dropped == 0 and not b.behind
    assert len(result.subbrokers) == len(result.pubbrokers) == 2
    assert all(1024 < f.rss_median_kb < 1024 * 1024 for f in result.subbrokers)
    assert "p99 ms" in result.render()


def test_backfill() -> None:
    """30 s of archive backfilled raw at 3,600 B/s: every sample back, the pace kept."""
    import subprocess

    out = subprocess.run(
        [sys.executable, str(HERE / "bench_backfill.py"), "--minutes", "0.5"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert out.returncode == 0, out.stdout + out.stderr
    assert "750 / 750" in out.stdout, out.stdout
