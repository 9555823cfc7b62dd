"""The link's own control traffic in the plan (modd_plan/control.py), by hand:
the STATUS frame the PubBroker sends (its counters as varints, the
instruments' health), the PONG of the keepalive, their CONTROL datagrams and
the serial framing; the bound is the link's STATUS room. The measured side is
tests/subbroker/test_radio_airtime.py (the real PubBroker through the radio
emulator)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from modd_model import load_text
from modd_plan.control import ControlInputs, status_frame_about, varint_bytes
from modd_plan.plan import make_plan

SERIAL = 'transport = serial; device = "/dev/x";'


def _model(scenarios_dir: Path, link: str, extra: str = "") -> dict[str, Any]:
    text = (scenarios_dir / "scenario1.modd").read_text() + extra + f"Link {{ {link} }}\n"
    result = load_text(text, "scenario1.modd")
    assert result.ok and result.model is not None, [str(d) for d in result.diagnostics]
    return result.model


def test_varints() -> None:
    assert [varint_bytes(v) for v in (0, 127, 128, 16383, 16384, 2**35)] == [1, 1, 2, 2, 3, 6]


def test_scenario1_over_serial_by_hand(scenarios_dir: Path) -> None:
    budget = make_plan(_model(scenarios_dir, SERIAL)).budget
    assert budget is not None and budget.control is not None
    # after an hour: uptime 3600 (2 B); 75 samples/s in and archived, 270,000
    # (3 B each); 4 DATA frames/s, 14,400 (2 B); 81.6 B/s, 293,760 link bytes
    # (3 B); 100,000 MB free (3 B); 10,000 archive B/s (2 B); 75 pending (1 B);
    # 0.8 datagrams/s, 2,880 (2 B); one publisher (1 B); the 27 others 0 (1 B
    # each); the count 37 (1 B): 50 B, + length and type = 52 B
    assert budget.control.about[1] == (52, 60.0)
    # in a CONTROL datagram: type, counter (2 B), tag (8 B): 63 B; serial:
    # + CRC 2, COBS 1, delimiter 1 = 67 B, one every 60 s
    assert budget.control_about == ((22, 120.0), (67, 60.0))
    # PONG: length, type, "alive" (7 B) in 18 B: 22 B on the line every 30 s
    assert budget.control.about[0] == (7, 120.0)
    # bound: a STATUS of the whole room (248 - 14 = 234 B frame) fills the
    # 252-B packet; a PONG with a 5-byte counter: 25 B
    assert budget.control_at_most == ((25, 120.0), (252, 60.0))
    assert budget.control_bytes_per_s == pytest.approx((22 * 120 + 67 * 60) / 3600)
    assert budget.drone_to_base == pytest.approx(81.6 + budget.control_bytes_per_s)
    assert budget.packets_per_s == pytest.approx(0.8 + 180 / 3600)
    doc = budget.to_json()["control"]
    assert doc == {
        "status_period_s": 60,
        "bytes_per_s": 1.85,
        "packets_per_s": 0.05,
        "bound_bytes_per_s": round((25 * 120 + 252 * 60) / 3600, 3),
    }


def _by_hand(t: int) -> int:
    """Scenario 1's STATUS frame ``t`` s into a run over serial, by hand: uptime
    t; 75 samples/s in and archived; 4 DATA frames/s; 81.6 link B/s; 0.8
    datagrams/s (varints); 100,000 MB free (3 B); 10,000 archive B/s (2 B); 75
    pending (1 B); one publisher (1 B); the 27 others 0 (1 B each); the count 37
    (1 B); + length and type."""
    grow = (t, 75 * t, 75 * t, 4 * t, int(81.6 * t), int(0.8 * t))
    return 1 + 1 + 1 + sum(varint_bytes(v) for v in grow) + 3 + 2 + 1 + 1 + 27


def test_a_run_of_a_given_length_has_its_own_status_frames(scenarios_dir: Path) -> None:
    """``status_horizon_s``: the STATUS frames of a 45-s run (4 at 10 s, younger
    counters than an hour's), each size at its share; the bound is unchanged."""
    model = _model(scenarios_dir, SERIAL)
    assert _by_hand(3600) == 52  # the hour's frame (the test above)
    short = make_plan(model, status_period_s=10, status_horizon_s=45).budget
    hour = make_plan(model, status_period_s=10).budget
    assert short is not None and short.control is not None and hour is not None
    sizes: dict[int, float] = {}
    for k in range(1, 5):
        sizes[_by_hand(10 * k)] = sizes.get(_by_hand(10 * k), 0) + 360 / 4
    assert dict(short.control.about[1:]) == pytest.approx(sizes)
    assert max(sizes) < 52 and short.control_at_most == hour.control_at_most
    assert short.control_bytes_per_s < hour.control_bytes_per_s


def test_instruments_add_their_health(scenarios_dir: Path) -> None:
    inputs = ControlInputs.of(_model(scenarios_dir, SERIAL))
    assert inputs.instruments == () and inputs.samples_per_s == pytest.approx(75)
    two = ControlInputs(60, ("gnss", "ctd"), inputs.samples_per_s)
    plain = status_frame_about(inputs, 4, 81.6, 0.8)
    # per instrument: name (length + bytes), field count, 13 fields (22 B)
    # instruments 2, open 2, a second publisher (modd-sensors): no width change;
    # the section's count 1 B
    assert status_frame_about(two, 4, 81.6, 0.8) == plain + 1 + (1 + 4 + 1 + 22) + (1 + 3 + 1 + 22)


def test_the_status_period_is_the_subbrokers(scenarios_dir: Path) -> None:
    model = _model(scenarios_dir, SERIAL)
    none = make_plan(model, status_period_s=0).budget
    fast = make_plan(model, status_period_s=5).budget
    assert none is not None and fast is not None
    assert none.control_about == ((22, 120.0),)  # PONGs only
    assert fast.control_about[1][1] == 720.0
    assert fast.drone_to_base > none.drone_to_base


def test_tcp_counts_segments(scenarios_dir: Path) -> None:
    budget = make_plan(_model(scenarios_dir, "transport = tcp;")).budget
    assert budget is not None
    # own segments (52 B of IPv4 + TCP): PONG 7 B, STATUS; bound the 1,400-B room
    assert budget.control_about[0] == (59, 120.0)
    assert budget.control_at_most[1] == (1452, 60.0)
