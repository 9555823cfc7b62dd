"""Every frame type that can travel in a link frame (the link's MsgType, the backfill
types, and the datagram group's control frame types such as NACK) has a code of its
own: a CONTROL datagram's frames are told apart by that byte alone (a new frame once
took NACK's 0x09, and the PubBroker read it as a NACK)."""

from __future__ import annotations

import json
from pathlib import Path

WIRE = Path(__file__).resolve().parents[1] / "src" / "modd_contracts" / "wire.json"


def _codes() -> list[tuple[str, int]]:
    groups = {g["name"]: g for g in json.loads(WIRE.read_text())["groups"]}
    out = []
    for group, enum in (("link", "MsgType"), ("backfill", "BackfillType")):
        for e in groups[group]["enums"]:
            if e["name"] == enum:
                out += [(f"{enum}.{v['name']}", int(str(v["value"]), 0)) for v in e["values"]]
    for c in groups["datagrams"]["constants"]:
        if str(c.get("doc", "")).startswith("Control frame type"):
            out.append((c["name"], int(str(c["value"]), 0)))
    return out


def test_frame_type_codes_are_distinct() -> None:
    codes = _codes()
    assert {"MsgType.ONBOARD", "NACK", "BackfillType.REQUEST"} <= {n for n, _ in codes}
    seen: dict[int, str] = {}
    clashes = [(seen.setdefault(v, n), n) for n, v in codes if seen.setdefault(v, n) != n]
    assert not clashes, clashes
