"""``modd archive recover FILE``: rewrite an MCAP file that a crash left
without summary and index (like ``mcap recover``), or that bad bytes damaged,
so that every reader (indexed readers included) opens it. The messages are
those of every chunk whose data checks, wherever it lies (:mod:`.scan` skips
damaged regions and reports them), with their schemas and channels, written in
log-time order by the official ``mcap`` writer (zstd chunks, message indexes,
statistics, summary, footer).

>>> report = recover("crashed.mcap", "crashed-recovered.mcap")   # doctest: +SKIP
>>> report.messages                                              # doctest: +SKIP
5120
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from mcap.writer import CompressionType, Writer

from .scan import Skipped, scan_file


@dataclass(frozen=True)
class Recovered:
    source: Path
    output: Path
    messages: int
    channels: int
    was_complete: bool
    stopped_at: str | None
    chunks: int = 0
    skipped: tuple[Skipped, ...] = ()


def default_output(path: Path) -> Path:
    """``x.mcap`` -> ``x-recovered.mcap`` beside it."""
    return path.with_name(f"{path.stem}-recovered{path.suffix or '.mcap'}")


def recover(
    source: str | Path, output: str | Path | None = None, chunk_size: int = 1 << 20
) -> Recovered:
    """Writes the readable part of ``source`` to ``output`` (default
    :func:`default_output`; ``output == source`` replaces it atomically)."""
    src = Path(source)
    dst = Path(output) if output is not None else default_output(src)
    scan = scan_file(src)
    tmp = dst.with_name(f".{dst.name}.tmp-{os.getpid()}")
    try:
        with open(tmp, "wb") as f:
            w = Writer(f, chunk_size=chunk_size, compression=CompressionType.ZSTD)
            w.start(profile="", library="modd archive recover")
            schema_ids: dict[int, int] = {}
            for sid, s in sorted(scan.schemas.items()):
                schema_ids[sid] = w.register_schema(s.name, s.encoding, s.data)
            channel_ids: dict[int, int] = {}
            for cid, c in sorted(scan.channels.items()):
                channel_ids[cid] = w.register_channel(
                    c.topic, c.message_encoding, schema_ids.get(c.schema_id, 0), dict(c.metadata)
                )
            kept = 0
            for m in sorted(scan.messages, key=lambda m: (m.log_time, m.channel_id, m.sequence)):
                if m.channel_id not in channel_ids:
                    continue  # a message whose channel record was lost: unreadable anyway
                w.add_message(
                    channel_ids[m.channel_id], m.log_time, m.data, m.publish_time, m.sequence
                )
                kept += 1
            w.finish()  # type: ignore[no-untyped-call]
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, dst)
    finally:
        tmp.unlink(missing_ok=True)
    return Recovered(
        src,
        dst,
        kept,
        len(channel_ids),
        scan.complete,
        scan.error,
        scan.chunks,
        tuple(scan.skipped),
    )


def format_report(r: Recovered, limit: int = 50) -> str:
    """What ``modd archive recover`` prints: what was written, then each
    damaged region skipped (offset and length in bytes, why)."""
    state = "was closed" if r.was_complete else "was not closed"
    lines = [
        f"{r.source} ({state}): {r.messages} messages on {r.channels} channels in "
        f"{r.chunks} chunks written to {r.output}"
    ]
    if r.skipped:
        total = sum(s.length for s in r.skipped)
        lines.append(f"  skipped {len(r.skipped)} damaged or torn region(s), {total} bytes:")
        lines += [f"    offset {s.offset}, {s.length} bytes: {s.why}" for s in r.skipped[:limit]]
        if len(r.skipped) > limit:
            lines.append(f"    ... {len(r.skipped) - limit} more")
    else:
        lines.append("  nothing skipped: every record checked")
    return "\n".join(lines)
