"""End to end on loopback, real processes: the C++ PubBroker, a publisher
load at the paper's rate, the SubBroker (CLI), zenoh subscribers in this
process and a TCP subscriber. The oracle recomputes every delivered window
from the MCAP archive (official reader): exact for MIN/MAX/FIRST/LAST/COUNT,
within float tolerance for AVERAGE/SUM; no window may be missing while the
link is up."""

from __future__ import annotations

import json
import socket
import threading
import time
from pathlib import Path
from typing import Any

import modd
import pytest
from modd.subbroker.client import NoReply, request
from modd.subbroker.payload import DeliveredValue
from modd.subscriber import subscribe_dynamic
from modd.zenoh_session import ZenohSettings, open_session, wait_connected
from modd_contracts.schema import validate
from subbroker_harness import (
    assert_contiguous,
    check_against_archive,
    free_port,
    load_counts,
    model_copy,
    processes,
    read_archive,
    start_load,
    start_pubbroker,
    start_subbroker,
    subbroker_config,
    wait_port,
)

from conftest import Collector

pytestmark = pytest.mark.usefixtures("needs_pubbroker")

RUN_S = 9.0


class TcpSink(threading.Thread):
    """A subscriber's TCP endpoint (the paper's delivery): JSON lines."""

    def __init__(self) -> None:
        super().__init__(daemon=True)
        self.server = socket.create_server(("127.0.0.1", 0))
        self.port = self.server.getsockname()[1]
        self.lines: list[dict[str, Any]] = []

    def run(self) -> None:
        try:
            conn, _ = self.server.accept()
        except OSError:
            return
        finally:
            self.server.close()
        buf = b""
        with conn:
            while chunk := conn.recv(65536):
                buf += chunk
                *lines, buf = buf.split(b"\n")
                self.lines += [json.loads(x) for x in lines]


def test_scenario1_delivery_matches_archive(tmp_path: Path, zenoh_client: Any) -> None:
    link, ingress, zport = free_port(), free_port(), free_port()
    tcp = TcpSink()
    tcp.start()
    model = model_copy(tmp_path, "scenario1.modd", {"sub_5": tcp.port})
    pb = start_pubbroker(tmp_path, model, link, ingress)
    sb = start_subbroker(tmp_path, subbroker_config(tmp_path, model, link, zport, tcp=True))
    load = None
    try:
        wait_port(zport)
        session = zenoh_client(zport)
        assert wait_connected(session)
        got = Collector()
        session.declare_subscriber("modd/usv/**", got.on_sample)
        assert sb.wait_log("running", 10), sb.log()
        load = start_load(tmp_path, model, ingress, RUN_S)
        time.sleep(1.0)
        ask = {"topic": "usv.accelerometer.accel_z", "period_s": "1.0", "aggregation": "MAX"}
        dyn = request(session, "modd/usv/subscribe", ask)
        assert dyn["status"] == "ACCEPTED", dyn
        assert dyn["derived_from"] == "usv.accelerometer.accel_z/MAX/0.25" and dyn["factor"] == 4
        no = request(session, "modd/usv/subscribe", {**ask, "aggregation": "FIRST"})
        assert no["status"] == "NOT_AVAILABLE" and "FIRST" in no["reason"]
        avg = subscribe_dynamic(
            "usv", "usv.accelerometer.accel_y", "0.5", "AVERAGE", session=session
        )
        sub4 = modd.subscribe("usv", "sub_4", session=session)
        load.p.wait(RUN_S + 10)
        time.sleep(0.6)
        avg_vals, sub4_vals = avg.collect(duration_s=0.1), sub4.collect(duration_s=0.1)
        avg.close()  # cancels it at the SubBroker
        sub4.close()
        cancel = request(
            session, "modd/usv/subscribe", {"action": "cancel", "subscriber": dyn["subscriber"]}
        )
        assert cancel["status"] == "CANCELLED"
        time.sleep(1.2)
        status = got.status[-1]
    finally:
        with processes(pb, sb, *([load] if load else [])):
            tcp.server.close()
    values = got.snapshot()
    archive = read_archive(tmp_path / "archive", model)
    sent = json.loads(load.log().strip().splitlines()[-1])["sent"]
    assert {t: len(s) for t, s in archive.items()} == sent  # lossless archive
    # every subscriber of the model got values, and the dynamic one
    assert avg.accepted is not None
    avg_name = avg.accepted["subscriber"]
    assert set(values) == {f"sub_{i}" for i in range(1, 8)} | {dyn["subscriber"], avg_name}
    assert status["dynamic"] == []  # both cancelled
    assert len(avg_vals) >= 2 * RUN_S - 4 and avg_vals == values[avg_name][: len(avg_vals)]
    assert sub4_vals == values["sub_4"][-len(sub4_vals) :] and len(sub4_vals) >= 4 * RUN_S - 8
    n = check_against_archive(values, archive)
    for name, vals in values.items():
        period = int(float(vals[0].period_s) * 1e9)
        # windows with samples, while the load ran: contiguous
        busy = [v for v in vals if v.count != 0 and v.value is not None]
        assert_contiguous(busy, period)
        if name not in (dyn["subscriber"], avg_name, "sub_1", "sub_2"):
            assert len(busy) >= int(RUN_S / 0.25) - 3, (name, len(busy))
    assert len(values["sub_1"]) >= 3 and values["sub_1"][1].count in (49, 50, 51)
    # the dynamic subscription stopped after its cancel
    assert values[dyn["subscriber"]][-1].end_ns < status["time_ns"]
    # the TCP subscriber got the same values as zenoh's sub_5
    tcp_vals = [DeliveredValue.from_dict(x) for x in tcp.lines]
    assert [(v.end_ns, v.value) for v in tcp_vals] == [
        (v.end_ns, v.value) for v in values["sub_5"]
    ][: len(tcp_vals)]
    assert len(tcp_vals) >= len(values["sub_5"]) - 2
    assert status["link"] == "up" and status["config_id"] == 1
    assert 0 < status["predicted_link_bytes_per_s"]["drone_to_base"] <= 300
    assert n > 150
    # what the processes really sent keeps to the contracts (modd_contracts)
    assert validate("status", status) == []
    assert [e for x in tcp.lines for e in validate("delivered_value", x)] == []


def test_no_subbroker_means_no_reply() -> None:
    port = free_port()
    # a peer can open while nothing listens (a client cannot): nothing answers
    session = open_session(ZenohSettings(mode="peer", connect=(f"tcp/127.0.0.1:{port}",)))
    try:
        t0 = time.monotonic()
        with pytest.raises(NoReply):
            request(session, "modd/usv/deploy", {"text": ""}, timeout_s=2)
        assert time.monotonic() - t0 < 2.5
    finally:
        session.close()  # type: ignore[no-untyped-call]


def test_scenario2_delivery_matches_archive(tmp_path: Path, zenoh_client: Any) -> None:
    link, ingress, zport = free_port(), free_port(), free_port()
    model = model_copy(tmp_path, "scenario2.modd")
    pb = start_pubbroker(tmp_path, model, link, ingress)
    sb = start_subbroker(tmp_path, subbroker_config(tmp_path, model, link, zport))
    load = None
    try:
        wait_port(zport)
        session = zenoh_client(zport)
        assert wait_connected(session)
        got = Collector()
        session.declare_subscriber("modd/usv/sub/*", got.on_sample)
        assert sb.wait_log("running", 10), sb.log()
        load = start_load(tmp_path, model, ingress, 5.5)
        load.p.wait(20)
        time.sleep(1.2)
    finally:
        with processes(pb, sb, *([load] if load else [])):
            pass
    values = got.snapshot()
    archive = read_archive(tmp_path / "archive", model)
    assert {t: len(s) for t, s in archive.items()} == load_counts(load)
    assert set(values) == {f"sub_{i}" for i in range(1, 20)}
    assert check_against_archive(values, archive) >= 19 * 4
    for vals in values.values():
        assert_contiguous([v for v in vals if v.value is not None], 1_000_000_000)
