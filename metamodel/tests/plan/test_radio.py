"""Radio profiles in the planner: LoRa time on air against published figures
and an independent formulation, a plan's air time and energy by hand, the
duty-cycle refusal located in the model, and proposals that fit when planned
again."""

from __future__ import annotations

import argparse
import io
import json
from math import ceil
from pathlib import Path
from typing import Any

import pytest
from modd_contracts.schema import validate as validate_contract
from modd_model import load_text, validate
from modd_model.printer import print_model
from modd_plan.airtime import lora_time_on_air, sik_time_on_air
from modd_plan.cli import register, run_plan
from modd_plan.linkbudget import KEEPALIVE_BYTES, KEEPALIVE_S, wire_bytes
from modd_plan.plan import Plan, make_plan
from modd_plan.proposals import changed
from modd_plan.radio import RadioProfile

LORA_SF7 = 'transport = serial; device = "/dev/ttyUSB0"; radio = lora; sf = 7; battery = 50;'


def _model(scenarios_dir: Path, name: str, link: str) -> dict[str, Any]:
    text = (scenarios_dir / name).read_text() + f"Link {{ {link} }}\n"
    result = load_text(text, name)
    assert result.ok and result.model is not None, [str(d) for d in result.diagnostics]
    return result.model


def _plan(scenarios_dir: Path, name: str, link: str) -> Plan:
    return make_plan(_model(scenarios_dir, name, link))


# Published figures: Semtech's LoRa calculator, SF7 / 125 kHz / CR 4/5,
# 8-symbol preamble, explicit header, CRC on, 20 B -> 56.6 ms; the AN1200.13
# spreadsheet (docs.google.com/spreadsheets/d/1voGAtQAjC1qBmaVuP1ApNKs1ekgUjavHuVQIXyYSvNc),
# SF9 / 125 kHz / CR 4/5, 8 symbols, explicit header, 13 B -> 164.864 ms.
def test_lora_time_on_air_published_figures() -> None:
    assert lora_time_on_air(20, 7, 125_000) == pytest.approx(0.056576, abs=1e-9)
    assert lora_time_on_air(13, 9, 125_000) == pytest.approx(0.164864, abs=1e-9)


def _lr1110_symbols(
    pl: int, sf: int, cr: int, preamble: int, header: bool, crc: bool, ldro: bool
) -> float:
    """Semtech LR1110 user manual (UM.LR1110.W.APP rev 1.0, section 8.2.2.4),
    SF7-SF12: N = Npreamble + 4.25 + 8 + ceil(max(8 PL + NbitCRC - 4 SF + 8
    + NsymbolHeader, 0) / (4 (SF - 2 LDRO))) x (CR + 4), CR 1..4."""
    n = 8 * pl + (16 if crc else 0) - 4 * sf + 8 + (20 if header else 0)
    return preamble + 4.25 + 8 + ceil(max(n, 0) / (4 * (sf - (2 if ldro else 0)))) * (cr + 4)


@pytest.mark.parametrize("sf", range(7, 13))
@pytest.mark.parametrize("bw", [125_000, 250_000, 500_000])
def test_lora_time_on_air_against_the_lr1110_formulation(sf: int, bw: int) -> None:
    for pl in (1, 13, 20, 51, 59, 100, 123, 222, 250):
        for cr in (1, 2, 3, 4):
            for header, crc in ((True, True), (False, True), (True, False)):
                ldro = 2**sf / bw > 0.016  # SF11-12 at 125 kHz, SF12 at 250 kHz
                want = _lr1110_symbols(pl, sf, cr, 8, header, crc, ldro) * 2**sf / bw
                got = lora_time_on_air(pl, sf, bw, cr + 4, 8, header, crc)
                assert got == pytest.approx(want, rel=1e-12), (pl, sf, bw, cr, header, crc)


# The link's control traffic on scenario 1 over serial (test_control.py): a PONG
# of 22 B (at most 25 B) every 30 s, a STATUS of about 67 B (at most the
# 252-B packet) every 60 s: 120 + 60 packets an hour.
PONG, STATUS, PONG_MAX, STATUS_MAX = 22, 67, 25, 252


def test_scenario1_air_time_and_energy_by_hand(scenarios_dir: Path) -> None:
    plan = _plan(scenarios_dir, "scenario1.modd", LORA_SF7)
    r = plan.radio
    assert r is not None

    def toa(n: int) -> float:
        return lora_time_on_air(n, 7, 125_000)

    # 0.8 datagrams/s of 98 B (test_linkbudget) framed to 102 B: one LoRa packet each
    assert r.packets_per_hour == pytest.approx(0.8 * 3600 + 120 + 60)
    data = 0.8 * 3600 * toa(102)
    air = data + 120 * toa(PONG) + 60 * toa(STATUS)
    assert r.air_s_per_hour == pytest.approx(air)
    assert r.control_s_per_hour == pytest.approx(air - data)
    rx = toa(wire_bytes("serial", KEEPALIVE_BYTES)) * 3600 / KEEPALIVE_S
    energy = 0.287 * air + 0.0356 * rx + 0.00528 * (3600 - air - rx)
    assert r.energy_j_per_hour == pytest.approx(energy)
    assert r.battery_share == pytest.approx(energy / (50 * 3600))
    # the duty-cycle check on the bound: a STATUS of 252 B goes as 250 B + 2 B
    bound = data + 120 * toa(PONG_MAX) + 60 * (toa(250) + toa(2))
    assert r.figures == "estimate" and r.ceiling is not None
    assert r.ceiling.air_s_per_hour == pytest.approx(bound)
    assert r.duty_share == pytest.approx(bound / 36)


def test_packets_above_the_payload_limit_are_split(scenarios_dir: Path) -> None:
    # SF10's 59 B limit: a 102 B frame goes as 59 B + 43 B
    r = _plan(scenarios_dir, "scenario1.modd", LORA_SF7.replace("sf = 7", "sf = 10")).radio
    assert r is not None and r.profile.max_payload == 59
    assert r.packets_per_hour == pytest.approx(2 * 0.8 * 3600 + 120 + 2 * 60)
    one = lora_time_on_air(59, 10, 125_000) + lora_time_on_air(43, 10, 125_000)
    pong = lora_time_on_air(PONG, 10, 125_000)
    status = lora_time_on_air(59, 10, 125_000) + lora_time_on_air(STATUS - 59, 10, 125_000)
    assert r.air_s_per_hour == pytest.approx(0.8 * 3600 * one + 120 * pong + 60 * status)


def test_sik_profile_fits_and_overrides(scenarios_dir: Path) -> None:
    link = 'transport = serial; device = "/dev/ttyUSB0"; radio = sik; ecc = true; txW = 1;'
    r = _plan(scenarios_dir, "scenario1.modd", link).radio
    assert r is not None and r.fits and r.duty_share is None and r.error is None
    assert r.profile.tx_w == 1.0 and r.profile.ecc
    packets = 0.8 * 3600 * (102 + 13) + 120 * (PONG + 13) + 60 * (STATUS + 13)
    assert r.air_s_per_hour == pytest.approx(packets * 16 / 64_000)
    assert sik_time_on_air(102, 64_000, True) == 2 * sik_time_on_air(102, 64_000)


def test_over_the_duty_cycle_is_refused_with_the_costs_located(scenarios_dir: Path) -> None:
    plan = _plan(scenarios_dir, "scenario1.modd", LORA_SF7)
    r = plan.radio
    assert r is not None and not r.fits and r.error is not None
    # sub_5 alone is served by its own 0.25 s MIN stream: the costliest
    assert r.costs[0].name == "sub_5" and "sub_5" in r.error
    data = r.air_s_per_hour - r.control_s_per_hour  # the subscriptions share the DATA's
    assert sum(c.air_s_per_hour for c in r.costs) == pytest.approx(data)
    doc = plan.to_json()["radio"]
    pointers = [d["pointer"] for d in doc["diagnostics"]]
    assert pointers[:2] == ["/link/radio", "/subscribers/4"]
    model = _model(scenarios_dir, "scenario1.modd", LORA_SF7)
    for d in doc["diagnostics"][1:]:
        index = int(d["pointer"].rsplit("/", 1)[1])
        assert d["message"].startswith(model["subscribers"][index]["name"] + " ")


# At 1 % (36 s/h) the control traffic's bound takes 31 s/h (test above): no
# plan of scenario 1 fits; at 2 % the proposals coarsen the periods.
LORA_SF7_2PC = LORA_SF7 + " dutyCycle = 0.02;"


def test_proposals_fit_when_planned_again(scenarios_dir: Path) -> None:
    model = _model(scenarios_dir, "scenario1.modd", LORA_SF7_2PC)
    plan = make_plan(model)
    assert plan.proposals
    keys = [
        (p.max_delay_s, p.report.energy_j_per_hour, p.report.bytes_per_s) for p in plan.proposals
    ]
    for i, a in enumerate(keys):  # a Pareto front: none dominates another
        assert not any(
            all(x <= y for x, y in zip(b, a, strict=True)) and b != a
            for j, b in enumerate(keys)
            if j != i
        )
    for p in plan.proposals:
        candidate = changed(model, p.accepted_delay_s, p.min_period_s)
        assert validate(candidate) == []
        text = print_model(candidate)  # and as the scientist would write it
        again = load_text(text, "proposal.modd")
        assert again.ok and again.model is not None
        replanned = make_plan(again.model)
        r = replanned.radio
        assert r is not None and r.fits and r.duty_share is not None and r.duty_share <= 1
        assert replanned.infeasible == ()  # the delay cap still met, as in the plan


def test_a_plan_that_fits_has_no_proposals(scenarios_dir: Path) -> None:
    plan = _plan(scenarios_dir, "scenario1.modd", LORA_SF7 + " dutyCycle = 0.2;")
    assert plan.radio is not None and plan.radio.fits and plan.proposals == ()
    assert plan.to_json()["radio"]["error"] is None


def test_no_radio_no_radio_key(scenarios_dir: Path) -> None:
    plan = _plan(scenarios_dir, "scenario1.modd", 'transport = serial; device = "/dev/x";')
    assert plan.radio is None and "radio" not in plan.to_json()


def test_profile_defaults_per_spreading_factor() -> None:
    assert RadioProfile.of({"kind": "lora", "spreadingFactor": 9}).max_payload == 123
    assert RadioProfile.of({"kind": "lora"}).duty_cycle == 0.01
    assert RadioProfile.of({"kind": "lora", "maxPayload": 64}).max_payload == 64
    assert RadioProfile.of({"kind": "wifi"}).duty_cycle is None


def test_modd_plan_refuses_with_exit_5(scenarios_dir: Path, tmp_path: Path) -> None:
    path = tmp_path / "lora.modd"
    path.write_text((scenarios_dir / "scenario1.modd").read_text() + f"Link {{ {LORA_SF7_2PC} }}\n")
    parser = argparse.ArgumentParser(prog="modd")
    register(parser.add_subparsers(dest="command", required=True))
    out = io.StringIO()
    assert run_plan(parser.parse_args(["plan", str(path)]), out) == 5
    text = out.getvalue()
    assert "REFUSED BY THE RADIO" in text and "nearest plans that fit:" in text
    out = io.StringIO()
    assert run_plan(parser.parse_args(["plan", str(path), "--json"]), out) == 5
    doc = json.loads(out.getvalue())
    assert doc["radio"]["proposals"] and doc["radio"]["duty_share"] > 1
    assert validate_contract("plan", doc) == []


def test_radio_settings_round_trip_and_located_errors(scenarios_dir: Path) -> None:
    link = (
        LORA_SF7 + " bandwidth = 250000; codingRate = 8; preamble = 12; explicitHeader = false;"
        " crc = false; lowDataRate = true; dutyCycle = 0.1; txW = 0.1; idleW = 0;"
    )
    model = _model(scenarios_dir, "scenario1.modd", link)
    radio = model["link"]["radio"]
    assert (radio["kind"], radio["bandwidthHz"], radio["codingRate"], radio["preamble"]) == (
        "lora",
        250000,
        8,
        12,
    )
    assert (radio["explicitHeader"], radio["crc"], radio["lowDataRate"]) == (False, False, True)
    profile = RadioProfile.of(radio)
    assert (profile.duty_cycle, profile.tx_w, profile.idle_w, profile.battery_wh) == (
        0.1,
        0.1,
        0.0,
        50.0,
    )
    again = load_text(print_model(model), "again.modd")
    assert again.model == model
    base = (scenarios_dir / "scenario1.modd").read_text()
    for setting, pointer, words in (
        ("bandwidth = 100000;", "/link/radio/bandwidthHz", "not a LoRa bandwidth"),
        ("dutyCycle = 1.5;", "/link/radio/dutyCycle", "must be in (0, 1]"),
        ("battery = 0;", "/link/radio/batteryWh", "must be > 0"),
        ("sf = 13;", "/link/radio/spreadingFactor", "maximum of 12"),
        ("crc = yes;", "/link/radio/crc", "takes true or false"),
    ):
        text = base + f'Link {{ transport = serial; device = "/d"; radio = lora; {setting} }}\n'
        diags = load_text(text, "bad.modd").diagnostics
        hits = [d for d in diags if d.pointer == pointer and words in d.message]
        assert hits and hits[0].location is not None and hits[0].location.line > 0, diags
