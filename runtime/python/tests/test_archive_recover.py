"""``modd archive recover`` on crashed files with damaged bytes (issue 28,
docs/pubbroker.md): every chunk whose data checks is kept, wherever it lies,
the damaged regions are reported, and no input gives a traceback. Oracle:
tests/support/mcap_oracle.py (a minimal reader of the spec sharing no code
with modd.archive) chunk by chunk, and the official ``mcap`` reader on the
output."""

from __future__ import annotations

import argparse
import random
import struct
import sys
import zlib
from pathlib import Path

import pytest
import zstandard
from mcap.reader import make_reader
from modd.archive import cli
from modd.archive.recover import recover
from modd.archive.scan import scan_file

sys.path.insert(0, str(Path(__file__).resolve().parents[3] / "tests"))
from support import mcap_oracle as oracle  # type: ignore[import-not-found]  # noqa: E402


def official_count(path: Path) -> int:
    with open(path, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        assert summary is not None and summary.statistics is not None
        n = sum(1 for _ in reader.iter_messages())
        assert summary.statistics.message_count == n
        return n


def run_cli(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="modd")
    cli.register(parser.add_subparsers(dest="command"))
    args = parser.parse_args(argv)
    code: int = args.func(args)
    return code


@pytest.fixture(scope="module")
def crashed() -> tuple[bytes, list[oracle.Record]]:
    data = oracle.crashed_mcap(3000, per_chunk=40)
    return data, oracle.records(data)


def test_the_fixture_is_what_the_oracle_expects(
    crashed: tuple[bytes, list[oracle.Record]], tmp_path: Path
) -> None:
    data, layout = crashed
    assert sum(1 for op, _, _ in layout if op == oracle.CHUNK) == 75
    assert oracle.count_valid(data, layout) == 3000  # the last chunk whole, its index torn
    src = tmp_path / "clean.mcap"
    src.write_bytes(data)
    r = recover(src)
    assert r.messages == 3000 and r.chunks == 75
    assert [s.why for s in r.skipped] == ["a record longer than the rest of the file"]  # torn
    assert official_count(r.output) == 3000
    again = scan_file(r.output)  # what it wrote reads back closed, nothing skipped
    assert again.complete and not again.skipped and len(again.messages) == 3000


def test_each_of_25_single_byte_flips_keeps_every_chunk_whose_data_checks(
    crashed: tuple[bytes, list[oracle.Record]], tmp_path: Path
) -> None:
    data, layout = crashed
    everything = 3000
    for at, mask in oracle.flips(data, layout):
        damaged = oracle.flipped(data, at, mask)
        want = oracle.count_valid(damaged, layout)
        src = tmp_path / f"flip-{at}.mcap"
        src.write_bytes(damaged)
        r = recover(src)
        assert r.messages == want, (at, mask)
        assert official_count(r.output) == want, (at, mask)
        assert want >= everything - 40  # one flip costs one chunk at most
        if want < everything:
            assert r.skipped and r.skipped[0].offset <= at, (at, r.skipped)


def test_a_flip_the_pubbrokers_decoder_reads_past_keeps_its_chunk(
    crashed: tuple[bytes, list[oracle.Record]], tmp_path: Path
) -> None:
    """python-zstandard refuses the flip; the chunk's data is still whole (the
    system's libzstd reads past it and the CRC checks), as the PubBroker keeps
    it. The output is written anew, so the official reader reads it."""
    data, layout = crashed
    flip = oracle.read_past_flip(data, layout)
    assert flip is not None
    damaged = oracle.flipped(data, *flip)
    assert oracle.count_valid(damaged, layout) == 3000
    src = tmp_path / "read-past.mcap"
    src.write_bytes(damaged)
    r = recover(src)
    assert r.messages == 3000
    assert official_count(r.output) == 3000


def test_all_25_flips_in_one_file(
    crashed: tuple[bytes, list[oracle.Record]], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    data, layout = crashed
    damaged = data
    for at, mask in oracle.flips(data, layout):
        damaged = oracle.flipped(damaged, at, mask)
    want = oracle.count_valid(damaged, layout)
    src = tmp_path / "all.mcap"
    src.write_bytes(damaged)
    assert run_cli(["archive", "recover", str(src), "-o", str(tmp_path / "out.mcap")]) == 0
    out = capsys.readouterr().out
    assert f"{want} messages on 3 channels" in out
    assert official_count(tmp_path / "out.mcap") == want
    # every damaged chunk lies in a skipped region, and the report names each region
    r = recover(src, tmp_path / "again.mcap")
    bad = [
        at
        for op, at, size in layout
        if op == oracle.CHUNK and oracle.chunk_messages(damaged, at, size) is None
    ]
    assert len(bad) >= 10
    for at in bad:
        assert any(s.offset <= at < s.offset + s.length for s in r.skipped), at
    for s in r.skipped:
        assert f"offset {s.offset}, {s.length} bytes: " in out


def chunk_record(comp: bytes, usize: int, crc: int) -> bytes:
    body = struct.pack("<QQQI", 1, 2, usize, crc) + struct.pack("<I", 4) + b"zstd"
    head = struct.pack("<BQ", 6, len(body) + 8 + len(comp))
    return head + body + struct.pack("<Q", len(comp)) + comp
    return head + body + struct.pack("<Q", len(comp)) + comp


def test_a_zstd_bomb_and_crafted_sizes_are_skipped_without_a_traceback(
    crashed: tuple[bytes, list[oracle.Record]], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    data, layout = crashed
    first = next(at for op, at, _ in layout if op == oracle.CHUNK)
    zeros = bytes(64 << 20)
    bomb = zstandard.ZstdCompressor(level=1).compress(zeros)
    assert len(bomb) < 64 << 10
    crafted = [
        chunk_record(bomb, 1024, 0),  # decompresses far past its declared size
        chunk_record(bomb, 1 << 40, zlib.crc32(zeros)),  # a declared size never allocated
        chunk_record(bomb[:100], 64 << 20, 0),  # a frame cut short
        struct.pack("<BQ", 6, 1 << 62) + bytes(60),  # a record length past the end
    ]
    for i, bad in enumerate(crafted):
        src = tmp_path / f"crafted-{i}.mcap"
        src.write_bytes(data[:first] + bad + data[first:])
        assert run_cli(["archive", "recover", str(src)]) == 0, i
        out = capsys.readouterr().out
        assert f"offset {first}," in out and "3000 messages" in out, (i, out)


def test_no_input_gives_a_traceback(
    crashed: tuple[bytes, list[oracle.Record]], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Random damage of every kind (flips, cuts, inserted and deleted bytes,
    garbage): the command answers 0 with a report or 1 with a one-line error."""
    data, _ = crashed
    rng = random.Random(28)
    inputs = [
        b"",
        oracle.MAGIC,
        oracle.MAGIC + bytes(9),
        rng.randbytes(5000),
        oracle.MAGIC + rng.randbytes(5000),
    ]
    for _ in range(60):
        b = bytearray(data)
        for _ in range(rng.randint(1, 30)):
            at = rng.randrange(len(b))
            kind = rng.randrange(4)
            if kind == 0:
                b[at] ^= rng.randint(1, 255)
            elif kind == 1:
                b[at:at] = rng.randbytes(rng.randint(1, 50))
            elif kind == 2:
                del b[at : at + rng.randint(1, 50)]
            else:
                b[at : at + 8] = struct.pack("<Q", rng.getrandbits(64))
        inputs.append(bytes(b[: rng.randint(len(b) // 2, len(b))]))
    for i, b in enumerate(inputs):
        src = tmp_path / f"in-{i}.mcap"
        src.write_bytes(b)
        code = run_cli(["archive", "recover", str(src), "-o", str(tmp_path / f"out-{i}.mcap")])
        err = capsys.readouterr().err
        assert code in (0, 1), i
        if code == 0:
            official_count(tmp_path / f"out-{i}.mcap")
        else:
            assert err.startswith("modd archive recover: ") and err.count("\n") == 1, err
