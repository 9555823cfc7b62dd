"""Every complete record of an MCAP file, whether it was closed properly or
cut by a crash (``kill -9``: no summary, no footer, maybe a torn last chunk).

The official ``mcap`` record scanner reads chunk by chunk; a record cut in
the middle raises, and everything before it has been yielded. So a scan keeps
what was read and says where the file stopped being readable.

>>> scan = scan_file("usv-20260101T000000Z-0000.mcap")    # doctest: +SKIP
>>> scan.complete, len(scan.messages)                      # doctest: +SKIP
(False, 5120)
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field
from pathlib import Path

from mcap.exceptions import McapError
from mcap.records import Channel, Footer, Message, Schema
from mcap.stream_reader import StreamReader


class TooLarge(ValueError):
    """More messages than a scan may hold in memory."""


@dataclass
class Scan:
    """What a file holds up to its last complete record.

    ``complete`` is True when the file ends with a footer (it was closed);
    ``error`` says why reading stopped early (None when it did not)."""

    path: Path
    schemas: dict[int, Schema] = field(default_factory=dict)
    channels: dict[int, Channel] = field(default_factory=dict)
    messages: list[Message] = field(default_factory=list)
    complete: bool = False
    error: str | None = None


def scan_file(path: str | Path, max_messages: int = 50_000_000) -> Scan:
    """Reads ``path`` record by record (CRCs checked); raises ``ValueError``
    when it is not an MCAP file at all. ``max_messages`` bounds memory."""
    p = Path(path)
    out = Scan(p)
    with open(p, "rb") as f:
        magic = f.read(8)
        if magic != b"\x89MCAP0\r\n":
            raise ValueError(f"{p}: not an MCAP file (no MCAP magic at offset 0)")
        f.seek(0)
        try:
            for rec in StreamReader(f, validate_crcs=True).records:
                if isinstance(rec, Schema):
                    out.schemas[rec.id] = rec
                elif isinstance(rec, Channel):
                    out.channels[rec.id] = rec
                elif isinstance(rec, Message):
                    if len(out.messages) >= max_messages:
                        raise TooLarge(f"{p}: more than {max_messages} messages")
                    out.messages.append(rec)
                elif isinstance(rec, Footer):
                    out.complete = True
        except TooLarge:
            raise
        except (McapError, EOFError, struct.error, ValueError) as exc:
            why = str(exc) or type(exc).__name__
            out.error = f"{p}: readable up to the last complete record; then {why}"
    return out
