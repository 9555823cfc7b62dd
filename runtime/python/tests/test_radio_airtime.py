"""modd-radio's profile channel: each packet takes the profile's air time,
and under a duty-cycle limit the radio stays silent for air x (1/duty - 1)
after it, delaying or refusing what comes meanwhile (clock driven, no sleep)."""

from __future__ import annotations

from pathlib import Path

import pytest
from modd.radio.airtime import AirtimeChannel
from modd.radio.channel import RadioSpec
from modd.radio.cli import main
from modd_plan.radio import RadioProfile

LORA = RadioProfile.of({"kind": "lora"})  # SF7/125 kHz, 1 %: 20 B take 56.576 ms


def test_duty_cycle_delays_then_refuses() -> None:
    ch = AirtimeChannel(RadioSpec(queue_s=10), profile=LORA)
    assert ch.offer(b"x" * 20, 0.0) == pytest.approx(0.056576)
    # silent until 5.6576 s: offered at 1 s, it waits 4.66 s (< queue_s) and goes
    assert ch.offer(b"x" * 20, 1.0) == pytest.approx(5.6576 + 0.056576)
    assert ch.delayed == 1
    # the band is now silent until 11.3152 s: offered at 1.2 s it would wait > 10 s
    assert ch.offer(b"x" * 20, 1.2) is None and ch.dropped["duty"] == 1
    assert ch.air_s == pytest.approx(2 * 0.056576) and ch.passed == 2
    assert "air 0.113152 s in 2 radio packets, delayed 1" in ch.summary()


def test_no_duty_limit_only_the_air_time() -> None:
    sik = RadioProfile.of({"kind": "sik"})
    ch = AirtimeChannel(RadioSpec(), profile=sik)
    # (87 + 13) B x 8 at 64 kbit/s = 12.5 ms, back to back
    assert ch.offer(b"x" * 87, 0.0) == pytest.approx(0.0125)
    assert ch.offer(b"x" * 87, 0.0) == pytest.approx(0.025)
    assert ch.delayed == 0 and not ch.dropped


def test_packets_above_the_payload_are_split() -> None:
    sf10 = RadioProfile.of({"kind": "lora", "spreadingFactor": 10, "dutyCycle": "1"})
    ch = AirtimeChannel(RadioSpec(), profile=sf10)
    ch.offer(b"x" * 102, 0.0)
    assert ch.radio_packets == 2
    assert ch.air_s == pytest.approx(sf10.one_packet_s(59) + sf10.one_packet_s(43))


def test_cli_refuses_a_model_without_a_radio(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    model = tmp_path / "m.json"
    model.write_text("{}")
    with pytest.raises(SystemExit):
        main(["--serial", "--profile", str(model)])
    assert "--profile" in capsys.readouterr().err
