"""State files never stop the base station (modd.subbroker.kept, record_file): a
structure-aware fuzz of ``windows.json``, ``deployed.json`` and ``dynamic.json``:
a good record mutated field by field (wrong types, huge numbers, non-finite
numbers, deep nesting, 10^6 entries, garbage bytes). Each is read within a time
bound, never raises, and is either taken or set aside with one message naming the
file; a good record is always taken."""

from __future__ import annotations

import json
import logging
import time
from fractions import Fraction
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from modd.subbroker.backfill import BackfillManager
from modd.subbroker.kept import StateDir
from modd.subbroker.record_file import read_record
from modd.subbroker.window_record import Due, Epoch, WindowRecord
from modd_plan.streams import StreamKey

S = 1_000_000_000
T0 = 1_700_000_000 * S
FAST = StreamKey("usv.a.x", "MIN", Fraction(1, 4))
SLOW = StreamKey("usv.a.x", "MIN", Fraction(2))
BOUND_S = 2.0  # reading any one file; the SubBroker's start must stay within 5 s


def good_record() -> dict[str, Any]:
    rec = WindowRecord()
    rec.begin(Epoch("m", 1, T0, [Due("sub", SLOW, FAST, "m", "float32")]))
    rec.add_received(FAST, T0, T0 + 10 * S)
    rec.add_derived(SLOW, T0, T0 + 10 * S)
    rec.add_filled("sub", SLOW, T0 + 20 * S, T0 + 22 * S)
    doc: dict[str, Any] = json.loads(json.dumps(rec.to_json()))
    return doc


NASTY: list[Any] = [
    None,
    True,
    -1,
    1 << 70,
    1e400,
    float("nan"),
    "",
    "x" * 5000,
    [],
    {},
    [[[[[]]]]],
    {"a": 1},
    "usv.a.x/MIN/0",
    "usv.a.x/NOPE/1",
    "usv.a.x/MIN/1e-400",
    "usv.a.x/MIN/1e400",
]


def paths(doc: Any, at: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    """Every place in ``doc`` a value could be replaced."""
    out = [at]
    if isinstance(doc, dict):
        for k, v in doc.items():
            out += paths(v, (*at, k))
    elif isinstance(doc, list):
        for i, v in enumerate(doc):
            out += paths(v, (*at, i))
    return out


def replaced(doc: Any, at: tuple[Any, ...], value: Any) -> Any:
    if not at:
        return value
    copy = json.loads(json.dumps(doc))
    node = copy
    for k in at[:-1]:
        node = node[k]
    node[at[-1]] = value
    return copy


def read_in_time(tmp: Path, name: str, raw: bytes) -> tuple[Any, StateDir, float]:
    (tmp / name).write_bytes(raw)
    state = StateDir(tmp)
    began = time.monotonic()
    if name == "windows.json":
        got: Any = BackfillManager(lambda _f: None, list, state).record
    elif name == "deployed.json":
        got = state.load_deployment()
    else:
        got = state.load_dynamic()
    return got, state, time.monotonic() - began


def check_taken_or_set_aside(tmp: Path, name: str, state: StateDir, took: float) -> None:
    assert took < BOUND_S, took
    left = (tmp / name).exists()
    aside = list(tmp.glob(f"{name}.bad-*"))
    assert left != bool(aside), (left, aside)  # taken as it is, or set aside (once)
    if aside:
        assert state.set_aside_files and state.set_aside_files[-1]["file"] == str(tmp / name)
        for f in aside:
            f.unlink()


GOOD = good_record()
PLACES = paths(GOOD)


@settings(
    max_examples=300, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(place=st.sampled_from(PLACES), value=st.sampled_from(NASTY))
def test_a_window_record_mutated_anywhere_is_read_or_set_aside(
    tmp_path: Path, place: tuple[Any, ...], value: Any
) -> None:
    doc = replaced(GOOD, place, value)
    raw = json.dumps(doc, allow_nan=True).encode()
    rec, state, took = read_in_time(tmp_path, "windows.json", raw)
    assert isinstance(rec, WindowRecord)
    check_taken_or_set_aside(tmp_path, "windows.json", state, took)
    rec.gaps("sub", T0, T0 + 30 * S)  # whatever was taken is usable


@pytest.mark.parametrize(
    "what,raw",
    [
        ("received is a list", json.dumps({**GOOD, "received": []}).encode()),
        ("1e400", json.dumps(GOOD).replace(str(T0), "1e400", 1).encode()),
        ("a 10,000-digit number", json.dumps(GOOD).replace(str(T0), "9" * 10_000, 1).encode()),
        ("nested 100,000 deep", b"[" * 100_000 + b"]" * 100_000),
        (
            "nested 60 deep in a field",
            json.dumps({**GOOD, "filled": [[[[[[[[]]]]]]]] * 8}).encode(),
        ),
        ("garbage bytes", bytes(range(256)) * 64),
        ("not UTF-8", b'{"epochs": "\xff\xfe"}'),
        ("empty", b""),
        ("NaN", b"NaN"),
    ],
)
def test_named_damage_is_set_aside(
    tmp_path: Path, what: str, raw: bytes, caplog: pytest.LogCaptureFixture
) -> None:
    with caplog.at_level(logging.ERROR, logger="modd.subbroker"):
        rec, state, took = read_in_time(tmp_path, "windows.json", raw)
    assert rec.epochs == [] and took < BOUND_S, (what, took)
    assert "windows.json" in caplog.text and "set aside as windows.json.bad-" in caplog.text
    check_taken_or_set_aside(tmp_path, "windows.json", state, took)


def test_a_million_recorded_configs_are_read_in_bounded_time(tmp_path: Path) -> None:
    """10^6 epochs: the file is past the size bound (set aside); 5·10^4 small ones within
    it: the newest 256 are taken."""
    due = json.dumps([["sub", SLOW.key, FAST.key, "m", "float32"]])
    item = '{"mission":"m","config_id":1,"due":%s,"epoch_ns":%d}'
    many = ",".join(item % (due, T0 + i) for i in range(1_000_000))
    raw = ('{"epochs":[' + many + '],"received":{},"filled":[]}').encode()
    rec, state, took = read_in_time(tmp_path, "windows.json", raw)
    assert rec.epochs == [] and took < BOUND_S, took
    check_taken_or_set_aside(tmp_path, "windows.json", state, took)
    fewer = ",".join(item % ("[]", T0 + i) for i in range(50_000))
    raw = ('{"epochs":[' + fewer + '],"received":{},"filled":[]}').encode()
    rec, state, took = read_in_time(tmp_path, "windows.json", raw)
    assert len(rec.epochs) == 256 and rec.epochs[-1].epoch_ns == T0 + 49_999, len(rec.epochs)
    assert took < BOUND_S, took
    check_taken_or_set_aside(tmp_path, "windows.json", state, took)


def test_a_good_record_is_taken_and_a_kept_record_stays_within_the_reader_bounds(
    tmp_path: Path,
) -> None:
    rec, state, took = read_in_time(tmp_path, "windows.json", json.dumps(GOOD).encode())
    assert json.loads(json.dumps(rec.to_json())) == GOOD and not state.set_aside_files
    big = WindowRecord()
    for i in range(20_000):  # a hole every other window: more intervals than kept
        big.add_received(FAST, T0 + 2 * i * S, T0 + (2 * i + 1) * S)
    back = read_record(json.loads(json.dumps(big.to_json())))
    assert len(back.received[FAST].spans) == 1024
    assert back.received_until() == big.received_until()


@pytest.mark.parametrize(
    "name,doc",
    [
        ("deployed.json", [1, 2]),
        ("deployed.json", "[" * 10_000),
        ("dynamic.json", {"subscriptions": {"a": 1}}),
        ("dynamic.json", 1e400),
    ],
)
def test_other_state_files_are_read_or_set_aside(tmp_path: Path, name: str, doc: Any) -> None:
    raw = doc.encode() if isinstance(doc, str) else json.dumps(doc).encode()
    got, state, took = read_in_time(tmp_path, name, raw)
    assert got in (None, [])
    check_taken_or_set_aside(tmp_path, name, state, took)
