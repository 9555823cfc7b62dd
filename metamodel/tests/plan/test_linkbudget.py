"""The link budget per transport: bytes on the wire computed by hand from the
datagram layout (docs/protocol.md) against the planner's walk, and the
over-budget error naming the subscriptions."""

from __future__ import annotations

from pathlib import Path

import pytest
from modd_model import load_text
from modd_plan.linkbudget import datagram_capacity, serial_frame_bytes, wire_bytes
from modd_plan.plan import make_plan


def _plan_with(scenarios_dir: Path, name: str, link: str):  # type: ignore[no-untyped-def]
    text = (scenarios_dir / name).read_text() + f"Link {{ {link} }}\n"
    result = load_text(text, name)
    assert result.ok and result.model is not None, [str(d) for d in result.diagnostics]
    return make_plan(result.model)


def test_serial_framing_by_hand() -> None:
    # 80 B + CRC 2 = 82 B body, one COBS code byte, one delimiter
    assert serial_frame_bytes(80) == 84
    # 300 B + 2: two COBS blocks
    assert serial_frame_bytes(300) == 302 + 2 + 1
    assert datagram_capacity("serial", 252) == 248
    assert serial_frame_bytes(248) == 252
    assert wire_bytes("udp", 80) == 108


def test_tcp_budget_is_todays_link_cost(scenarios_dir: Path) -> None:
    plan = _plan_with(scenarios_dir, "scenario1.modd", "transport = tcp;")
    assert plan.budget is not None
    assert plan.budget.data_to_base == pytest.approx(plan.link.drone_to_base)
    assert plan.link.drone_to_base == 292.0
    assert plan.budget.base_to_drone == 208.0


def test_scenario1_udp_and_serial_by_hand(scenarios_dir: Path) -> None:
    # scenario 1: a slot every 0.25 s with 18 B of values (2 AVERAGE f32 + count,
    # MIN, MAX f32); with 1 s accepted delay a datagram holds the 5 slots of
    # dates t .. t + 1 s: 4 B header + 90 B values + 4 B tag = 98 B, 0.8/s.
    udp = _plan_with(scenarios_dir, "scenario1.modd", "transport = udp; rate = 3600;").budget
    assert udp is not None
    assert abs(udp.data_packets_per_s - 0.8) < 1e-9
    assert abs(udp.data_to_base - 0.8 * (98 + 28)) < 1e-9
    assert udp.base_to_drone < 5
    assert udp.error is None and abs(udp.share - udp.drone_to_base / 3600) < 1e-12
    serial = _plan_with(
        scenarios_dir, "scenario1.modd", 'transport = serial; device = "/dev/ttyUSB0";'
    ).budget
    assert serial is not None
    assert abs(serial.data_to_base - 0.8 * (98 + 2 + 1 + 1)) < 1e-9
    assert serial.settings.max_packet == 252
    # the first slot of a datagram waits the whole accepted delay
    assert 1.0 <= max(serial.delays_s.values()) < 1.1


def test_accepted_delay_bounds_packing(scenarios_dir: Path) -> None:
    budget = _plan_with(scenarios_dir, "scenario1.modd", "transport = udp; delay = 0.25;").budget
    assert budget is not None
    # 2 slots per datagram: 4 + 36 + 4 = 44 B, 2 datagrams/s
    assert abs(budget.data_to_base - 2 * (44 + 28)) < 1e-9
    assert max(budget.delays_s.values()) < 0.3


def test_small_packet_splits_datagrams(scenarios_dir: Path) -> None:
    # scenario 2: one slot of 19 MIN f32 (76 B) a second; a 100 B serial packet
    # holds one slot (96 B payload room): no packing, 1 datagram/s of 84 B + framing
    budget = _plan_with(
        scenarios_dir, "scenario2.modd", 'transport = serial; device = "/dev/x"; packet = 100;'
    ).budget
    assert budget is not None
    assert abs(budget.data_packets_per_s - 1) < 1e-9
    assert abs(budget.data_to_base - serial_frame_bytes(4 + 76 + 4)) < 1e-9
    # 64 B packet: the slot goes as two fragments with their own header and tag
    frag = _plan_with(scenarios_dir, "scenario2.modd", "transport = udp; packet = 64;").budget
    assert frag is not None
    assert abs(frag.data_packets_per_s - 2) < 1e-9
    assert abs(frag.data_to_base - (2 * (4 + 1 + 4 + 28) + 76)) < 1e-9


def test_over_budget_names_the_subscriptions(scenarios_dir: Path) -> None:
    plan = _plan_with(
        scenarios_dir, "scenario1.modd", 'transport = serial; device = "/dev/x"; rate = 60;'
    )
    budget = plan.budget
    assert budget is not None and budget.error is not None
    # 81.6 B/s of DATA and 1.85 B/s of STATUS and PONG (test_control.py)
    assert "83.4 B/s" in budget.error and "60 B/s" in budget.error
    assert budget.over_budget and all(n in budget.error for n in budget.over_budget)
    j = plan.to_json()["link_budget"]
    assert j["error"] == budget.error and j["over_budget"] == list(budget.over_budget)
    ok = _plan_with(
        scenarios_dir, "scenario1.modd", 'transport = serial; device = "/dev/x"; rate = 3600;'
    ).budget
    assert ok is not None and ok.error is None and ok.over_budget == ()


def test_exact_sum_equals_the_fraction_sum() -> None:
    """The per-denominator integer sum against Fraction addition, seeded."""
    import random
    from fractions import Fraction

    from modd_plan.linkbudget import exact_sum

    rng = random.Random(7)
    for _ in range(200):
        values = [
            Fraction(rng.randint(-(10**6), 10**6), rng.choice([1, 2, 3, 7, 10, 12, 10**6]))
            for _ in range(rng.randint(0, 40))
        ]
        assert exact_sum(values) == sum(values, Fraction(0))
        assert isinstance(exact_sum(values), Fraction)
        # the same objects many times (a plan's window sizes), and temporaries
        # made one by one (an object freed early could lend its id to the next)
        repeated = [rng.choice(values or [Fraction(1, 3)]) for _ in range(50)]
        assert exact_sum(repeated) == sum(repeated, Fraction(0))
        assert exact_sum(Fraction(v.numerator + 1, v.denominator) for v in repeated) == sum(
            (Fraction(v.numerator + 1, v.denominator) for v in repeated), Fraction(0)
        )
