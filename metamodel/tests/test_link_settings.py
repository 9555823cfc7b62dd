"""The link block's transport settings (udp, serial): parsed, printed back,
validated with located errors."""

from __future__ import annotations

import pytest
from modd_model import load_text
from modd_model.printer import print_model

BASE = """\
Drone usv {
    Sensors {
        Sensor imu measures {
            ax(METER_PER_SECOND_SQUARED);
            ay(METER_PER_SECOND_SQUARED);
        }
    }
}
PubBroker("127.0.0.1":7171, "/logs");
SubBroker("127.0.0.1":7272, "/conf");
Publishers {
    Publisher pub_1("127.0.0.1":7373, 0.04, "usv.imu.ax", "usv.imu.ay");
}
Subscriptions {
    Subscriber sub_1("127.0.0.1":7401, "usv.imu.ax", 2.0, AVERAGE);
}
"""

SERIAL = """Link {
    transport = serial;
    device = "/dev/ttyUSB0";
    baud = 57600;
    rate = 3600;
    packet = 252;
    delay = 1.5;
}
"""


def _with_link(link: str) -> str:
    return BASE.replace("Publishers {", link + "Publishers {")


def test_serial_link_parses_and_prints_back() -> None:
    result = load_text(_with_link(SERIAL), "m.modd")
    assert result.ok, [str(d) for d in result.diagnostics]
    assert result.model is not None
    assert result.model["link"] == {
        "transport": "serial",
        "device": "/dev/ttyUSB0",
        "baud": 57600,
        "rateBps": 3600,
        "maxPacket": 252,
        "acceptedDelayS": "1.5",
    }
    printed = print_model(result.model)
    assert SERIAL in printed
    again = load_text(printed, "p.modd")
    assert again.model == result.model


def test_udp_link_parses() -> None:
    result = load_text(_with_link("Link { transport = udp; rate = 4000; packet = 1200; }\n"))
    assert result.ok, [str(d) for d in result.diagnostics]
    assert result.model is not None and result.model["link"]["transport"] == "udp"


@pytest.mark.parametrize(
    ("link", "fragment", "pointer", "line"),
    [
        ("Link { transport = radio; }\n", "'radio' is not one of", "/link/transport", 11),
        ("Link { transport = serial; }\n", "needs the radio's device", "/link", 11),
        (
            'Link { transport = udp;\n device = "/dev/x"; }\n',
            "only for a serial link",
            "/link/device",
            12,
        ),
        (
            "Link { delay = 0; }\n",
            "accepted delay must be greater than zero",
            "/link/acceptedDelayS",
            11,
        ),
        ("Link { packet = 8; }\n", "8 is less than the minimum of 32", "/link/maxPacket", 11),
        (
            'Link { transport = serial; device = "/dev/x";\n packet = 9000; }\n',
            "larger than any telemetry radio",
            "/link/maxPacket",
            12,
        ),
        ('Link { rate = "fast"; }\n', "takes a whole number", "/link/rateBps", 11),
    ],
)
def test_bad_link_settings_are_located(link: str, fragment: str, pointer: str, line: int) -> None:
    result = load_text(_with_link(link), "m.modd")
    hits = [d for d in result.diagnostics if fragment in d.message]
    assert hits, [str(d) for d in result.diagnostics]
    assert hits[0].pointer == pointer
    assert hits[0].location is not None and hits[0].location.line == line
