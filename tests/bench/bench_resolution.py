"""Declared resolution on the live link (issue 34), side by side in one run:
the real PubBroker and SubBroker over serial through modd-radio, scenario 1
and 2 with today's float32 link and with 0.01 (m/s², rad/s, ... in each
variable's unit) declared on every variable; drone->base bytes/s as the
emulator counted them, the planner's prediction, windows delivered, and the
largest error of a delivered window against the window recomputed from the
on-board archive (the official mcap reader). Two loads: a smooth sea-wave
signal (what a resolution is for) and uniform noise in [-10, 10] (the worst
case: consecutive windows thousands of steps apart). MAVLink 2 and zenoh rows
come from bench_radio.py (same emulator, same scenarios). The LoRa row's
planner is also calibrated by the archive of the scenario 1 0.01 wave row (a
different run of the same load generator; with --lora-only, a calibration run
of --seconds first): planned at most, planned calibrated and measured, side by
side. Asserts nothing.

    .venv/bin/python tests/bench/bench_resolution.py [--seconds 30] [--json F]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from tempfile import TemporaryDirectory
from typing import Any

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "subbroker"))
sys.path.insert(0, str(HERE))

from bench_radio import _snapshot, _watch, delivery  # noqa: E402
from modd.ports import free_port  # noqa: E402
from modd_plan import make_plan  # noqa: E402
from radio_harness import (  # noqa: E402
    start_pubbroker_dgram,
    start_radio_serial,
    subbroker_dgram_config,
    through_profile,
)
from subbroker_harness import (  # noqa: E402
    model_copy,
    oracle_value,
    processes,
    read_archive,
    start_load,
    start_subbroker,
    window_samples,
)

STEP = 0.01
TARGET = 40.0  # scenario 1 over serial at 0.01 m/s², drone->base B/s
RANGE = 20  # validMin/validMax declared with the resolution (±20 m/s², the wave is ±1.1)
LORA: dict[str, Any] = {
    "kind": "lora",
    "spreadingFactor": 7,
    "bandwidthHz": 125000,
    "dutyCycle": "0.01",
}


def _model(tmp: Path, scenario: str, resolution: float | None) -> Path:
    path = model_copy(tmp, scenario)
    doc = json.loads(path.read_text())
    for s in doc["drone"]["sensors"]:
        for v in s["variables"]:
            if resolution is not None:  # the range bounds the planner's absolute values
                v.update(resolution=resolution, validMin=-RANGE, validMax=RANGE)
    path.write_text(json.dumps(doc))
    return path


def max_error(values: dict[str, list[Any]], archive: dict[str, Any]) -> float:
    worst = 0.0
    for vals in values.values():
        for v in vals:
            want, _ = oracle_value(
                v.aggregation, window_samples(archive.get(v.topic, []), v.start_ns, v.end_ns)
            )
            if want is not None and v.value is not None:
                worst = max(worst, abs(v.value - want))
    return worst


def run(
    tmp: Path,
    scenario: str,
    resolution: float | None,
    signal: str,
    spec: str,
    seconds: float,
    samples: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """One serial row; ``samples`` (when given) gets the archive's samples by
    topic (modd plan --calibrate's reader), for the LoRa row's calibration."""
    model = _model(tmp, scenario, resolution)
    doc = json.loads(model.read_text())
    doc["link"] = {**doc.get("link", {}), "transport": "serial", "device": "/dev/null"}
    predicted = make_plan(doc).budget
    zport, ingress = free_port(), free_port()
    radio, base, drone = start_radio_serial(tmp, spec or "seed=1")
    pb = start_pubbroker_dgram(
        tmp, model, {"transport": "serial", "device": drone, "port": 1}, ingress
    )
    sb = start_subbroker(
        tmp, subbroker_dgram_config(tmp, model, "127.0.0.1:1", zport, "serial", device=base)
    )
    session = None
    try:
        session, got = _watch(zport)
        if not sb.wait_log("running", 60):
            raise RuntimeError(sb.log()[-2000:])
        load = start_load(tmp, model, ingress, seconds + 4, signal=signal)
        time.sleep(3.0)
        t0, c0 = time.monotonic(), _snapshot(radio)
        time.sleep(seconds)
        t1, c1 = time.monotonic(), _snapshot(radio)
        load.p.wait(30)
        time.sleep(4.0)  # the last NACKs
        values = got.snapshot()
        with processes(load):
            pass
    finally:
        with processes(radio, pb, sb):
            pass
        if session is not None:
            session.close()
    archive = read_archive(tmp / "archive", model)
    delivered, expected, _ = delivery(values, archive)
    if samples is not None:
        from test_radio_airtime import _archive_samples

        samples.update(_archive_samples(tmp / "archive"))
    return {
        "scenario": scenario,
        "resolution": resolution,
        "signal": signal,
        "radio": spec,
        "down_Bps": round((c1[3] - c0[3]) / (t1 - t0), 1),
        "planned_Bps": round(predicted.drone_to_base, 1) if predicted else None,
        "delivered": delivered,
        "expected": expected,
        "max_error": max_error(values, archive),
    }


def run_lora(tmp: Path, seconds: float, samples: dict[str, Any]) -> dict[str, Any]:
    """Scenario 1 at 0.01 m/s² over LoRa SF7/125 kHz at 1 % duty: the planner
    refuses it and proposes; the first proposal runs through the emulator with
    the LoRa profile (the relay in this process, recording each packet's air
    time, as test_radio_airtime.py); planned (at most, and calibrated by
    ``samples``, another run's archive) and measured air time and energy."""
    from modd.radio import relay
    from modd_plan.calibration import Calibration
    from modd_plan.radio import RadioProfile
    from test_radio_airtime import _is_data, _Recording

    relay.AirtimeChannel = _Recording  # type: ignore[attr-defined]
    base, base_path = relay.open_pty_pair()
    drone, drone_path = relay.open_pty_pair()
    path = _model(tmp, "scenario1.modd", STEP)
    doc = json.loads(path.read_text())
    doc["link"] = {"transport": "serial", "device": base_path, "radio": LORA}
    refused = make_plan(doc)
    assert refused.radio is not None and refused.proposals, "the plan was expected to refuse"
    chosen = refused.proposals[0]
    path.write_text(json.dumps(chosen.model))
    predicted = chosen.report
    planned = make_plan(chosen.model).budget  # the proposal's packets, as planned
    assert planned is not None
    calibrated = make_plan(
        chosen.model, calibration=Calibration("serial wave row", samples)
    ).radio  # the same proposal, its values sized from the other run's samples
    assert calibrated is not None and calibrated.calibration is not None
    profile = RadioProfile.of(LORA)
    # The emulator times every packet with the LoRa profile but enforces no duty
    # limit: at 1 % each side, the handshake and the CONFIG (0.3 s of air, then 30 s
    # of silence) take minutes; the measured air time is compared with the limit.
    emulated = RadioProfile.of({**LORA, "dutyCycle": "1"})
    up, down = through_profile(
        tmp, path, (base, base_path, drone, drone_path), emulated, seconds, signal="wave"
    )
    sent = [(t, packet, air) for t, packet, air in down.sent if _is_data(packet)]
    data = [(t, air) for t, _, air in sent]
    span = data[-1][0] - data[0][0]
    air = sum(a for _, a in data[1:]) * 3600 / span
    rx = sum(a for t, _, a in up.sent if data[0][0] <= t <= data[-1][0]) * 3600 / span
    energy = profile.tx_w * air + profile.rx_w * rx + profile.idle_w * (3600 - air - rx)
    return {
        "refused": refused.radio.error,
        "proposal": chosen.describe(),
        "packets": len(data),
        # datagram by datagram: the planner's sizes (each value at its declared
        # range) against the emulator's, and one packet's air time for each
        "planned_packet_bytes": _sizes(planned.packet_sizes, profile),
        "measured_packet_bytes": _sizes([len(p) for _, p, _ in sent], profile),
        "planned_figures_are": predicted.at_most.strip() or "exact",
        "planned_air_s_per_hour": round(predicted.air_s_per_hour, 2),
        "calibrated_air_s_per_hour": round(calibrated.air_s_per_hour, 2),
        "measured_air_s_per_hour": round(air, 2),
        "planned_energy_j_per_hour": round(predicted.energy_j_per_hour, 1),
        "calibrated_energy_j_per_hour": round(calibrated.energy_j_per_hour, 1),
        "measured_energy_j_per_hour": round(energy, 1),
        "calibrated_value_bytes": {
            k: f"{float(v.absolute):.2f} / {float(v.delta):.2f} ({v.windows} windows)"
            for k, v in calibrated.calibration.sizes
        },
        "dropped_by_radio": dict(down.dropped),
        "limit_air_s_per_hour": 3600 * float(LORA["dutyCycle"]),
    }


def _sizes(sizes: Any, profile: Any) -> dict[str, str]:
    """Packet size (B) -> "count x air time (ms)"."""
    counts: dict[int, int] = {}
    for n in sizes:
        counts[n] = counts.get(n, 0) + 1
    return {
        str(n): f"{c} x {1000 * profile.one_packet_s(n):.2f} ms" for n, c in sorted(counts.items())
    }


def main() -> int:
    p = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    p.add_argument("--seconds", type=float, default=30.0)
    p.add_argument("--json", type=Path)
    p.add_argument(
        "--lora-only",
        action="store_true",
        help="only the LoRa run (after the serial row whose archive calibrates it)",
    )
    args = p.parse_args()
    plan = [
        ("scenario1.modd", None, "wave", ""),
        ("scenario1.modd", STEP, "wave", ""),
        ("scenario1.modd", STEP, "wave", "loss=0.05,latency_ms=40,seed=5"),
        ("scenario1.modd", None, "uniform", ""),
        ("scenario1.modd", STEP, "uniform", ""),
        ("scenario2.modd", None, "wave", ""),
        ("scenario2.modd", STEP, "wave", ""),
    ]
    rows: list[dict[str, Any]] = []
    samples: dict[str, Any] = {}  # the calibration of the LoRa row: plan[1]'s archive
    for scenario, resolution, signal, spec in plan[1:2] if args.lora_only else plan:
        keep = samples if (scenario, resolution, signal, spec) == plan[1] else None
        with TemporaryDirectory(prefix="modd-bench-res-") as d:
            rows.append(run(Path(d), scenario, resolution, signal, spec, args.seconds, keep))
        print(json.dumps(rows[-1]), flush=True)
    print(
        "\n| scenario | resolution | load | radio | drone→base B/s | planned B/s | "
        "delivered | max error vs archive |"
    )
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for r in rows:
        share = f"{100 * r['delivered'] / r['expected']:.2f} %" if r["expected"] else "—"
        print(
            f"| {r['scenario']} | {r['resolution'] or 'float32'} | {r['signal']} | "
            f"{r['radio'] or '—'} | {r['down_Bps']} | {r['planned_Bps']} | {share} "
            f"({r['delivered']}/{r['expected']}) | {r['max_error']:.2e} |"
        )
    with TemporaryDirectory(prefix="modd-bench-lora-") as d:
        try:
            lora = run_lora(Path(d), max(60.0, 2 * args.seconds), samples)
        except Exception as exc:  # the serial rows above stand on their own
            lora = {"error": repr(exc)}
    print("\nLoRa SF7/125 kHz, 1 % duty cycle, scenario 1 at 0.01 m/s2 (wave load):")
    print(json.dumps(lora, indent=1))
    print(
        f"\ntarget: scenario 1 over serial at {STEP} m/s2 <= {TARGET} B/s, every window "
        f"within {STEP / 2} of the archive's"
    )
    if args.json:
        args.json.write_text(json.dumps({"serial": rows, "lora": lora}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
