"""The dataset's archive reader (modd.dataset.mcapread) against the official ``mcap``
reader: every message of every topic, values and both times, through its fast path
(a chunk of archive records only) and its record loop (a chunk with channels, a
record not in the compact form, a header whose bytes spell the record's prefix)."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap.writer import CompressionType, Writer
from modd.dataset.mcapread import FileState, _fast, read_file

VECTORS = Path(__file__).resolve().parents[3] / "contracts" / "vectors"
TYPES = {"b.s.f": "float32", "b.s.d": "float64", "b.s.i": "int", "b.s.w": "bool"}
#: A log time whose last four bytes, with the publish time's first five, spell the
#: prefix ``{"value":`` (little-endian): a chance match the reader must not trust.
TRAP_LOG = int.from_bytes(b'\x00\x00\x00\x00{"va', "little")
TRAP_PUB = int.from_bytes(b'lue":\x00\x00\x00', "little")


def _text(value: Any) -> bytes:
    if isinstance(value, bool):
        return b"true" if value else b"false"
    if isinstance(value, float) and not math.isfinite(value):
        return b"nan" if value != value else (b"inf" if value > 0 else b"-inf")
    return repr(value).encode()


def _messages(rng: np.random.Generator, n: int) -> list[tuple[str, int, int, bytes]]:
    out = []
    for k in range(n):
        topic = str(rng.choice(list(TYPES)))
        kind = TYPES[topic]
        if kind == "bool":
            value: Any = bool(rng.random() < 0.5)
        elif kind == "int":
            value = int(rng.integers(-(2**40), 2**40))
        else:
            value = float(rng.choice([rng.normal(0, 1e3), math.nan, math.inf, -math.inf, 0.0]))
            value = float(np.float32(value)) if kind == "float32" else value
        t = 1_790_000_000 * 10**9 + k * 1_000_000
        out.append(
            (topic, t, t + int(rng.integers(-(10**9), 10**9)), b'{"value":' + _text(value) + b"}")
        )
    return out


def _write(path: Path, messages: list[tuple[str, int, int, bytes]], chunk_size: int) -> None:
    """The messages by the official writer; every channel registered first, as the
    contract's vectors give them (the first chunk: channels, then messages)."""
    vectors = json.loads((VECTORS / "archive_record.json").read_text())["channels"]
    by_type = {c["type"]: c for c in vectors}
    with path.open("wb") as f:
        w = Writer(f, chunk_size=chunk_size, compression=CompressionType.ZSTD)
        w.start(profile="", library="test")
        ids = {}
        for topic, kind in TYPES.items():
            c = by_type[kind]
            schema = (c["schema_name"], c["schema_encoding"], c["schema_data"].encode())
            ids[topic] = w.register_channel(
                topic, c["message_encoding"], w.register_schema(*schema), c["metadata"]
            )
        for topic, t, pub, data in messages:
            w.add_message(ids[topic], log_time=t, data=data, publish_time=pub)
        w.finish()  # type: ignore[no-untyped-call]


def _ours(path: Path) -> dict[str, list[tuple[int, int, float]]]:
    out: dict[str, list[tuple[int, int, float]]] = {}
    for b in read_file(path, FileState(path)):
        assert b.publish_ns is not None
        rows = zip(b.time_ns.tolist(), b.publish_ns.tolist(), b.value.tolist(), strict=True)
        out.setdefault(b.topic, []).extend(rows)
    return out


def _official(path: Path) -> dict[str, list[tuple[int, int, float]]]:
    out: dict[str, list[tuple[int, int, float]]] = {}
    with path.open("rb") as f:
        for _s, ch, m in make_reader(f).iter_messages(log_time_order=False):
            text = m.data.decode()
            value = json.loads(
                text.replace("-inf", "-Infinity").replace("inf", "Infinity").replace("nan", "NaN")
            )["value"]
            out.setdefault(ch.topic, []).append((m.log_time, m.publish_time, float(value)))
    return out


def _same(a: dict[str, list[tuple[int, int, float]]], b: dict[str, Any]) -> None:
    assert a.keys() == b.keys()
    for topic in a:
        x, y = np.array(a[topic], dtype=object), np.array(b[topic], dtype=object)
        assert x[:, :2].tolist() == y[:, :2].tolist(), topic
        vx, vy = x[:, 2].astype(float), y[:, 2].astype(float)
        assert np.array_equal(vx, vy, equal_nan=True), topic


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("chunk_size", [64, 1024, 1 << 20])
def test_every_message_is_the_official_readers(tmp_path: Path, seed: int, chunk_size: int) -> None:
    path = tmp_path / "a.mcap"
    _write(path, _messages(np.random.default_rng(seed), 3000), chunk_size)
    _same(_ours(path), _official(path))


def test_odd_records_are_read_by_the_record_loop(tmp_path: Path) -> None:
    rng = np.random.default_rng(7)
    messages = _messages(rng, 2000)
    topic, t, _pub, _data = messages[1500]
    messages[1500] = (
        topic,
        TRAP_LOG,
        TRAP_PUB,
        b'{"value":1}' if TYPES[topic] != "bool" else b'{"value":true}',
    )
    topic, t, pub, _data = messages[1700]
    messages[1700] = (
        topic,
        t,
        pub,
        b'{ "value" : 0 }' if TYPES[topic] != "bool" else b'{ "value" : false }',
    )
    path = tmp_path / "odd.mcap"
    _write(path, messages, 4096)  # the odd records in chunks of messages only
    _same(_ours(path), _official(path))


def test_the_fast_path_refuses_a_chunk_it_cannot_tile() -> None:
    head = bytes([0x05]) + (22 + 11).to_bytes(8, "little") + bytes(22)
    record = head + b'{"value":1}'
    assert _fast(record * 3) is not None
    assert _fast(record * 3 + b"\x00") is None  # a byte more than the records
    trap = bytes([0x05]) + (22 + 11).to_bytes(8, "little") + bytes(6)
    trap += TRAP_LOG.to_bytes(8, "little") + TRAP_PUB.to_bytes(8, "little") + b'{"value":1}'
    assert _fast(record + trap + record) is None  # the prefix met in a header
