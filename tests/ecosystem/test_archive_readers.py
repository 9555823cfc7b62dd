"""The PubBroker's MCAP files read by two independent readers — the Python
``mcap`` package and the TypeScript ``@mcap/core`` — with identical message
counts, for closed files, files cut by ``kill -9``, and those files after
``modd archive recover``; and ``modd archive info``."""

from __future__ import annotations

import argparse
import json
import signal
import time
from collections import Counter
from collections.abc import Iterator
from pathlib import Path

import pytest
from ecosystem_support import node_json
from mcap.reader import make_reader
from modd.archive.info import archive_info
from modd.archive.recover import recover
from modd.archive.scan import scan_file
from pubbroker_harness import BIN, PubBroker, run_load

TOPICS = [(f"usv.accelerometer.accel_{a}", "float32") for a in "xyz"]
NAMES = [t for t, _ in TOPICS]


@pytest.fixture(autouse=True)
def _pubbroker_built() -> None:
    """make test builds it: missing is a setup bug, not a skip."""
    if not BIN.exists():
        pytest.fail(f"{BIN} is missing: run make build")


ARCHIVE = {"flush_interval_ms": 200, "chunk_bytes": 4000, "rotate_bytes": 8000}


@pytest.fixture
def broker(tmp_path: Path) -> Iterator[PubBroker]:
    b = PubBroker(tmp_path, TOPICS, archive=ARCHIVE)
    b.start()
    try:
        yield b
    finally:
        b.stop(signal.SIGKILL)


def closed_archive(tmp_path: Path, **archive: object) -> tuple[list[Path], dict[str, int]]:
    b = PubBroker(tmp_path, TOPICS, archive={**ARCHIVE, **archive})
    b.start()
    try:
        load = run_load(f"unix:{b.unix_path}", NAMES, 200.0, 1.0)
    finally:
        assert b.stop() == 0
    files = sorted(b.archive_dir.glob("*.mcap"))
    assert len(files) >= 2, "rotate_bytes should have cut several files"
    return files, load.per_topic


def python_counts(path: Path) -> dict[str, int]:
    with open(path, "rb") as f:
        reader = make_reader(f)
        return dict(Counter(ch.topic for _s, ch, _m in reader.iter_messages()))


def scan_counts(path: Path) -> dict[str, int]:
    scan = scan_file(path)
    return dict(Counter(scan.channels[m.channel_id].topic for m in scan.messages))


def test_closed_files_read_the_same_front_to_back(tmp_path: Path) -> None:
    """Default archive settings (no MCAP Message Index records)."""
    files, published = closed_archive(tmp_path)
    ts = node_json("mcap_count.cjs", "--stream", *map(str, files))
    total: Counter[str] = Counter()
    for f in files:
        py = python_counts(f)
        assert ts[str(f)]["error"] is None and ts[str(f)]["complete"]
        assert ts[str(f)]["counts"] == py, f.name
        total.update(py)
    assert dict(total) == published


def test_closed_files_with_message_indexes_read_the_same_indexed(tmp_path: Path) -> None:
    files, published = closed_archive(tmp_path, message_index=True)
    ts = node_json("mcap_count.cjs", *map(str, files))
    total: Counter[str] = Counter()
    for f in files:
        py = python_counts(f)
        assert ts[str(f)]["error"] is None
        assert ts[str(f)]["counts"] == py, f.name
        total.update(py)
    assert dict(total) == published


def test_default_files_open_in_the_indexed_typescript_reader(tmp_path: Path) -> None:
    """@mcap/core's indexed reader (the one Foxglove and Lichtblick open files with)
    refuses chunk indexes without message indexes: the default writes them."""
    files, published = closed_archive(tmp_path)
    ts = node_json("mcap_count.cjs", *map(str, files))
    total: Counter[str] = Counter()
    for f in files:
        assert ts[str(f)]["error"] is None, f.name
        assert ts[str(f)]["counts"] == python_counts(f)
        total.update(ts[str(f)]["counts"])
    assert dict(total) == published


def test_files_without_message_indexes_are_refused_by_the_indexed_reader(tmp_path: Path) -> None:
    """Why the default is on: the same files without message indexes."""
    files, _ = closed_archive(tmp_path, message_index=False)
    ts = node_json("mcap_count.cjs", str(files[0]))
    assert "chunk index without message indexes" in str(ts[str(files[0])]["error"])


def test_recover_makes_unindexed_files_open_in_the_indexed_reader(tmp_path: Path) -> None:
    files, _ = closed_archive(tmp_path, message_index=False)
    out = tmp_path / "indexed.mcap"
    recover(files[0], out)
    ts = node_json("mcap_count.cjs", str(out))
    assert ts[str(out)]["error"] is None
    assert ts[str(out)]["counts"] == python_counts(files[0]) == python_counts(out)


def test_a_file_cut_by_kill9_reads_the_same_and_recovers(broker: PubBroker, tmp_path: Path) -> None:
    load = run_load(f"unix:{broker.unix_path}", NAMES, 200.0, 1.0)
    time.sleep(0.6)  # > flush interval: everything handed over has been written
    broker.stop(signal.SIGKILL)
    files = sorted(broker.archive_dir.glob("*.mcap"))
    last = files[-1]
    with open(last, "rb") as cut, pytest.raises(Exception):  # noqa: B017 - any reader error
        list(make_reader(cut).iter_messages())
    # front to back: both readers see the same messages in the cut file
    ts_stream = node_json("mcap_count.cjs", "--stream", *map(str, files))
    total: Counter[str] = Counter()
    for f in files:
        py = scan_counts(f)
        assert ts_stream[str(f)]["counts"] == py, f.name
        total.update(py)
    assert dict(total) == load.per_topic  # nothing handed over was lost
    assert not ts_stream[str(last)]["complete"]

    # recovered: indexed readers open it, with the same counts
    out = tmp_path / "recovered.mcap"
    r = recover(last, out)
    assert not r.was_complete and r.messages == sum(scan_counts(last).values())
    ts = node_json("mcap_count.cjs", str(out))
    assert ts[str(out)]["error"] is None
    assert ts[str(out)]["counts"] == python_counts(out) == scan_counts(last)
    with open(out, "rb") as recovered:
        summary = make_reader(recovered).get_summary()
    assert summary is not None and summary.statistics is not None
    assert summary.statistics.message_count == r.messages
    assert summary.chunk_indexes


def modd_archive(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    """``modd archive ...`` through the same ``register`` the ``modd`` entry point loads
    (in-process: the full ``modd`` start-up imports every plugin)."""
    from modd.archive.cli import register

    parser = argparse.ArgumentParser(prog="modd")
    register(parser.add_subparsers(dest="command", required=True))
    code = parser.parse_args(["archive", *argv]).func(parser.parse_args(["archive", *argv]))
    out = capsys.readouterr()
    return code, out.out, out.err


def test_archive_is_a_modd_command() -> None:
    from importlib.metadata import entry_points

    eps = {e.name: e.value for e in entry_points(group="modd.commands")}
    assert eps.get("archive") == "modd.archive.cli:register"


def test_modd_archive_recover_and_info_commands(
    broker: PubBroker, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    run_load(f"unix:{broker.unix_path}", NAMES, 100.0, 0.5)
    time.sleep(0.4)
    broker.stop(signal.SIGKILL)
    last = sorted(broker.archive_dir.glob("*.mcap"))[-1]
    before = scan_counts(last)
    code, out, _ = modd_archive(capsys, "info", str(last), "--json")
    doc = json.loads(out)
    assert code == 0 and doc["complete"] is False
    assert {t["topic"]: t["count"] for t in doc["topics"] if t["count"]} == before
    code, out, _ = modd_archive(capsys, "recover", str(last), "--in-place")
    assert code == 0 and f"{sum(before.values())} messages" in out
    assert python_counts(last) == before
    code, text, _ = modd_archive(capsys, "info", str(last))
    assert code == 0 and "closed" in text and "NOT CLOSED" not in text
    code, _, err = modd_archive(capsys, "info", str(tmp_path / "none.mcap"))
    assert code == 2 and "no such file" in err
    (tmp_path / "junk.mcap").write_bytes(b"not an mcap file")
    code, _, err = modd_archive(capsys, "recover", str(tmp_path / "junk.mcap"))
    assert code == 1 and "not an MCAP file" in err


def test_info_reports_gaps(tmp_path: Path) -> None:
    from mcap.writer import Writer

    path = tmp_path / "gap.mcap"
    with open(path, "wb") as f:
        w = Writer(f)
        w.start()
        sid = w.register_schema("v", "jsonschema", b"{}")
        cid = w.register_channel("t", "json", sid)
        for t in [0, 10, 20, 30, 1000, 1010]:
            w.add_message(cid, t * 1_000_000, b'{"value":1}', t * 1_000_000)
        w.finish()  # type: ignore[no-untyped-call]
    info = archive_info(path)
    assert info.complete and info.topics["t"].count == 6
    assert info.topics["t"].gaps == [(30_000_000, 1_000_000_000)]
    assert info.start_ns == 0 and info.end_ns == 1_010_000_000
