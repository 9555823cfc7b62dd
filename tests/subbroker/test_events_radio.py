"""The event subscriptions' scripted signal (steps, a ramp, noise around the threshold,
flapping; tests/subbroker/test_events_e2e.py) over the datagram links, real processes:
udp through a Wi-Fi radio profile and serial (pseudo-terminals) through a SiK one, the
radio emulator's relay (modd.radio.relay) in this process so that every packet it
carried is seen and timed at the profile's air time. What the PubBroker sent drone to
base, bytes a second and air time an hour, stays within the plan's "at most"
(``plan.radio.ceiling``, which counts every event window at its worst, N events), and
every event the reference definition implies over the archive (read with the official
``mcap`` reader) is delivered in its window."""

from __future__ import annotations

import json
import threading
from pathlib import Path
from typing import Any

import pytest
from modd.radio import relay
from modd.radio.channel import RadioSpec
from modd_plan.radio import RadioProfile
from radio_harness import start_pubbroker_dgram, subbroker_dgram_config, through_profile
from subbroker_harness import (
    free_port,
    model_copy,
    processes,
    read_archive,
    start_load,
    start_subbroker,
    wait_port,
)
from test_events_e2e import SUBS, check_event_windows
from test_radio_airtime import STATUS_S, _Recording, plan_of

from conftest import Collector

pytestmark = [pytest.mark.usefixtures("needs_pubbroker"), pytest.mark.e2e]

LOAD_S = 24.0
RADIOS = {"udp": {"kind": "wifi"}, "serial": {"kind": "sik"}}


def _model(tmp: Path, transport: str) -> dict[str, Any]:
    model: dict[str, Any] = json.loads(model_copy(tmp, "scenario1.modd").read_text())
    model["subscribers"] = SUBS
    model["link"] = {"transport": transport, "radio": RADIOS[transport]}
    return model


def _udp(tmp: Path, model_path: Path, profile: RadioProfile, got: Any) -> tuple[Any, Any]:
    """The processes over udp through the relay in this thread's sibling; (up, down)."""
    pb_port, front, zport, ingress = free_port("udp"), free_port("udp"), free_port(), free_port()
    stopping = threading.Event()
    out: list[tuple[Any, Any]] = []
    thread = threading.Thread(
        target=lambda: out.append(
            relay.run_udp(
                RadioSpec(),
                ("127.0.0.1", front),
                ("127.0.0.1", pb_port),
                stopping.is_set,
                profile=profile,
            )
        ),
        daemon=True,
    )
    thread.start()
    pb = start_pubbroker_dgram(tmp, model_path, {"transport": "udp", "port": pb_port}, ingress)
    cfg = subbroker_dgram_config(
        tmp, model_path, f"127.0.0.1:{front}", zport, "udp", pb_status_s=STATUS_S
    )
    sb = start_subbroker(tmp, cfg)
    try:
        with processes(pb, sb):
            wait_port(zport, 40)
            got(zport)
            assert sb.wait_log("running", 60), sb.log()[-3000:]
            load = start_load(tmp, model_path, ingress, LOAD_S, signal="scripted")
            load.p.wait(LOAD_S + 30)
            with processes(load):
                pass
    finally:
        stopping.set()
        thread.join(10)
    return out[0]


def _serial(tmp: Path, model: dict[str, Any], profile: RadioProfile, got: Any) -> Any:
    base, base_path = relay.open_pty_pair()
    drone, drone_path = relay.open_pty_pair()
    model["link"]["device"] = base_path
    model_path = tmp / "model.json"
    model_path.write_text(json.dumps(model))
    ptys = (base, base_path, drone, drone_path)
    return through_profile(
        tmp, model_path, ptys, profile, LOAD_S, "scripted", STATUS_S, on_zenoh=got
    )


def _rates(sent: list[tuple[float, bytes, float]]) -> tuple[float, float]:
    """Air time an hour and bytes a second of every packet the relay carried drone to
    base (DATA, STATUS, PONG, ...): those after the first, over the span since it."""
    assert len(sent) > 12, len(sent)
    span = sent[-1][0] - sent[0][0]
    air = sum(a for _, _, a in sent[1:]) * 3600 / span
    return air, sum(len(p) for _, p, _ in sent[1:]) / span


@pytest.mark.parametrize("transport", sorted(RADIOS))
def test_events_over_the_radio_stay_within_the_planned_worst_case(
    transport: str, tmp_path: Path, zenoh_client: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(relay, "AirtimeChannel", _Recording)
    model = _model(tmp_path, transport)
    predicted = plan_of(model).radio
    assert predicted is not None and predicted.fits and predicted.ceiling is not None
    profile = RadioProfile.of(model["link"]["radio"])
    values = Collector()

    def listen(zport: int) -> None:
        zenoh_client(zport).declare_subscriber("modd/usv/**", values.on_sample)

    if transport == "udp":
        model_path = tmp_path / "model.json"
        model_path.write_text(json.dumps(model))
        up, down = _udp(tmp_path, model_path, profile, listen)
    else:
        up, down = _serial(tmp_path, model, profile, listen)
    assert not down.dropped, down.summary()  # a plan that fits: nothing refused
    air, sent_bps = _rates(down.sent)
    ceiling = predicted.ceiling
    print(
        f"events over {transport} ({profile.kind}): {sent_bps:.1f} B/s sent, at most "
        f"{ceiling.bytes_per_s:.1f} planned; air {air:.3f} s/h measured, about "
        f"{predicted.air_s_per_hour:.3f}, at most {ceiling.air_s_per_hour:.3f} planned"
    )
    assert air <= ceiling.air_s_per_hour
    assert sent_bps <= ceiling.bytes_per_s
    archive = read_archive(tmp_path / "archive", tmp_path / "model.json")
    got = values.snapshot()
    for sub in SUBS:
        assert check_event_windows(sub, got[sub["name"]], archive[sub["topic"]]) >= 5
