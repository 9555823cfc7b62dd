"""``modd-radio`` refuses settings no radio has and a relay to itself, with a
clear message naming the setting (issue 28); nothing is opened for them."""

from __future__ import annotations

import pytest
from modd import uplink
from modd.radio import cli
from modd.radio.channel import MAX_PACKET, Channel, RadioSpec


@pytest.mark.parametrize(
    "spec,message",
    [
        ("rate=0", "rate=0.0 is out of range"),
        ("rate=-5", "rate=-5.0 is out of range"),
        ("rate=nan", "expected a finite number"),
        ("loss=-0.1", "loss=-0.1 is out of range"),
        ("loss=1.01", "loss=1.01 is out of range"),
        ("duplicate=2", "duplicate=2.0 is out of range"),
        ("latency_ms=1e9", "latency_ms=1000000000.0 is out of range"),
        ("latency_ms=inf", "expected a finite number"),
        ("jitter_ms=-1", "jitter_ms=-1.0 is out of range"),
        ("packet=0", "packet=0 is out of range"),
        ("packet=70000", "packet=70000 is out of range"),
        ("packet=2.5", "packet=2.5: expected a whole number"),
        ("queue_s=0", "queue_s=0.0 is out of range"),
        ("seed=1.5", "seed=1.5: expected a whole number"),
        ("outage=5+0", "outage=5.0+0.0 is out of range"),
        ("outage=-1+3", "outage=-1.0+3.0 is out of range"),
        ("outage=nan+3", "outage=nan+3.0 is out of range"),
        ("loss=0.1,loss=0.2", "'loss' given twice"),
    ],
)
def test_a_setting_no_radio_has_is_refused_by_name(spec: str, message: str) -> None:
    with pytest.raises(ValueError, match=message.replace("+", r"\+").replace(".", r"\.")):
        RadioSpec.parse(spec)
    with pytest.raises(uplink.LinkSetupError, match="--radio: radio setting"):
        uplink.check("udp", spec, {})


def test_the_edges_of_each_range_are_accepted() -> None:
    s = RadioSpec.parse(
        f"rate=1,packet={MAX_PACKET},loss=1,duplicate=0,latency_ms=600000,"
        "jitter_ms=0,queue_s=3600,seed=0,outage=0+0.5"
    )
    assert s.packet == MAX_PACKET and s.loss == 1 and s.outages == ((0.0, 0.5),)
    assert Channel(s).offer(b"x", 0.0) is None  # in the outage
    with pytest.raises(ValueError, match="rate=0 is out of range"):
        RadioSpec(rate=0)  # built directly, not parsed: checked alike


@pytest.mark.parametrize(
    "listen,to",
    [
        ("127.0.0.1:7181", "127.0.0.1:7181"),
        ("0.0.0.0:7181", "127.0.0.1:7181"),
        ("localhost:7181", "127.0.0.1:7181"),
    ],
)
def test_a_relay_to_itself_is_refused(
    listen: str, to: str, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as exit_:
        cli.main(["--udp", listen, "--to", to, "--duration", "1"])
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert "is where the radio listens (--udp): it would relay every datagram to itself" in err


def test_a_bad_spec_on_the_command_line_is_a_usage_error(
    capsys: pytest.CaptureFixture[str],
) -> None:
    with pytest.raises(SystemExit) as exit_:
        cli.main(["--udp", "127.0.0.1:7181", "--to", "127.0.0.1:7171", "--radio", "loss=3"])
    assert exit_.value.code == 2
    assert "argument --radio: radio setting loss=3.0 is out of range" in capsys.readouterr().err
