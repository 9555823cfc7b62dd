"""Done when (issue 39, item 2): MWV true and relative wind land in two topics by a
condition in the model, and XDR transducers by their names; a CTD's record types
likewise. Real-style sentences written by pynmea2 (a library we did not write: valid
checksums; MWV T and R interleaved, a void one among them; XDR with several
transducers per sentence, in any order, some with none the model reads) go through
pseudo-terminals into the ``modd-sensors`` process, on to the real PubBroker; its
archive, read with the official MCAP reader, holds in each topic exactly the values
its condition selects (pynmea2's own decode of each sentence is the oracle), none of
the other's."""

from __future__ import annotations

import random
import sys
import time
from collections import defaultdict
from pathlib import Path

import pynmea2  # type: ignore[import-untyped]
from devices import PtyDevice, wait_until
from mavlink_harness import Proc, load_model, read_archive, start_pubbroker
from modd.ports import free_port
from test_sensors_corpus import _health

MODEL = """
Drone usv { Sensors {
    Sensor wx "weather station" kind nmea on "DEV/wx" measures {
        true_angle("deg", float64) from sentence MWV.angle where reference = T;
        true_speed("kt", float64) from sentence MWV.speed where reference = T;
        apparent_angle("deg", float64) from sentence MWV.angle where reference = R;
        apparent_speed("kt", float64) from sentence MWV.speed where reference = "R";
        air_temperature(DEGREE_CELSIUS, float64) from sentence XDR.value where id = AIRTEMP;
        pressure(BAR, float64) from sentence XDR.value where id = BARO;
        humidity("percent", float64) from sentence XDR.value where id = HUMIDITY;
    }
    Sensor ctd kind ascii on "DEV/ctd" measures {
        temperature(DEGREE_CELSIUS, float64) from column 2 where column 1 = S;
        battery("V", float64) from column 2 where column 1 = B;
    }
} }
PubBroker onboard("127.0.0.1":7171, "/tmp/unused");
SubBroker base("127.0.0.1":7272, "/tmp/unused");
Publishers {
    Publisher wx(0.1, "usv.wx.true_angle", "usv.wx.true_speed", "usv.wx.apparent_angle",
                 "usv.wx.apparent_speed", "usv.wx.air_temperature", "usv.wx.pressure",
                 "usv.wx.humidity");
    Publisher water(0.1, "usv.ctd.temperature", "usv.ctd.battery");
}
"""
XDR_NAMES = {"AIRTEMP": "air_temperature", "BARO": "pressure", "HUMIDITY": "humidity"}
TRANSDUCERS = [
    ("C", "C", "AIRTEMP"),
    ("P", "B", "BARO"),
    ("H", "P", "HUMIDITY"),
    ("A", "D", "PITCH"),
]


def _sentences(rng: random.Random) -> list[str]:
    """MWV T and R interleaved at random (true angles 100-200°, relative 0-100°: the two
    sets cannot be mistaken), one void; XDR with 1-4 transducers in any order."""
    out = []
    for i in range(60):
        ref = rng.choice("TR")
        angle = rng.uniform(100, 200) if ref == "T" else rng.uniform(0, 100)
        speed = rng.uniform(20, 30) if ref == "T" else rng.uniform(0, 10)
        status = "V" if i == 17 else "A"
        wind = (f"{angle:.1f}", ref, f"{speed:.1f}", "N", status)
        out.append(str(pynmea2.MWV("WI", "MWV", wind)))
        if i % 2:
            quads = rng.sample(TRANSDUCERS, rng.randint(1, 4))
            values = [f"{rng.uniform(-5, 35):.2f}" for _ in quads]
            fields = tuple(
                x for (t, u, n), v in zip(quads, values, strict=True) for x in (t, v, u, n)
            )
            out.append(str(pynmea2.XDR("YX", "XDR", fields)))
    return out


def _expected(lines: list[str]) -> dict[str, list[float]]:
    """What each topic must hold, by pynmea2's decode of each sentence."""
    want: dict[str, list[float]] = defaultdict(list)
    for line in lines:
        msg = pynmea2.parse(line, check=True)
        if isinstance(msg, pynmea2.MWV) and msg.status == "A":
            kind = "true" if msg.reference == "T" else "apparent"
            want[f"usv.wx.{kind}_angle"].append(float(msg.wind_angle))
            want[f"usv.wx.{kind}_speed"].append(float(msg.wind_speed))
        elif isinstance(msg, pynmea2.XDR):
            for i in range(msg.num_transducers):
                t = msg.get_transducer(i)
                if t.id in XDR_NAMES:
                    want[f"usv.wx.{XDR_NAMES[t.id]}"].append(float(t.value))
    return want


def test_conditions_split_multiplexed_instruments_into_topics(tmp_path: Path) -> None:
    rng = random.Random(39)
    nmea_lines = _sentences(rng)
    ctd_lines = [f"S,{rng.uniform(5, 15):.3f},{rng.uniform(0, 50):.2f}" for _ in range(20)]
    ctd_lines[3:3] = ["B,12.41", "B,12.40", "X,not,a,record"]
    want = _expected(nmea_lines)
    want["usv.ctd.temperature"] = [float(x.split(",")[1]) for x in ctd_lines if x[0] == "S"]
    want["usv.ctd.battery"] = [12.41, 12.40]
    assert {"usv.wx.true_angle", "usv.wx.apparent_angle", "usv.wx.pressure"} <= set(want)

    dev = tmp_path / "dev"
    dev.mkdir()
    wx, ctd = PtyDevice(dev / "wx"), PtyDevice(dev / "ctd")
    src = tmp_path / "boat.modd"
    src.write_text(MODEL.replace("DEV", str(dev)))
    model = load_model(src, free_port())
    broker, _, model_json = start_pubbroker(model, tmp_path / "run")
    status = tmp_path / "sensors.json"
    sensors = Proc(
        [
            str(Path(sys.executable).parent / "modd-sensors"),
            "--model",
            str(model_json),
            "--status-file",
            str(status),
        ],
        tmp_path / "sensors.log",
    )
    try:
        wait_until(
            lambda: all(_health(status).get(s, {}).get("connected") for s in ("wx", "ctd")),
            30,
            "both devices open",
        )
        for line in nmea_lines:
            wx.write(line.encode() + b"\r\n")
            time.sleep(0.01)
        for line in ctd_lines:
            ctd.write(line.encode() + b"\r\n")
            time.sleep(0.01)
        wait_until(
            lambda: (
                _health(status)["wx"]["linesOk"] == len(nmea_lines)
                and _health(status)["ctd"]["linesOk"] == len(ctd_lines)
            ),
            30,
            "every line read",
        )
        health = _health(status)
    finally:
        sensors_code = sensors.stop()
        broker.stop()
        wx.close()
        ctd.close()
    assert sensors_code == 0, sensors.log()
    archive = read_archive(tmp_path / "run" / "archive")
    for topic, values in want.items():
        got = [v for _, v in archive.get(topic, [])]
        assert sorted(got) == sorted(values), (topic, got, values)
    assert set(archive) == set(want), sorted(archive)
    xdr_without = sum(
        1
        for line in nmea_lines
        if line.startswith("$YXXDR") and not any(n in line for n in XDR_NAMES)
    )
    wxh = health["wx"]
    assert wxh["linesBad"] == 0 and wxh["ignored"] == xdr_without, wxh
    assert wxh["noFix"] == 2 and wxh["values"] == sum(
        len(v) for k, v in want.items() if ".wx." in k
    )
    assert health["ctd"]["ignored"] == 1 and health["ctd"]["linesBad"] == 0, health["ctd"]
