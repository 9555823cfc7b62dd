"""Planned against measured air time, every byte on the air (issue 39): the real
PubBroker and SubBroker over serial through the radio emulator (the relay in this
process recording each packet, tests/subbroker/test_radio_airtime.py), SiK and LoRa
profiles, scenario 1 and a long-window set (every subscription at 2 s), without and
with a declared resolution (0.01 on every variable in +-10, the uniform load, a 0.2 s
accepted delay: one window a datagram). The PubBroker sends STATUS every 10 s and
answers the SubBroker's keepalive PING (every 30 s) with a PONG; the measured air time
counts every packet it sent (DATA, STATUS, PONG), each kind at its own rate. Per row:
the planner's "about" and "at most", the measured, measured / about, and whether the
bound held. Asserts nothing.

The "about" is planned for the run's length (``status_horizon_s``: the STATUS
frames such a run sends, whose counters are younger than an hour's) and, with a
declared resolution, calibrated by the archive of ANOTHER run of the same load
(the other radio's row of the same set: ``modd plan --calibrate``, issue 34), as an
operator plans from an earlier flight: a value sized at its declared range is a
bound, not an estimate. The uncalibrated figure is printed beside it.

    .venv/bin/python tests/bench/bench_airtime.py [--seconds 60] [--json F]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from tempfile import TemporaryDirectory
from typing import Any

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "subbroker"))
sys.path.insert(0, str(HERE))

from modd.radio import relay  # noqa: E402
from subbroker_harness import model_copy  # noqa: E402
from test_radio_airtime import (  # noqa: E402
    STATUS_S,
    _archive_samples,
    _at_resolution,
    _Recording,
    long_windows,
    measure_serial,
    plan_of,
)

# LoRa SF7 at a 50 % limit: every row's plan fits (the emulator's silence after
# each packet ends before the next)
PROFILES: dict[str, dict[str, Any]] = {
    "sik": {"kind": "sik"},
    "lora": {"kind": "lora", "dutyCycle": "0.5"},
}


def _model(tmp: Path, radio: dict[str, Any], long: bool, resolution: bool) -> dict[str, Any]:
    model: dict[str, Any]
    if resolution:
        model = _at_resolution(tmp, 10, "0.2", radio)
    else:
        model = json.loads(model_copy(tmp, "scenario1.modd").read_text())
        model["link"] = {"transport": "serial", "device": "", "radio": radio}
    return long_windows(model) if long else model


def row(tmp: Path, name: str, long: bool, resolution: bool, seconds: float) -> dict[str, Any]:
    model = _model(tmp, PROFILES[name], long, resolution)
    plan = plan_of(model, status_horizon_s=round(seconds))
    r = plan.radio
    assert r is not None and r.ceiling is not None and plan.budget is not None
    _, air, _, by_kind = measure_serial(tmp, model, seconds)
    return {
        "radio": name,
        "set": "long windows" if long else "scenario 1",
        "resolution": "0.01" if resolution else "-",
        "about_s_h": round(r.air_s_per_hour, 2),
        "at_most_s_h": round(r.ceiling.air_s_per_hour, 2),
        "measured_s_h": round(air, 2),
        "measured_over_about": round(air / r.air_s_per_hour, 3),
        "bound_holds": air <= r.ceiling.air_s_per_hour,
        "planned_control_s_h": round(r.control_s_per_hour, 2),
        "measured_by_kind_s_h": {k: round(v, 2) for k, v in sorted(by_kind.items())},
        "planned_packets_h": round(r.packets_per_hour, 1),
        "_model": model,
        "_archive": tmp / "archive",
    }


def calibrate(rows: list[dict[str, Any]], seconds: float) -> None:
    """Each row with a resolution planned again, calibrated by the archive of the
    other radio's row of the same set (another run of the same load)."""
    from modd_plan.calibration import Calibration

    for x in rows:
        if x["resolution"] == "-":
            continue
        other = next(
            y
            for y in rows
            if y["radio"] != x["radio"] and y["set"] == x["set"] and y["resolution"] != "-"
        )
        cal = Calibration(f"{other['radio']}.mcap", _archive_samples(other["_archive"]))
        r = plan_of(x["_model"], calibration=cal, status_horizon_s=round(seconds)).radio
        assert r is not None and r.calibration is not None and not r.calibration.missing
        x["uncalibrated_about_s_h"] = x["about_s_h"]
        x["about_s_h"] = round(r.air_s_per_hour, 2)
        x["calibrated_by"] = other["radio"]
        x["measured_over_about"] = round(x["measured_s_h"] / r.air_s_per_hour, 3)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=60.0, help="load per row")
    ap.add_argument("--json", type=Path, help="write the rows here too")
    args = ap.parse_args()
    setattr(relay, "AirtimeChannel", _Recording)  # noqa: B010  # every packet recorded
    rows = []
    with TemporaryDirectory(prefix="modd-bench-airtime-") as d:
        for name in PROFILES:
            for long in (False, True):
                for resolution in (False, True):
                    tmp = Path(d) / f"{name}-{int(long)}-{int(resolution)}"
                    tmp.mkdir()
                    rows.append(row(tmp, name, long, resolution, args.seconds))
        calibrate(rows, args.seconds)
    for x in rows:
        x.pop("_model")
        x.pop("_archive")
        print(json.dumps(x), flush=True)
    print(f"\nserial, STATUS every {STATUS_S} s, {args.seconds:g} s of load a row; air s/h")
    head = "| radio | set | resolution | about | (uncalibrated) | at most | measured |"
    print(head + " measured/about | bound holds |")
    print("|" + " --- |" * 9)
    for x in rows:
        print(
            f"| {x['radio']} | {x['set']} | {x['resolution']} | {x['about_s_h']} | "
            f"{x.get('uncalibrated_about_s_h', '-')} | {x['at_most_s_h']} | "
            f"{x['measured_s_h']} | {x['measured_over_about']} | "
            f"{'yes' if x['bound_holds'] else 'NO'} |"
        )
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
