"""Quantised-value vectors (declared resolution: docs/protocol.md, "Quantised
values"), written to quantised.json by generate.py with the Python codec.

Each unit is the values of consecutive slots as one DATA datagram carries them
(one chain of steps per stream, starting empty): both codecs decode every unit
on its own to the listed numbers (the steps times the resolution, exactly) and
encode those numbers back to the same bytes."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from modd.link import codec
from modd.link.frames import Aggregation, Value, ValueKind, ValueType, value_kind

F32, F64 = ValueType.FLOAT32, ValueType.FLOAT64
AVG, MIN, MAX, ALL = Aggregation.AVERAGE, Aggregation.MIN, Aggregation.MAX, Aggregation.ALL
S1 = [
    value_kind(F32, AVG, 0.01),
    value_kind(F32, AVG, 0.01),
    value_kind(F32, MIN, 0.01),
    value_kind(F32, MAX, 0.01),
]


def _kind_json(k: ValueKind, vtype: ValueType) -> dict[str, Any]:
    return {
        "type": vtype.label,
        "aggregation": k.aggregation.name,
        **({"resolution": k.resolution} if k.resolution is not None else {}),
    }


def _unit(
    name: str,
    meaning: str,
    kinds: list[ValueKind],
    types: list[ValueType],
    slots: list[tuple[list[int], list[Value]]],
) -> dict[str, Any]:
    chain: dict[int, int] = {}
    wire = b"".join(
        codec.encode_slot_values(vals, [kinds[s] for s in ids], ids, chain) for ids, vals in slots
    )
    r = codec.Reader(wire)
    back: dict[int, int] = {}
    out = []
    for ids, vals in slots:
        got = [
            codec._get_value(r, kinds[s], back, s) if v.present else Value()
            for s, v in zip(ids, vals, strict=True)
        ]
        out.append(
            {
                "streams": ids,
                "values": [
                    {
                        "present": g.present,
                        "number": g.number,
                        "count": g.count,
                        "samples": g.samples,
                        "sent": v.samples or v.number,
                    }
                    for g, v in zip(got, vals, strict=True)
                ],
            }
        )
    r.end()
    return {
        "name": name,
        "meaning": meaning,
        "hex": wire.hex(),
        "kinds": [_kind_json(k, t) for k, t in zip(kinds, types, strict=True)],
        "slots": out,
    }


def _s1(i: int) -> list[Value]:
    return [
        Value(True, 0.5 + 0.013 * i, 0, 6),
        Value(True, -1.25 - 0.07 * i, 0, 7),
        Value(True, 9.75 - 0.9 * i),
        Value(True, 10.5 + 0.004 * i),
    ]


def write(here: Path) -> None:
    s1_types = [F32] * 4
    units = [
        _unit(
            "scenario1_five_slots",
            "scenario 1, 5 slots of 0.25 s at 0.01 m/s2: the first "
            "slot absolute, then deltas of a few steps (1 B each)",
            S1,
            s1_types,
            [([0, 1, 2, 3], _s1(i)) for i in range(5)],
        ),
        _unit(
            "scenario1_absent_and_escape",
            "stream 1 absent in slot 1 (its next value is a "
            "delta against slot 0's), 1e30 on MIN z escapes (code 0, f64le), the next MIN "
            "z is a delta against the last quantised one",
            S1,
            s1_types,
            [
                ([0, 1, 2, 3], _s1(0)),
                (
                    [0, 1, 2, 3],
                    [Value(True, 0.52, 0, 6), Value(), Value(True, 1e30), Value(True, 10.0)],
                ),
                ([0, 1, 2, 3], _s1(2)),
            ],
        ),
        _unit(
            "mixed_periods_and_all",
            "streams 0 (f64 ALL, 0.5) and 1 (f32 AVERAGE, 0.01) "
            "at 0.25 s, stream 2 (f64 LAST, 0.001) at 0.5 s: ALL's samples chain one after "
            "the other, across slots too",
            [
                value_kind(F64, ALL, 0.5),
                value_kind(F32, AVG, 0.01),
                value_kind(F64, Aggregation.LAST, 0.001),
            ],
            [F64, F32, F64],
            [
                ([0, 1], [Value(True, 0, 0, 3, [1.0, 1.5, 3.2]), Value(True, 20.0, 0, 6)]),
                (
                    [0, 1, 2],
                    [
                        Value(True, 0, 0, 2, [3.0, -700.25]),
                        Value(True, 19.994, 0, 6),
                        Value(True, 4.0005),
                    ],
                ),
            ],
        ),
    ]
    (here / "quantised.json").write_text(
        json.dumps(
            {
                "name": "quantised",
                "meaning": "DATA datagram values of streams with a declared "
                "resolution: each unit decodes on its own (a lost datagram corrupts no other)",
                "units": units,
            },
            indent=1,
        )
        + "\n"
    )
