"""``modd-ros2`` against the rmw_zenoh format (ROS 2 Jazzy; ros2/rmw_zenoh
docs/design.md, liveliness_utils.cpp, attachment_helpers.cpp), field by
field, with independent decoders: the CDR payloads decoded by hand with
``struct`` (not by rosbags, which encodes them), the attachment by zenoh's
own deserializer, the type hashes against the published hash of
std_msgs/msg/Float64 and rosbags' own RIHS01 implementation.

The SubBroker's side is played by a zenoh session putting real delivered
values (``modd.subbroker.payload.DeliveredValue``) on ``modd/usv/sub/*``."""

from __future__ import annotations

import json
import math
import struct
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from dataclasses import replace
from typing import Any

import pytest
import zenoh
import zenoh.ext as ze
from modd.ports import free_port
from modd.ros2 import rmw
from modd.ros2.messages import FLOAT64_HASH, TIME, WINDOW, WINDOW_HASH, WINDOW_MSG, typestore
from modd.ros2.typehash import Field, MessageType, type_hash
from modd.subbroker.payload import DeliveredValue

#: std_msgs/msg/Float64's hash as rosidl generates it (float64__description.c:
#: 0x70, 0x5b, 0xa9, ... in the generated C of std_msgs for Jazzy and later).
PUBLISHED_FLOAT64 = "RIHS01_705ba9c3d1a09df43737eb67095534de36fd426c0587779bda2bc51fe790182a"


def test_type_hashes() -> None:
    assert FLOAT64_HASH == PUBLISHED_FLOAT64
    store = typestore()
    assert store.hash_rihs01("std_msgs/msg/Float64") == PUBLISHED_FLOAT64
    assert store.hash_rihs01(WINDOW.name) == WINDOW_HASH
    # the hash depends on every field: a renamed field changes it
    renamed = MessageType(WINDOW.name, (*WINDOW.fields[:-1], Field("agg", "string")))
    assert type_hash(renamed, [TIME]) != WINDOW_HASH
    with pytest.raises(ValueError, match="description of builtin_interfaces"):
        type_hash(WINDOW)
    assert "float64 value" in WINDOW_MSG


def session(listen: str | None = None, connect: str | None = None) -> zenoh.Session:
    c = zenoh.Config()
    c.insert_json5("mode", '"peer"')
    c.insert_json5("scouting/multicast/enabled", "false")
    c.insert_json5("scouting/delay", "0")
    c.insert_json5("listen/endpoints", json.dumps([listen] if listen else []))
    if connect:
        c.insert_json5("connect/endpoints", json.dumps([connect]))
    return zenoh.open(c)


@pytest.fixture
def networks() -> Iterator[tuple[zenoh.Session, zenoh.Session, str, str]]:
    """(MoDD side, ROS side) sessions listening on loopback, with endpoints."""
    modd_ep = f"tcp/127.0.0.1:{free_port()}"
    ros_ep = f"tcp/127.0.0.1:{free_port()}"
    modd, ros = session(listen=modd_ep), session(listen=ros_ep)
    try:
        yield modd, ros, modd_ep, ros_ep
    finally:
        modd.close()  # type: ignore[no-untyped-call]
        ros.close()  # type: ignore[no-untyped-call]


def decode_window(cdr: bytes) -> dict[str, Any]:
    """Hand-written CDR decoder (XCDR1 little endian, alignment from after the
    4-byte encapsulation header)."""
    assert cdr[:4] == b"\x00\x01\x00\x00", "CDR_LE encapsulation"
    body = cdr[4:]
    s0, n0, s1, n1 = struct.unpack_from("<iIiI", body, 0)
    (value,) = struct.unpack_from("<d", body, 16)  # offset 16: already 8-aligned
    (count, slen) = struct.unpack_from("<II", body, 24)
    end = 32 + slen
    text = body[32:end]
    assert text[-1:] == b"\x00", "CDR strings end with NUL"
    has_count = body[end]
    at = (end + 1 + 3) // 4 * 4  # the sequence's length: uint32, 4-aligned
    (n,) = struct.unpack_from("<I", body, at)
    at = (at + 4 + 7) // 8 * 8 if n else at + 4  # float64 items, 8-aligned
    samples = list(struct.unpack_from(f"<{n}d", body, at))
    assert len(body) == at + 8 * n, "nothing after the samples"
    return {
        "start_ns": s0 * 10**9 + n0,
        "end_ns": s1 * 10**9 + n1,
        "value": value,
        "count": count,
        "aggregation": text[:-1].decode(),
        "has_count": has_count,
        "samples": samples,
    }


def test_bridge_publishes_as_rmw_zenoh(
    networks: tuple[zenoh.Session, zenoh.Session, str, str],
) -> None:
    modd, ros, modd_ep, ros_ep = networks
    got: dict[str, list[tuple[bytes, bytes]]] = {}
    lock = threading.Lock()

    def on(sample: zenoh.Sample) -> None:
        att = sample.attachment.to_bytes() if sample.attachment is not None else b""
        with lock:
            got.setdefault(str(sample.key_expr), []).append((sample.payload.to_bytes(), att))

    data_sub = ros.declare_subscriber("0/**", on)
    tokens: list[str] = []
    withdrawn: list[str] = []

    def on_token(s: zenoh.Sample) -> None:
        (tokens if s.kind == zenoh.SampleKind.PUT else withdrawn).append(str(s.key_expr))

    live_sub = ros.liveliness().declare_subscriber("@ros2_lv/0/**", on_token)
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "modd.ros2.cli",
            "--modd-connect",
            modd_ep,
            "--ros-connect",
            ros_ep,
            "--drone",
            "usv",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    try:
        assert proc.stdout is not None
        assert "modd-ros2: node /modd_bridge" in proc.stdout.readline()
        time.sleep(1.0)  # the bridge's sessions are connected
        values = [
            DeliveredValue(
                "sub_3",
                "usv.accelerometer.accel_x",
                "AVERAGE",
                "0.25",
                "M",
                1,
                k,
                1_795_000_000_000_000_000 + k * 250_000_000,
                1_795_000_000_250_000_000 + k * 250_000_000,
                -0.1 * k,
                6,
                0,
            )
            for k in range(5)
        ] + [
            DeliveredValue(
                "sub_5",
                "usv.accelerometer.accel_z",
                "MIN",
                "0.25",
                "M",
                1,
                9,
                1_795_000_000_000_000_000,
                1_795_000_000_250_000_000,
                None,
                None,
                0,
            ),
            DeliveredValue(
                "sub_6",
                "usv.accelerometer.accel_z",
                "MAX",
                "0.25",
                "M",
                1,
                9,
                1_795_000_000_000_000_000,
                1_795_000_000_250_000_000,
                2.5,
                None,
                0,
            ),
            DeliveredValue(
                "sub_7",
                "usv.accelerometer.accel_z",
                "ALL",
                "0.25",
                "M",
                1,
                9,
                1_795_000_000_000_000_000,
                1_795_000_000_250_000_000,
                [1.5, -2.25, 3.0],
                3,
                0,
            ),
        ]
        # a backfilled (historical) copy of an older window, after the live ones
        late = replace(values[1], value=-7.5, backfilled=True)
        for v in [*values, late]:
            modd.put(f"modd/usv/sub/{v.subscriber}", v.to_json())
            time.sleep(0.02)
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline and sum(len(v) for v in got.values()) < 17:
            time.sleep(0.05)
        # liveliness tokens are also answered to a query (late joiners: ros2 topic list)
        queried = [
            str(r.ok.key_expr)
            for r in ros.liveliness().get("@ros2_lv/0/**", timeout=3)
            if r.ok is not None
        ]
    finally:
        proc.terminate()
        proc.wait(10)
        if proc.stdout is not None:
            proc.stdout.close()
        time.sleep(0.3)
        data_sub.undeclare()  # type: ignore[no-untyped-call]
        live_sub.undeclare()  # type: ignore[no-untyped-call]

    window_key = f"0/usv/sub_3/modd_msgs::msg::dds_::Window_/{WINDOW_HASH}"
    float_key = f"0/usv/sub_3/value/std_msgs::msg::dds_::Float64_/{PUBLISHED_FLOAT64}"
    assert set(got) >= {window_key, float_key}
    windows = [decode_window(p) for p, _ in got[window_key]]
    assert windows == [
        {
            "start_ns": v.start_ns,
            "end_ns": v.end_ns,
            "value": v.value,
            "count": 6,
            "aggregation": "AVERAGE",
            "has_count": 1,
            "samples": [],
        }
        for v in values[:5]
    ]
    # the historical window: on its own topic, never on the live ones (whose last it would be)
    back_key = f"0/usv/sub_3/backfilled/modd_msgs::msg::dds_::Window_/{WINDOW_HASH}"
    assert [decode_window(p) for p, _ in got[back_key]] == [
        {
            "start_ns": late.start_ns,
            "end_ns": late.end_ns,
            "value": -7.5,
            "count": 6,
            "aggregation": "AVERAGE",
            "has_count": 1,
            "samples": [],
        }
    ]
    floats = [struct.unpack("<d", p[4:])[0] for p, _ in got[float_key]]
    assert [p[:4] for p, _ in got[float_key]] == [b"\x00\x01\x00\x00"] * 5
    assert floats == [v.value for v in values[:5]]
    empty = decode_window(got[f"0/usv/sub_5/modd_msgs::msg::dds_::Window_/{WINDOW_HASH}"][0][0])
    assert math.isnan(empty["value"]) and (empty["count"], empty["has_count"]) == (0, 1)
    # a MIN/MAX/LAST window: the drone does not say how many samples; the type says so
    most = decode_window(got[f"0/usv/sub_6/modd_msgs::msg::dds_::Window_/{WINDOW_HASH}"][0][0])
    assert (most["value"], most["count"], most["has_count"]) == (2.5, 0, 0)
    # an ALL window carries its samples
    every = decode_window(got[f"0/usv/sub_7/modd_msgs::msg::dds_::Window_/{WINDOW_HASH}"][0][0])
    assert math.isnan(every["value"])
    assert (every["samples"], every["count"], every["has_count"]) == ([1.5, -2.25, 3.0], 3, 1)

    # attachment: sequence number from 1, source timestamp now, GID of 16 bytes
    atts = [
        ze.z_deserialize(tuple[ze.Int64, ze.Int64, bytes], zenoh.ZBytes(a))
        for _, a in got[window_key]
    ]
    assert all(len(a) == 33 for _, a in got[window_key])
    assert [a[0] for a in atts] == [1, 2, 3, 4, 5]
    assert all(abs(a[1] - time.time_ns()) < 60 * 10**9 for a in atts)
    gids = {a[2] for a in atts}
    assert len(gids) == 1 and len(next(iter(gids))) == 16

    # liveliness: node NN and publishers MP, parts as in liveliness_utils.cpp
    assert sorted(queried) == sorted(tokens)
    assert sorted(withdrawn) == sorted(tokens), "tokens go when the bridge stops"
    node = [t for t in tokens if "/NN/" in t]
    assert len(node) == 1
    _admin, domain, zid, nid, eid, kind, enclave, ns, name = node[0].split("/")
    assert (domain, nid, eid, kind, enclave, ns, name) == (
        "0",
        "0",
        "0",
        "NN",
        "%",
        "%",
        "modd_bridge",
    )
    pubs = {t.split("/")[9]: t.split("/") for t in tokens if "/MP/" in t}
    w = pubs["%usv%sub_3"]
    assert len(w) == 13 and w[2] == zid and w[5] == "MP"
    assert w[10:13] == ["modd_msgs::msg::dds_::Window_", WINDOW_HASH, "::,:,:,:,,"]
    f = pubs["%usv%sub_3%value"]
    assert f[10:12] == ["std_msgs::msg::dds_::Float64_", PUBLISHED_FLOAT64]
    # the historical topic is a Window publisher of its own (ros2 topic list shows it)
    assert pubs["%usv%sub_3%backfilled"][10:12] == ["modd_msgs::msg::dds_::Window_", WINDOW_HASH]
    assert rmw.gid("/".join(w)) in gids  # the GID is the publisher's own
    assert len({p[4] for p in pubs.values()}) == len(pubs)  # one entity id each
