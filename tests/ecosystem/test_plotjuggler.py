"""``modd-plotjuggler``: one UDP datagram per delivered window, in the JSON
PlotJuggler's UDP server flattens (``/<drone>/<subscriber>/value``, timestamp
field in seconds); empty windows send nothing. The SubBroker's side is a
zenoh session putting real delivered values."""

from __future__ import annotations

import json
import socket
import subprocess
import sys
import time
from dataclasses import replace
from pathlib import Path
from typing import Any, cast

import pytest
from modd.plotjuggler import datagrams, parse_udp
from modd.ports import free_port
from modd.subbroker.payload import DeliveredValue
from modd_contracts.types_gen import DeliveredValue as DeliveredDict

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from support.loopback import shared_credentials, zenoh_router  # noqa: E402

VECTORS = Path(__file__).resolve().parents[2] / "contracts" / "vectors" / "delivered_value.json"


def flatten(doc: dict[str, object], prefix: str = "") -> dict[str, object]:
    """PlotJuggler's JSON parser (plugins/ParserJSON, 3.9): nested keys joined
    by '/', an array's items as ``name[i]``, one point per leaf at the
    message's timestamp."""
    out: dict[str, object] = {}
    for k, v in doc.items():
        if isinstance(v, dict):
            out.update(flatten(v, f"{prefix}/{k}"))
        elif isinstance(v, list):
            out.update({f"{prefix}/{k}[{i}]": x for i, x in enumerate(v)})
        else:
            out[f"{prefix}/{k}"] = v
    return out


def test_datagrams_from_delivered_values() -> None:
    udp = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    udp.bind(("127.0.0.1", 0))
    udp.settimeout(10)
    port = free_port()
    zep = f"tcp/127.0.0.1:{port}"
    # the SubBroker's router, authentication and access control on; the bridge is a viewer
    router = zenoh_router(port)
    station = router.__enter__()
    viewer = str(shared_credentials().cred_file("viewer"))
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "modd.plotjuggler",
            "--modd-connect",
            zep,
            "--credentials",
            viewer,
            "--udp",
            f"127.0.0.1:{udp.getsockname()[1]}",
            "--drone",
            "usv",
        ],
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert proc.stdout is not None and "modd-plotjuggler" in proc.stdout.readline()
        time.sleep(1.0)
        values = [
            DeliveredValue(
                "sub_3",
                "usv.a.x",
                "AVERAGE",
                "0.25",
                "M",
                1,
                k,
                k * 250_000_000,
                (k + 1) * 250_000_000,
                0.5 * k,
                4,
                0,
            )
            for k in range(1, 4)
        ]
        values.insert(
            1,
            DeliveredValue(
                "sub_5", "usv.a.z", "MIN", "0.25", "M", 1, 0, 0, 250_000_000, None, None, 0
            ),
        )  # empty: nothing sent
        values.append(
            DeliveredValue(
                "all_1", "usv.a.z", "ALL", "1", "M", 1, 0, 0, 1_000_000_000, [1.0, 2.0], 2, 0
            )
        )
        # a backfilled (historical) window, older than the live ones, arriving last
        values.append(replace(values[0], value=-7.5, backfilled=True))
        for v in values:
            station.put(f"modd/usv/sub/{v.subscriber}", v.to_json())
        got = [json.loads(udp.recv(65536)) for _ in range(6)]
        udp.settimeout(0.5)
        with pytest.raises(TimeoutError):
            udp.recv(65536)
    finally:
        proc.terminate()
        proc.wait(10)
        if proc.stdout is not None:
            proc.stdout.close()
        router.__exit__(None, None, None)
        udp.close()
    series = [flatten(g) for g in got]
    live = {"/usv/sub_3/count": 4, "/usv/sub_3/backfilled": 0}
    assert series[:3] == [
        {"/timestamp": (k + 1) * 0.25, "/usv/sub_3/value": 0.5 * k, **live} for k in range(1, 4)
    ]
    assert series[3:5] == [
        {"/timestamp": 0.5, "/usv/all_1/value": 1.0},
        {
            "/timestamp": 1.0,
            "/usv/all_1/value": 2.0,
            "/usv/all_1/count": 2,
            "/usv/all_1/backfilled": 0,
        },
    ]
    # the historical window is marked and stamped with its own window's end (placed in time)
    assert series[5] == {
        "/timestamp": 0.5,
        "/usv/sub_3/value": -7.5,
        "/usv/sub_3/count": 4,
        "/usv/sub_3/backfilled": 1,
    }


def plotted(lines: list[bytes]) -> dict[str, list[tuple[float, object]]]:
    """The series PlotJuggler makes of datagrams: name -> [(t, value)]."""
    out: dict[str, list[tuple[float, object]]] = {}
    for line in lines:
        flat = flatten(json.loads(line))
        t = flat.pop("/timestamp")
        assert isinstance(t, float)
        for name, v in flat.items():
            out.setdefault(name, []).append((t, v))
    return out


def test_every_contract_vector_plots_as_its_samples() -> None:
    """The delivered-value contract says what a chart plots (``samples``: ALL
    spread over the window): PlotJuggler gets exactly that, as one series per
    subscriber (an ALL window was 14 unrelated ``value[i]`` series before)."""
    for vector in json.loads(VECTORS.read_text())["vectors"]:
        doc = json.loads(vector["line"])
        series = plotted(datagrams("usv", doc["subscriber"], doc))
        values = series.pop(f"/usv/{doc['subscriber']}/value", [])
        assert len(values) == len(vector["samples"]), vector["name"]
        for (t, v), (want_t, want_v) in zip(values, vector["samples"], strict=True):
            assert t == pytest.approx(want_t) and v == want_v, vector["name"]
        # the historical mark rides with the window's last sample: 1 backfilled, 0 live
        mark = series.pop(f"/usv/{doc['subscriber']}/backfilled", [])
        assert [m for _, m in mark] == ([1 if doc.get("backfilled") else 0] if values else [])
        assert set(series) <= {f"/usv/{doc['subscriber']}/count"}, vector["name"]


def partial(fields: dict[str, Any]) -> DeliveredDict:
    """A delivered value with fields missing, as a bad peer could send."""
    return cast(DeliveredDict, fields)


def test_bad_values_and_options() -> None:
    assert datagrams("usv", "s", partial({"end_ns": 1, "value": float("nan")})) == []
    assert datagrams("usv", "s", partial({"value": 1.0})) == []
    assert datagrams("usv", "s", partial({"end_ns": 10**9, "value": [1.0]})) == []  # no start
    many = datagrams("usv", "s", partial({"start_ns": 0, "end_ns": 10**9, "value": [0.5] * 20_000}))
    assert len(many) == 20_000 and all(len(d) < 100 for d in many)
    backfilled = partial({"end_ns": 10**9, "value": 1, "backfilled": True})
    assert json.loads(datagrams("usv", "s", backfilled)[0])["usv"]["s"]["backfilled"] == 1
    live = partial({"end_ns": 10**9, "value": 1})
    assert json.loads(datagrams("usv", "s", live)[0])["usv"]["s"]["backfilled"] == 0
    assert parse_udp("127.0.0.1:9870") == ("127.0.0.1", 9870)
    assert parse_udp("[::1]:9870") == ("::1", 9870)
    for bad in ("9870", "host:", "host:0", "host:x"):
        with pytest.raises(ValueError, match="HOST:PORT"):
            parse_udp(bad)
