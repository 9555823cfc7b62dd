"""A slot larger than the radio's packet, over serial through the emulator:
the PubBroker cuts it into 0x32 fragments that each fit the packet (the
emulator drops any frame larger than it), the SubBroker puts them back
together, and a lost fragment is asked for again with its slot. Oracle: the
on-board archive (every delivered window equals the one recomputed from the
archived samples, and every window of the large subscription arrives)."""

from __future__ import annotations

import json
import re
import time
from pathlib import Path
from typing import Any

import pytest
from modd.zenoh_session import wait_connected
from radio_harness import (
    radio_counts,
    start_pubbroker_dgram,
    start_radio_serial,
    subbroker_dgram_config,
)
from subbroker_harness import (
    check_against_archive,
    free_port,
    model_copy,
    processes,
    read_archive,
    start_load,
    start_subbroker,
    wait_port,
)

from conftest import Collector

pytestmark = pytest.mark.usefixtures("needs_pubbroker")

# The radio's largest frame: room for scenario 1's CONFIG in one control datagram (~130 B
# framed), not for 2 s of 25 Hz samples (ALL, ~220 B).
PACKET = 144
PERIOD_NS = 2_000_000_000


def _model(tmp: Path) -> Path:
    """Scenario 1 with a serial link of small packets and one more subscription:
    every sample of accel_x each 2 s (ALL: ~50 values, a slot of ~220 B)."""
    path = model_copy(tmp, "scenario1.modd")
    model = json.loads(path.read_text())
    model["link"] = {"transport": "serial", "device": "/dev/null", "maxPacket": PACKET}
    # without sub_3 (accel_x every 0.25 s) the plan cannot derive sub_8 from short windows
    model["subscribers"] = [s for s in model["subscribers"] if s["name"] != "sub_3"]
    model["subscribers"].append(
        {
            "name": "sub_8",
            "topic": "usv.accelerometer.accel_x",
            "periodS": "2.0",
            "aggregation": "ALL",
        }
    )
    path.write_text(json.dumps(model))
    return path


def _ends(values: dict[str, list[Any]], name: str) -> list[int]:
    return sorted(v.end_ns for v in values.get(name, []) if v.value is not None)


@pytest.mark.parametrize("loss", [0.0, 0.1])
def test_slots_larger_than_the_packet_arrive_as_fragments(
    loss: float, tmp_path: Path, zenoh_client: Any
) -> None:
    model = _model(tmp_path)
    spec = f"packet={PACKET},loss={loss},latency_ms=20,seed=11"
    radio, base, drone = start_radio_serial(tmp_path, spec)
    zport, ingress = free_port(), free_port()
    pb = start_pubbroker_dgram(
        tmp_path,
        model,
        {"transport": "serial", "device": drone, "port": 1, "max_packet": PACKET},
        ingress,
    )
    sb = start_subbroker(
        tmp_path,
        subbroker_dgram_config(tmp_path, model, "127.0.0.1:1", zport, "serial", device=base),
    )
    with processes(radio, pb, sb):
        wait_port(zport, 40)
        session = zenoh_client(zport)
        assert wait_connected(session)
        got = Collector()
        session.declare_subscriber("modd/usv/**", got.on_sample)
        assert sb.wait_log("running", 20), sb.log()[-3000:]
        load = start_load(tmp_path, model, ingress, 9.0)
        load.p.wait(30)
        time.sleep(3.0)  # the last second's slot and, under loss, its NACK
        with processes(load):
            pass
        values = got.snapshot()
        archive = read_archive(tmp_path / "archive", model)
        counts = radio_counts(radio)
        time.sleep(1.2)  # the PubBroker logs its link counters every second
        pb_log = pb.log()
    assert check_against_archive(values, archive) > 50, values.keys()
    ends = _ends(values, "sub_8")
    stamps = [t for t, _ in archive["usv.accelerometer.accel_x"]]
    # every 2 s window with archived samples, from the first delivered on
    want = (
        [
            e
            for e in range(ends[0], max(stamps) + PERIOD_NS + 1, PERIOD_NS)
            if any(e - PERIOD_NS <= t < e for t in stamps)
        ]
        if ends
        else []
    )
    assert len(ends) >= 3 and ends == want, (ends, want, counts)
    # the windows between the load's first and last are full: 25 Hz x 2 s
    assert max(len(v.value) for v in values["sub_8"] if isinstance(v.value, list)) >= 45, values[
        "sub_8"
    ]
    frags = [int(x) for x in re.findall(r"link: .*fragments=(\d+)", pb_log)]
    # two fragments a full window (the edge windows, partly filled, may fit one packet)
    assert frags and frags[-1] >= 2 * (len(ends) - 2), pb_log[-1500:]
    assert "oversize" not in counts, counts  # nothing larger than the packet was offered
    if loss:
        r = got.status[-1]["radio"]
        assert r["nacks"] > 0 and r["retransmissions"] > 0, (r, counts)
