"""The base-station record (record.py) read back by the official MCAP reader:
one file per mission, one channel per subscriber key, each message the
delivered payload as given, stamped with its window's end."""

from __future__ import annotations

import json
from pathlib import Path

from mcap.reader import make_reader
from modd.subbroker.record import BaseRecord

EPOCH = 1_763_700_000_000_000_000


def _value(sub: str, end_ns: int, value: float) -> bytes:
    return json.dumps(
        {
            "subscriber": sub,
            "end_ns": end_ns,
            "start_ns": end_ns - 10**9,
            "value": value,
            "delivered_ns": end_ns + 5,
        }
    ).encode()


def _read(path: Path) -> list[tuple[str, str, int, int, bytes]]:
    with path.open("rb") as f:
        return [
            (s.name if s else "", c.topic, m.log_time, m.publish_time, m.data)
            for s, c, m in make_reader(f).iter_messages()
        ]


def test_each_mission_is_one_file_of_what_was_delivered(tmp_path: Path) -> None:
    rec = BaseRecord(tmp_path, "usv")
    rec.begin("scenario 1", EPOCH)  # the mission's name made safe for a path
    first = rec.path
    sent = [("sub_a", EPOCH + k * 10**9, float(k)) for k in range(1, 4)]
    sent += [("sub_b", EPOCH + 2 * 10**9, -1.5)]
    for sub, end, v in sent:
        rec.put(sub, _value(sub, end, v))
    rec.begin("scenario 1", EPOCH + 10**9)  # the same mission: the same file
    assert rec.path == first
    rec.begin("scenario 2", EPOCH)  # another: a new file beside it
    rec.put("sub_a", _value("sub_a", EPOCH + 10**9, 9.0))
    rec.close()
    assert first is not None and rec.path is not None and rec.path != first
    assert first.parent == tmp_path / "usv" and first.name == "scenario_1-20251121T044000Z.mcap"
    assert rec.path.name == "scenario_2-20251121T044000Z.mcap"
    got = _read(first)
    recorded = [(topic, log, pub, json.loads(data)["value"]) for _, topic, log, pub, data in got]
    # the reader gives them in time order
    assert sorted(recorded) == sorted(
        (f"modd/usv/sub/{sub}", end, end + 5, v) for sub, end, v in sent
    )
    assert {schema for schema, *_ in got} == {"modd.DeliveredValue"}
    assert [json.loads(d)["value"] for *_, d in _read(rec.path)] == [9.0]
    assert rec.messages == 5 and rec.dropped == 0


def test_a_mission_begun_again_in_the_same_second_gets_its_own_file(tmp_path: Path) -> None:
    paths = []
    for _ in range(3):
        rec = BaseRecord(tmp_path, "usv")
        rec.begin("m", EPOCH)
        rec.put("s", _value("s", EPOCH + 1, 1.0))
        rec.close()
        paths.append(rec.path)
    assert [p.name for p in paths if p] == [
        "m-20251121T044000Z.mcap",
        "m-20251121T044000Z-1.mcap",
        "m-20251121T044000Z-2.mcap",
    ]
    assert all(len(_read(p)) == 1 for p in paths if p)
