"""The windows a SubBroker delivers, written down **before** each delivery
(docs/fleet.md, "Exactly once at the subscriber"): ``windows.journal`` beside the
window record (``windows.json``, written once every ``SAVE_S``). A station killed with
-9 loses nothing it delivered: each line is in the kernel before the value is put
(``os.write`` to a file opened for appending; no fsync: a power cut may lose the last
lines, and with them the radio link that was delivering), and it is read back into
the record at the next start. So a restarted station never backfills a window it had
delivered, and its fleet record (``modd/<drone>/fleet/held/<station>``) holds it.

Each line is one JSON list of entries: ``["r", source, start, end]`` a live window
received, ``["d", stream, start, end]`` a derived window delivered, ``["f",
subscriber, stream, start, end]`` a window backfilled. When the record is saved the
journal is set aside (``windows.journal.old``) under the record's lock and removed
once the record is written, so a kill between the two loses nothing either.

>>> import tempfile; from pathlib import Path
>>> from modd_plan.streams import StreamKey
>>> d = Path(tempfile.mkdtemp()); j = WindowJournal(d / "windows.journal")
>>> j.append([["r", "t/AVERAGE/1", 0, 10]]); rec = WindowRecord()
>>> replay(d / "windows.journal", rec), rec.received[StreamKey.parse("t/AVERAGE/1")].spans
(1, [(0, 10)])
"""

from __future__ import annotations

import json
import logging
import os
from pathlib import Path
from typing import Any

from .record_file import _int, _list, _str, _stream
from .window_record import WindowRecord

log = logging.getLogger("modd.subbroker.window_journal")

#: A journal larger than this is read up to it (a record saved every second keeps it
#: far below: the entries of about one second).
MAX_JOURNAL_BYTES = 16 * 1024 * 1024

Entry = list[Any]


class WindowJournal:
    """One SubBroker's journal file, open for appending."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.old = path.with_name(path.name + ".old")
        path.parent.mkdir(parents=True, exist_ok=True)
        self._fd = self._open()

    def _open(self) -> int:
        return os.open(self.path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o600)

    def append(self, entries: list[Entry]) -> None:
        """Write ``entries`` as one line (before the values they name are put)."""
        if entries:
            line = json.dumps(entries, separators=(",", ":")) + "\n"
            try:
                os.write(self._fd, line.encode())
            except OSError as exc:  # a full disk must not stop the delivery
                log.error("cannot write %s: %s", self.path, exc)

    def rotate(self) -> None:
        """Set the journal aside while the record that holds it is written (after a
        failed write, what is aside stays and this one is added to it)."""
        os.close(self._fd)
        if self.old.exists():
            with self.path.open("rb") as src, self.old.open("ab") as dst:
                dst.write(src.read(MAX_JOURNAL_BYTES))
            self.path.unlink()
        else:
            os.replace(self.path, self.old)
        self._fd = self._open()

    def saved(self) -> None:
        """The record holding what was set aside is written: forget it."""
        self.old.unlink(missing_ok=True)

    def close(self) -> None:
        os.close(self._fd)


def replay(path: Path, record: WindowRecord) -> int:
    """Add the windows of the journal at ``path`` (and of its ``.old``) to ``record``;
    the number of lines read. A bad line (a kill in the middle of a write, an edit) is
    skipped and named."""
    lines = 0
    for f in (path.with_name(path.name + ".old"), path):
        try:
            with f.open("rb") as fh:
                raw = fh.read(MAX_JOURNAL_BYTES)
        except FileNotFoundError:
            continue
        except OSError as exc:  # unreadable: the record alone, as before the journal
            log.error("window journal %s unreadable (%s): ignored", f, exc)
            continue
        for n, line in enumerate(raw.splitlines(), 1):
            try:
                for entry in _list(json.loads(line), f"{f.name}:{n}"):
                    _add(record, _list(entry, f"{f.name}:{n}"), f"{f.name}:{n}")
                lines += 1
            except (ValueError, ArithmeticError) as exc:
                log.warning("%s line %d skipped: %s", f, n, exc)
    return lines


def _add(record: WindowRecord, e: list[Any] | tuple[Any, ...], at: str) -> None:
    kind = e[0] if e else None
    if kind == "f" and len(e) == 5:
        start, end = _int(e[3], at), _int(e[4], at)
        record.add_filled(_str(e[1], at), _stream(e[2], at), start, end)
    elif kind in ("r", "d") and len(e) == 4:
        key, start, end = _stream(e[1], at), _int(e[2], at), _int(e[3], at)
        (record.add_received if kind == "r" else record.add_derived)(key, start, end)
    else:
        raise ValueError(f"{at}: not a journal entry ({str(e)[:60]})")
