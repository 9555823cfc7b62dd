"""The link over udp and over serial, end to end on loopback and
pseudo-terminals, real processes: the C++ PubBroker, the publisher load, the
SubBroker, the radio emulator (modd-radio) in the path. The oracle is the
on-board archive (MCAP, official reader): every delivered window equals the
one recomputed from the archived samples, and the windows that must arrive
are all there (loss, reordering, duplication, an outage, reboots are
repaired, or only cost the live view what the protocol says)."""

from __future__ import annotations

import re
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import pytest
from modd.zenoh_session import wait_connected
from modd_contracts.schema import validate
from radio_harness import (
    Injector,
    radio_counts,
    start_pubbroker_dgram,
    start_radio_serial,
    start_radio_udp,
    subbroker_dgram_config,
)
from subbroker_harness import (
    Proc,
    check_against_archive,
    free_port,
    load_counts,
    model_copy,
    processes,
    read_archive,
    start_load,
    start_subbroker,
    wait_port,
)

from conftest import Collector

pytestmark = pytest.mark.usefixtures("needs_pubbroker")

PERIOD_NS = 250_000_000  # scenario 1's subscriptions that are sent every 0.25 s


def _watch(zenoh_client: Any, zport: int) -> Collector:
    wait_port(zport, 40)  # the SubBroker's start (imports, zenoh) on a loaded machine
    session = zenoh_client(zport)
    assert wait_connected(session)
    got = Collector()
    session.declare_subscriber("modd/usv/**", got.on_sample)
    return got


def _windows(values: dict[str, list[Any]], name: str) -> set[int]:
    return {v.end_ns for v in values.get(name, []) if v.value is not None}


def _expected(
    archive: dict[str, list[tuple[int, Any]]],
    topic: str,
    period_ns: int,
    first_end: int,
    last_end: int,
) -> set[int]:
    """Window ends in [first_end, last_end] whose window holds archived samples."""
    stamps = [t for t, _ in archive[topic]]
    out = set()
    for end in range(first_end, last_end + 1, period_ns):
        if any(end - period_ns <= t < end for t in stamps):
            out.add(end)
    return out


def _delivered_share(
    values: dict[str, list[Any]], archive: dict[str, Any], name: str = "sub_5"
) -> tuple[float, set[int]]:
    """Share of sub_5's windows (accel_z MAX every 0.25 s) delivered, between its
    first and last delivered window, and the missing window ends."""
    got = _windows(values, name)
    topic = values[name][0].topic
    want = _expected(archive, topic, PERIOD_NS, min(got), max(got))
    return len(got & want) / len(want), want - got


def _run(
    tmp: Path, model: Path, pb: Proc, sb: Proc, got: Collector, seconds: float, settle: float = 2.0
) -> tuple[dict[str, list[Any]], dict[str, Any], Proc]:
    assert sb.wait_log("running", 20), sb.log()[-3000:]
    load = start_load(tmp, model, _ingress(pb), seconds)
    load.p.wait(seconds + 20)
    time.sleep(settle)
    with processes(load):
        pass
    return got.snapshot(), read_archive(tmp / "archive", model), load


def _ingress(pb: Proc) -> int:
    ingress = pb.log_path.with_suffix(".json").read_text().split('"ingress"')[1]
    found = re.search(r'"port": (\d+)', ingress)
    assert found, ingress
    return int(found.group(1))


def _start(
    tmp: Path, transport: str, spec: str | None, pb_status_s: int = 60, ping_period_s: float = 0.0
) -> tuple[Path, Proc, Proc, Proc | None, int]:
    model = model_copy(tmp, "scenario1.modd")
    zport, ingress = free_port(), free_port()
    radio: Proc | None = None
    if transport == "udp":
        port = free_port("udp")
        pb = start_pubbroker_dgram(tmp, model, {"transport": "udp", "port": port}, ingress)
        endpoint = port
        if spec is not None:
            radio, endpoint = start_radio_udp(tmp, port, spec)
        cfg = subbroker_dgram_config(
            tmp,
            model,
            f"127.0.0.1:{endpoint}",
            zport,
            "udp",
            pb_status_s=pb_status_s,
            ping_period_s=ping_period_s,
        )
    else:
        radio, base, drone = start_radio_serial(tmp, spec or "")
        pb = start_pubbroker_dgram(
            tmp, model, {"transport": "serial", "device": drone, "port": 1}, ingress
        )
        cfg = subbroker_dgram_config(
            tmp,
            model,
            "127.0.0.1:1",
            zport,
            "serial",
            device=base,
            pb_status_s=pb_status_s,
            ping_period_s=ping_period_s,
        )
    sb = start_subbroker(tmp, cfg)
    return model, pb, sb, radio, zport


@pytest.mark.parametrize("transport", ["udp", "serial"])
def test_transport_delivers_what_the_archive_holds(
    transport: str, tmp_path: Path, zenoh_client: Any
) -> None:
    model, pb, sb, radio, zport = _start(tmp_path, transport, None, pb_status_s=2)
    with processes(*([radio] if radio else []), pb, sb):
        got = _watch(zenoh_client, zport)
        values, archive, load = _run(tmp_path, model, pb, sb, got, 6.0)
        status = got.status[-1]
    assert {t: len(s) for t, s in archive.items()} == load_counts(load)  # lossless archive
    assert set(values) >= {f"sub_{i}" for i in range(3, 8)}  # sub_1, sub_2: 10 s windows
    assert check_against_archive(values, archive) > 100
    share, missing = _delivered_share(values, archive)
    assert share == 1.0, sorted(missing)
    radio_st = status["radio"]
    assert status["transport"] == transport and status["link"] == "up"
    assert radio_st["forged"] == 0 and radio_st["replayed"] == 0 and radio_st["nacks"] == 0
    # nothing flows back while nothing is lost (the PINGs of the RTT, at most)
    assert radio_st["wire_bytes_out_per_s"] is not None and radio_st["wire_bytes_out_per_s"] < 20
    assert 0 < radio_st["wire_bytes_in_per_s"] < 300
    assert validate("status", status) == []  # the contract, radio figures included
    # the PubBroker's side, from its STATUS (fields 24..29)
    pb_side = next(
        s["radio"]["pubbroker"]
        for s in reversed(got.status)
        if s["radio"] and s["radio"]["pubbroker"]
    )
    assert pb_side["datagrams_sent"] > 10 and pb_side["datagrams_resent"] == 0, pb_side
    assert pb_side["forged"] == 0 and pb_side["replayed"] == 0 and pb_side["nacks"] == 0


def test_periodic_pings_measure_the_radio_round_trip(tmp_path: Path, zenoh_client: Any) -> None:
    """``ping_period_s``: PINGs go every 0.1 s besides the data (the quiet link of
    the test above sends under 20 B/s), and the RTT they measure is the radio's
    (60 ms of latency each way)."""
    model, pb, sb, radio, zport = _start(tmp_path, "udp", "latency_ms=60,seed=1", ping_period_s=0.1)
    assert radio is not None
    with processes(radio, pb, sb):
        got = _watch(zenoh_client, zport)
        _run(tmp_path, model, pb, sb, got, 3.0)
        status = got.status[-1]
    r = status["radio"]
    assert r["wire_bytes_out_per_s"] is not None and r["wire_bytes_out_per_s"] > 200, r
    assert status["rtt_s"] is not None and 0.11 < status["rtt_s"] < 0.5, status


@pytest.mark.parametrize("transport", ["udp", "serial"])
def test_loss_reordering_duplication_are_repaired(
    transport: str, tmp_path: Path, zenoh_client: Any
) -> None:
    spec = "loss=0.15,latency_ms=40,jitter_ms=30,duplicate=0.1,seed=5"
    model, pb, sb, radio, zport = _start(tmp_path, transport, spec)
    assert radio is not None
    with processes(radio, pb, sb):
        got = _watch(zenoh_client, zport)
        values, archive, _ = _run(tmp_path, model, pb, sb, got, 8.0, settle=4.0)
        status = got.status[-1]
        counts = radio_counts(radio)
    assert check_against_archive(values, archive) > 100  # no wrong value, ever
    share, missing = _delivered_share(values, archive)
    assert share >= 0.97, (share, sorted(missing), status["radio"], counts)
    r = status["radio"]
    assert "loss" in counts and r["nacks"] > 0 and r["retransmissions"] > 0, (r, counts)
    assert r["replayed"] > 0, r  # the duplicates, dropped and counted
    assert r["forged"] == 0 and r["loss"] > 0


OUTAGE_S = 30.0


def test_outage_and_reboots_through_the_emulator(tmp_path: Path, zenoh_client: Any) -> None:
    """Over udp and over serial at once (two stacks, in parallel): a radio
    outage of 30 s is repaired from the PubBroker's resend ring after a new
    handshake; a SubBroker killed with -9 and started again, then a PubBroker
    restarted, each get the link back through the emulator without anyone's
    help."""
    with ThreadPoolExecutor(2) as pool:
        runs = {
            t: pool.submit(_outage_and_reboots, tmp_path / t, t, zenoh_client)
            for t in ("udp", "serial")
        }
        for transport, run in runs.items():
            try:
                run.result()
            except AssertionError as exc:
                raise AssertionError(f"over {transport}: {exc}") from exc


def _missing_report(missing: set[int], got: Collector, radio: Proc, pb: Proc) -> str:
    """What a failure needs to be understood, short enough not to be cut: the missing
    windows as a count and span, both sides' link counters and the emulator's."""
    pb_link = [line for line in pb.log().splitlines() if "modd-pubbroker: link:" in line]
    return (
        f"{len(missing)} windows missing, {min(missing)}..{max(missing)}; "
        f"SubBroker radio {got.status[-1]['radio']}; PubBroker {pb_link[-1:]}; "
        f"{radio_counts(radio)}"
    )


def _outage_and_reboots(tmp: Path, transport: str, zenoh_client: Any) -> None:
    tmp.mkdir()
    model = model_copy(tmp, "scenario1.modd")
    zport, ingress = free_port(), free_port()
    radio: Proc | None = None
    pb: Proc | None = None
    sb: Proc | None = None
    try:
        if transport == "udp":
            port, relay = free_port("udp"), free_port("udp")
            link: dict[str, Any] = {"transport": "udp", "port": port}
            pb = start_pubbroker_dgram(tmp, model, link, ingress)
            sb = start_subbroker(
                tmp, subbroker_dgram_config(tmp, model, f"127.0.0.1:{relay}", zport, "udp")
            )
            got = _watch(zenoh_client, zport)
            # the emulator starts once the SubBroker is up, so that its outage falls
            # while the load runs; the handshake waits for it
            outage_at = 4.0
            radio = start_radio_udp(
                tmp, port, f"latency_ms=30,outage={outage_at}+{OUTAGE_S},seed=2", relay=relay
            )[0]
        else:
            # the emulator makes the pseudo-terminals: it comes first, its outage later
            outage_at = 14.0
            radio, base, drone = start_radio_serial(
                tmp, f"latency_ms=30,outage={outage_at}+{OUTAGE_S},seed=2"
            )
            link = {"transport": "serial", "device": drone, "port": 1}
            pb = start_pubbroker_dgram(tmp, model, link, ingress)
            sb = start_subbroker(
                tmp, subbroker_dgram_config(tmp, model, "127.0.0.1:1", zport, "serial", device=base)
            )
            got = _watch(zenoh_client, zport)
        started = radio.started
        assert sb.wait_log("running", 30), sb.log()[-3000:]
        # the load runs from before the outage to 6 s after it
        seconds = outage_at + OUTAGE_S + 6.0 - (time.monotonic() - started)
        assert seconds > OUTAGE_S + 6.0, "the SubBroker started after the outage began"
        load = start_load(tmp, model, ingress, seconds)
        load.p.wait(seconds + 30)
        # the NACKs of the outage's slots, after the new handshake: on a loaded
        # machine the repair takes longer, but nothing may stay missing
        deadline = time.monotonic() + 30.0
        while True:
            time.sleep(1.0)
            values = got.snapshot()
            archive = read_archive(tmp / "archive", model)
            share, missing = _delivered_share(values, archive)
            if share == 1.0 or time.monotonic() > deadline:
                break
        assert check_against_archive(values, archive) > 100
        assert share == 1.0, _missing_report(missing, got, radio, pb)
        assert "outage" in radio_counts(radio)
        r = got.status[-1]["radio"]
        # a new session, and the outage's 120 slots of 0.25 s resent from the ring
        assert r["handshakes"] >= 2 and r["retransmissions"] >= 100, r

        # the SubBroker dies (-9) and comes back: a new session, a new CONFIG
        sb.kill9()
        sb = start_subbroker(tmp, tmp / "sb.toml", tag="sb2")
        assert sb.wait_log("running", 30), sb.log()[-3000:]
        before = len(got.snapshot().get("sub_5", []))
        load2 = start_load(tmp, model, ingress, 3.0, tag="load2")
        load2.p.wait(20)
        time.sleep(1.5)
        assert len(got.snapshot().get("sub_5", [])) > before + 8, sb.log()[-2000:]

        # the PubBroker restarts: the SubBroker finds the silence, handshakes again
        pb.stop()
        with processes(load, load2):
            pass
        archive = read_archive(tmp / "archive", model)  # what the first PubBroker kept
        pb = start_pubbroker_dgram(tmp, model, link, ingress, tag="pb2", archive="archive2")
        deadline = time.monotonic() + 30
        while "PubBroker config 0" not in sb.log() and time.monotonic() < deadline:
            time.sleep(0.2)
        assert "PubBroker config 0" in sb.log(), sb.log()[-3000:]  # it met the new PubBroker
        time.sleep(2.0)
        before = len(got.snapshot().get("sub_5", []))
        load3 = start_load(tmp, model, ingress, 3.0, tag="load3")
        load3.p.wait(20)
        time.sleep(1.5)
        with processes(load3):
            pass
        after = got.snapshot()
        assert len(after.get("sub_5", [])) > before + 8, sb.log()[-2000:]
        archive2 = read_archive(tmp / "archive2", model)
        late = {
            k: [v for v in vs if v.start_ns > max(t for t, _ in archive[v.topic])]
            for k, vs in after.items()
        }
        assert check_against_archive(late, archive2) > 20
    finally:
        with processes(radio, pb, sb):
            pass


def test_forged_and_replayed_datagrams_are_dropped_and_counted(
    tmp_path: Path, zenoh_client: Any
) -> None:
    model = model_copy(tmp_path, "scenario1.modd")
    zport, ingress, port = free_port(), free_port(), free_port("udp")
    pb = start_pubbroker_dgram(tmp_path, model, {"transport": "udp", "port": port}, ingress)
    tap = Injector(port)
    sb = start_subbroker(
        tmp_path, subbroker_dgram_config(tmp_path, model, f"127.0.0.1:{tap.port}", zport, "udp")
    )
    try:
        with processes(pb, sb):
            got = _watch(zenoh_client, zport)
            values, archive, _ = _run(tmp_path, model, pb, sb, got, 5.0)
            status = got.status[-1]
            time.sleep(1.2)  # the PubBroker logs its link counters every second
            pb_log = pb.log()
    finally:
        tap.close()
    r = status["radio"]
    assert tap.forged_down > 5 and r["forged"] >= tap.forged_down - 2, (r, tap.forged_down)
    assert r["replayed"] >= tap.replayed_down - 2, (r, tap.replayed_down)
    assert check_against_archive(values, archive) > 100  # only genuine values came out
    share, missing = _delivered_share(values, archive)
    assert share == 1.0, sorted(missing)
    forged_up = [int(x) for x in re.findall(r"link: datagrams_in=\d+ .*?forged=(\d+)", pb_log)]
    assert forged_up and forged_up[-1] >= tap.forged_up > 0, pb_log[-2000:]


def _attacks(counts: str, direction: str) -> tuple[int, int]:
    """(forged, replayed) by the emulator's attacker in one direction."""
    part = counts.split(f"{direction} ")[1].split(";")[0]
    forged = re.search(r"forged (\d+)", part)
    replayed = re.search(r"replayed (\d+)", part)
    return (int(forged.group(1)) if forged else 0, int(replayed.group(1)) if replayed else 0)


@pytest.mark.parametrize("transport", ["udp", "serial"])
def test_forged_and_replayed_on_the_air_are_dropped(
    transport: str, tmp_path: Path, zenoh_client: Any
) -> None:
    """An attacker on the radio (the emulator) forges a share of the datagrams
    each way (over serial with a good CRC, so the tag must refuse them) and
    replays others 1.5 s later: none is decoded, each is counted, and the
    delivery is still whole and equal to the archive."""
    spec = "forge=0.5,replay=0.5,latency_ms=20,seed=4"
    model, pb, sb, radio, zport = _start(tmp_path, transport, spec, pb_status_s=1)
    assert radio is not None
    with processes(radio, pb, sb):
        got = _watch(zenoh_client, zport)
        values, archive, _ = _run(tmp_path, model, pb, sb, got, 6.0, settle=3.0)
        # the emulator's report and the SubBroker's status are each a second apart:
        # wait (briefly) until the status has counted what the report says was sent
        deadline = time.monotonic() + 8.0
        while True:
            counts, status = radio_counts(radio), got.status[-1]
            r = status["radio"]
            down_forged, down_replayed = _attacks(counts, "drone->base")
            refused = r["forged"] + r["unknown_config"] + r["malformed"] + r["replayed"]
            if refused >= down_forged + down_replayed - 1 or time.monotonic() > deadline:
                break
            time.sleep(0.3)
        pb_log = pb.log()
    up_forged, up_replayed = _attacks(counts, "base->drone")
    assert down_forged > 2 and down_replayed > 2, counts
    # a forgery is refused by its tag, or earlier (a flipped config id names no config); a
    # replay by the replay window, or as a handshake datagram out of a handshake (malformed)
    assert r["forged"] > 0 and r["replayed"] > 0, (r, counts)
    assert refused >= down_forged + down_replayed - 1, (r, counts)
    assert check_against_archive(values, archive) > 100  # only genuine values came out
    share, missing = _delivered_share(values, archive)
    assert share == 1.0, (sorted(missing), r, counts)
    pb_counts = re.findall(r"link: datagrams_in=\d+ .*?forged=(\d+) replayed=(\d+)", pb_log)
    assert pb_counts, pb_log[-2000:]
    pb_side = r["pubbroker"]  # the PubBroker's STATUS, in the SubBroker's status
    assert pb_side is not None and validate("status", status) == [], r
    if up_forged:
        assert int(pb_counts[-1][0]) > 0 and pb_side["forged"] > 0, (pb_side, counts)
    if up_replayed:
        assert int(pb_counts[-1][1]) > 0 and pb_side["replayed"] > 0, (pb_side, counts)
