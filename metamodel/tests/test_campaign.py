"""A campaign: one mission model flown by several vehicles (issue 44, item 1).

The oracle for the expansion is the mission text itself, edited by hand the
way a user would write each vehicle's own model (the drone renamed in every
topic, its device and link changed): each vehicle's expanded model must equal
that, and its plan must equal the plan made from it."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from modd_model import load_text, validate
from modd_model.campaign import drone_names, expand
from modd_model.printer import print_model
from modd_plan import make_plan
from modd_plan.campaign import channel_diagnostics, link_bytes_per_s, plan_campaign

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
MISSION = """\
Drone usv "Survey boat" {
    Sensors {
        Sensor imu measures {
            ax(METER_PER_SECOND_SQUARED);
            ay(METER_PER_SECOND_SQUARED);
        }
        Sensor ctd kind ascii on "/dev/ttyUSB1" { baud = 9600; } measures {
            temp(degC) from column 1;
        }
    }
}
PubBroker("127.0.0.1":7171, "/logs");
SubBroker("127.0.0.1":7272, "/conf");
Link { rate = 5000; }
Publishers {
    Publisher pub_1("127.0.0.1":7373, 0.04, "usv.imu.ax", "usv.imu.ay");
    Publisher ctd(0.5, "usv.ctd.temp");
}
Subscriptions {
    Subscriber sub_1("usv.imu.ax", 2.0, AVERAGE);
    Subscriber temp("usv.ctd.temp", 1.0, LAST);
}
"""
CAMPAIGN = """\
Campaign lake "Two boats" {
    Channel ch1 { rate = RATE; }
    Vehicle a { channel = ch1; PubBroker("127.0.0.1":7181, "/logs/a"); }
    Vehicle b "South" {
        channel = ch1;
        PubBroker("127.0.0.1":7182);
        SubBroker("127.0.0.1":7282, "/conf/b");
        device ctd = "/dev/ttyUSB3";
        Link { rate = 900; }
    }
}
"""


def _campaign(rate: int = 100000, extra: str = "") -> str:
    return MISSION + CAMPAIGN.replace("RATE", str(rate)).replace(
        "Vehicle a {", extra + "Vehicle a {"
    )


def _model(text: str) -> dict[str, Any]:
    result = load_text(text)
    assert result.model is not None and result.ok, [str(d) for d in result.diagnostics]
    return result.model


def _by_hand(vehicle: str, pub: str, sub: str | None = None, device: str | None = None) -> str:
    """The vehicle's own model, written as a user would without a campaign."""
    text = MISSION.replace('"usv.', f'"{vehicle}.').replace("Drone usv", f"Drone {vehicle}")
    text = text.replace('PubBroker("127.0.0.1":7171, "/logs")', pub)
    if sub is not None:
        text = text.replace('SubBroker("127.0.0.1":7272, "/conf")', sub)
    if device is not None:
        text = text.replace('"/dev/ttyUSB1"', f'"{device}"').replace("rate = 5000", "rate = 900")
    return text


def test_expansion_equals_each_vehicles_own_model() -> None:
    model = _model(_campaign())
    drones = expand(model)
    assert list(drones) == drone_names(model) == ["a", "b"]
    a = _model(_by_hand("a", 'PubBroker("127.0.0.1":7181, "/logs/a")'))
    b = _model(
        _by_hand(
            "b",
            'PubBroker("127.0.0.1":7182, "/logs")',
            'SubBroker("127.0.0.1":7282, "/conf/b")',
            "/dev/ttyUSB3",
        ).replace('Drone b "Survey boat"', 'Drone b "South"')
    )
    assert drones["a"] == a
    assert drones["b"] == b
    assert make_plan(drones["b"]).to_json() == make_plan(b).to_json()


def test_one_drone_model_is_unchanged() -> None:
    model = _model(MISSION)
    assert expand(model) == {"usv": model}
    assert drone_names(model) == ["usv"]
    plans = plan_campaign(model)
    assert list(plans.plans) == ["usv"] and plans.channels == ()
    assert plans.plans["usv"].to_json() == make_plan(model).to_json()


def test_text_json_text_round_trip() -> None:
    model = _model(_campaign())
    assert _model(print_model(model)) == model
    again = load_text(json.dumps(model), fmt="json")
    assert again.ok and again.model == model


def test_the_example_campaign_is_valid_and_expands_to_three() -> None:
    text = (EXAMPLES / "campaign.modd").read_text()
    model = _model(text)
    assert drone_names(model) == ["usv1", "usv2", "usv3"]
    assert validate(model) == [] or all(d.severity != "error" for d in validate(model))


def _errors(text: str) -> list[tuple[str, str, int | None]]:
    result = load_text(text)
    return [
        (d.pointer, d.message, d.location.line if d.location else None)
        for d in result.diagnostics
        if d.severity == "error"
    ]


def _line_of(text: str, needle: str) -> int:
    """The line of the first occurrence of ``needle`` (a trailing newline: at the line's end)."""
    return text[: text.index(needle)].count("\n") + 1


@pytest.mark.parametrize(
    ("old", "new", "pointer", "words", "needle"),
    [
        (
            "a { channel = ch1",
            "a { channel = ch9",
            "/campaign/vehicles/0/channel",
            "no channel 'ch9'",
            "Vehicle a",
        ),
        (
            "device ctd",
            "device sonar",
            "/campaign/vehicles/1/devices/0/sensor",
            "no sensor 'sonar'",
            "device",
        ),
        (
            "device ctd",
            "device imu",
            "/campaign/vehicles/1/devices/0/sensor",
            "reads no device",
            "device",
        ),
        (
            'Vehicle b "South"',
            "Vehicle a",
            "/campaign/vehicles/1/name",
            "declared twice",
            "Vehicle a {\n",
        ),
        ("7182)", "7181)", "/campaign/vehicles/1/pubBroker", "one PubBroker endpoint", "7181);"),
    ],
)
def test_campaign_errors_are_located(
    old: str, new: str, pointer: str, words: str, needle: str
) -> None:
    text = _campaign().replace(old, new)
    found = _errors(text)
    assert [(p, ln) for p, m, ln in found if words in m] == [(pointer, _line_of(text, needle))], (
        found
    )


def test_a_vehicles_own_problem_is_located_at_the_vehicle() -> None:
    """A serial link needs a device: wrong only for the vehicle that asks for serial."""
    text = _campaign().replace("Link { rate = 900; }", "Link { transport = serial; }")
    found = _errors(text)
    assert any(p.startswith("/campaign/vehicles/1/link") and "'b'" in m for p, m, _ in found), found
    assert not any(p.startswith("/campaign/vehicles/0") for p, _, _ in found), found


def test_unknown_setting_in_a_channel_is_located() -> None:
    text = _campaign().replace("{ rate = 100000; }", "{ rate = 100000; speed = 3; }")
    found = _errors(text)
    assert any("unknown setting 'speed'" in m for _, m, _ in found), found
    assert any(ln == _line_of(text, "Channel ch1") for _, _, ln in found), found


def test_shared_channel_sums_its_vehicles_links() -> None:
    model = _model(_campaign())
    result = plan_campaign(model)
    (channel,) = result.channels
    own = [make_plan(m) for m in expand(model).values()]  # each drone planned on its own
    assert channel.bytes_per_s == pytest.approx(sum(link_bytes_per_s(p) for p in own))
    assert channel.bytes_per_s > 0 and result.fits
    rate = int(channel.bytes_per_s) - 1  # one byte per second short of the sum
    tight = plan_campaign(_model(_campaign(rate)))
    assert not tight.fits
    assert "over its rate" in tight.channels[0].errors[0]
    # each vehicle alone fits that rate: only the sum does not
    assert all(link_bytes_per_s(p) < rate for p in own)


def test_shared_channel_duty_cycle_sums_air_time() -> None:
    lora = "Link { radio = lora; sf = 7; dutyCycle = 0.5; }"
    text = _campaign().replace("Link { rate = 900; }", "")
    text = text.replace("Link { rate = 5000; }", lora)
    text = text.replace("{ rate = 100000; }", "{ dutyCycle = DUTY; }")
    solo = plan_campaign(_model(text.replace("DUTY", "0.9")))
    shares = [p.radio.air_s_per_hour / 3600 for p in solo.plans.values() if p.radio]
    assert len(shares) == 2 and solo.fits
    between = (max(shares) + sum(shares)) / 2  # each alone fits, both together do not
    tight = plan_campaign(_model(text.replace("DUTY", f"{between:.6f}")))
    assert not tight.fits and "duty cycle" in tight.channels[0].errors[0]


def test_cli_plans_every_drone_and_refuses_an_overloaded_channel(tmp_path: Path) -> None:
    path = tmp_path / "c.modd"
    path.write_text(_campaign(10))
    run = subprocess.run(
        [sys.executable, "-m", "modd_model.cli", "plan", str(path)],
        capture_output=True,
        text=True,
        check=False,
    )
    assert run.returncode == 6, run.stderr
    assert re.findall(r"== drone (\w+)", run.stdout) == ["a", "b"]
    assert "over its rate of 10 B/s" in run.stdout


def test_an_overloaded_channel_is_a_diagnostic_at_the_channel() -> None:
    """What the workbench's live plan pins on the model (backend planning.live_plan)."""
    assert channel_diagnostics(_model(_campaign())) == []
    assert channel_diagnostics(_model(MISSION)) == []
    (d,) = channel_diagnostics(_model(_campaign(10)))
    assert d.pointer == "/campaign/channels/0" and "over its rate of 10 B/s" in d.message
