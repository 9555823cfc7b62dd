"""STATUS as the SubBroker reads it (modd.link.status_read): every counter and health
field range-checked, a bad one logged and left out, and nothing in a STATUS a reason to
drop the link (docs/protocol.md, "Instruments' health")."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st
from modd.link import codec
from modd.link.frames import SensorHealth, Status
from modd.link.status_read import checked_counters, checked_sensors, read_status
from modd_contracts.link_wire_gen import MAX_HEALTH_COUNT, MAX_LAST_VALUE_MS

BIG = (1 << 53, 1 << 63, (1 << 64) - 1)


def _body(status: Status) -> bytes:
    frame = codec.split_frame(codec.encode(status))
    assert frame is not None
    return frame.body


def _raw_status(counters: list[int], sensors: list[tuple[bytes, list[int]]]) -> bytes:
    out = codec.varint(len(counters)) + b"".join(codec.varint(c) for c in counters)
    out += codec.varint(len(sensors))
    for name, fields in sensors:
        out += codec.varint(len(name)) + name + codec.varint(len(fields))
        out += b"".join(codec.varint(f) for f in fields)
    return out


def test_a_good_status_reads_as_the_codec_reads_it() -> None:
    st_ = Status((1, 2, 3), (SensorHealth("ctd", (1, 5, 0, 0, 1_764_892_800_000)),))
    got, problems = read_status(_body(st_))
    assert (got, problems) == (st_, [])
    assert checked_sensors(got.sensors) == ({"ctd": st_.sensors[0].as_dict()}, [])


def test_a_forged_name_and_huge_numbers_never_reach_the_status() -> None:
    body = _raw_status(
        [7, 1 << 63, 9],
        [
            (b"\xff\xfegps", [1, 2]),  # not UTF-8
            (b"\x1b[2Jctd", [1, 2]),  # an ANSI escape
            (b"imu", [5, 1 << 53, 0, 0, 1 << 53]),  # state 5, 2^53 lines, last value in 2255
            (b"gnss", [1, 3, 0, 0, 1_764_892_800_000]),
        ],
    )
    status, problems = read_status(body)
    counters, bad_counters = checked_counters(status)
    sensors, bad_sensors = checked_sensors(status.sensors)
    assert counters == {"uptime_s": 7, "samples_archived": 9}
    assert sorted(sensors) == ["gnss", "imu"]
    assert sensors["imu"] == {"reconnects": 0, "lines_bad": 0}
    assert sensors["gnss"]["last_value_ms"] == 1_764_892_800_000
    assert len(problems) == 1 and "not UTF-8" in problems[0]
    assert len(bad_counters) == 1 and len(bad_sensors) == 4


def test_a_cut_status_keeps_what_reads_and_says_where() -> None:
    body = _raw_status([4, 5], [(b"ctd", [1, 2]), (b"gnss", [1, 3])])
    status, problems = read_status(body[:-3])
    assert status.counters == (4, 5)
    assert [s.name for s in status.sensors] == ["ctd"]
    assert problems and "truncated" in problems[0]
    status, problems = read_status(b"\xff")  # not even the counter count
    assert status == Status(())
    assert problems


@settings(max_examples=300, deadline=None)
@given(st.binary(max_size=400))
def test_any_bytes_read_without_raising_and_forward_only_values_in_range(body: bytes) -> None:
    status, _ = read_status(body)
    counters, _ = checked_counters(status)
    sensors, _ = checked_sensors(status.sensors)
    assert all(v <= MAX_HEALTH_COUNT for v in counters.values())
    for doc in sensors.values():
        assert all(v <= MAX_HEALTH_COUNT for v in doc.values())
        assert doc.get("state", 0) <= 2
        assert doc.get("last_value_ms", 0) <= MAX_LAST_VALUE_MS


@given(st.sampled_from(BIG))
def test_a_huge_counter_is_left_out_by_position(v: int) -> None:
    counters, problems = checked_counters(Status((1, v, 3)))
    assert counters == {"uptime_s": 1, "samples_archived": 3}
    assert problems
