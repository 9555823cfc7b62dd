"""Bytes from a device → lines, with a bounded buffer: a line longer than
``max_line`` is dropped (counted) up to the next terminator instead of growing
the buffer, so a device sending garbage with no terminator (the wrong baud
rate) costs at most ``max_line`` bytes of memory.

Example::

    >>> s = LineSplitter(b"\\n", max_line=16)
    >>> s.feed(b"a,1\\r\\nb,"), s.feed(b"2\\n")
    (['a,1'], ['b,2'])
"""

from __future__ import annotations

#: The byte a line is split at, and what ends a line written to the device, per terminator.
TERMINATORS = {"crlf": b"\n", "lf": b"\n", "cr": b"\r"}
LINE_ENDS = {"crlf": b"\r\n", "lf": b"\n", "cr": b"\r"}


class LineSplitter:
    def __init__(self, terminator: bytes = b"\n", max_line: int = 4096) -> None:
        self.terminator = terminator
        self.max_line = max_line
        self._buf = bytearray()
        self._skipping = False  # inside an overlong line: drop up to the next terminator
        self.overlong = 0  # lines dropped for their length
        self.undecodable = 0  # lines that are not ASCII/UTF-8 text

    def feed(self, data: bytes) -> list[str]:
        """The complete lines ``data`` ends (without terminator nor trailing CR)."""
        out: list[str] = []
        start = 0
        while True:
            end = data.find(self.terminator, start)
            if end < 0:
                break
            piece = data[start:end]
            start = end + 1
            if self._skipping:
                self._skipping = False
                self._buf.clear()
                continue
            self._buf += piece
            line = bytes(self._buf)
            self._buf.clear()
            if len(line) > self.max_line:
                self.overlong += 1
                continue
            try:
                out.append(line.decode("utf-8").rstrip("\r\n"))
            except UnicodeDecodeError:
                self.undecodable += 1
        rest = data[start:]
        if not self._skipping:
            self._buf += rest
            if len(self._buf) > self.max_line:
                self._buf.clear()
                self._skipping = True
                self.overlong += 1
        return out

    def reset(self) -> None:
        """Forget a partial line (the device was reopened: its end will never come)."""
        self._buf.clear()
        self._skipping = False
