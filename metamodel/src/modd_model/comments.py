"""The comments of .modd text, carried into its canonical form (``modd fmt``).

Comments are not part of the model, so the printer never sees them. They are
carried by position instead: each comment is attached to an element of the
source, an entry of the parser's source map (a JSON pointer and its span), as

- *leading*: on its own line(s) before the element it precedes;
- *trailing*: after code on the same line, kept at the end of the printed line
  of the element that code belongs to;
- *closing*: the last thing inside a block, kept before the block's ``}``;

and put back at that element's place in the printed text, found by parsing the
printed text again. Every construct the parser marks in its source map keeps
its comments, with no code here for any one construct.

>>> src = 'Drone d { Sensors { Sensor s measures { v(METER); // volts?\\n } } }\\n' \\
...       'PubBroker("127.0.0.1":1, "/l"); SubBroker("127.0.0.1":2, "/c");'
>>> from .parser import parse_text
>>> from .printer import print_model
>>> doc, smap = parse_text(src)
>>> print(keep_comments(src, smap, print_model(doc)).splitlines()[3])
            v(METER); // volts?
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

if TYPE_CHECKING:
    from lark.exceptions import UnexpectedInput
else:
    from ._modd_parser_gen import UnexpectedInput

from .diagnostics import Location, pointer_parent
from .parser import SourceMap, _parser, parse_text

Pos = tuple[int, int]
#: where a comment goes: before a pointer's line, at the end of its first or
#: last line, before its last line (the closing brace), or at the end of the text
Place = Literal["before", "after_start", "after_end", "close", "end"]
INDENT = "    "


@dataclass(frozen=True)
class Comment:
    text: str
    start: Pos
    end: Pos
    #: the end of the code before it on its line, if any
    after_code: Pos | None


def comments_of(text: str) -> list[Comment]:
    """The comments of ``text`` in order (none if it does not lex)."""
    out: list[Comment] = []
    last_code: tuple[int, Pos] | None = None  # (line, end) of the last code token
    try:
        for tok in _parser().lex(text, dont_ignore=True):
            start = (tok.line or 1, tok.column or 1)
            end = (tok.end_line or start[0], tok.end_column or start[1])
            if tok.type in ("LINE_COMMENT", "BLOCK_COMMENT"):
                code = last_code[1] if last_code and last_code[0] == start[0] else None
                out.append(Comment(str(tok), start, end, code))
            elif tok.type != "WS":
                last_code = (end[0], end)
    except UnexpectedInput:
        return []
    return out


def _span(loc: Location) -> tuple[Pos, Pos]:
    start = (loc.line, loc.col)
    return start, (loc.end_line or loc.line, loc.end_col or loc.col)


def _innermost(spans: dict[str, tuple[Pos, Pos]], pos: Pos, *, closed_end: bool) -> str | None:
    """The smallest element whose span holds ``pos`` (its end included if closed_end)."""
    best: str | None = None
    for ptr, (start, end) in spans.items():
        inside = start < pos <= end if closed_end else start < pos < end
        if inside and (best is None or (start, _neg(end)) > (spans[best][0], _neg(spans[best][1]))):
            best = ptr
    return best


def _neg(pos: Pos) -> Pos:
    return (-pos[0], -pos[1])


def _attach(comment: Comment, spans: dict[str, tuple[Pos, Pos]]) -> tuple[Place, str]:
    if comment.after_code is not None:
        owner = _innermost(spans, comment.after_code, closed_end=True)
        if owner is not None:
            return ("after_end" if spans[owner][1] == comment.after_code else "after_start"), owner
    container = _innermost(spans, comment.start, closed_end=False)
    limit = spans[container][1] if container else (1 << 62, 0)
    following = [
        (start, _neg(end), ptr)
        for ptr, (start, end) in spans.items()
        if start >= comment.end and end <= limit
    ]
    if following:
        return "before", min(following)[2]
    return ("close", container) if container else ("end", "")


class _Printed:
    """The printed text as lines, with each element's printed span."""

    def __init__(self, printed: str) -> None:
        self.lines = printed.splitlines()
        _, pmap = parse_text(printed)
        self.spans = {ptr: _span(loc) for ptr, loc in pmap.items()}
        self.before: dict[int, list[str]] = {}  # 0-based line -> comments put before it
        self.after: dict[int, list[str]] = {}

    def line_start(self, ptr: str) -> int | None:
        """The line of the nearest element (``ptr`` or an ancestor) that begins
        its printed line, where a comment on its own line can go."""
        while True:
            span = self.spans.get(ptr)
            if span is not None:
                (line, col), _ = span
                if not self.lines[line - 1][: col - 1].strip():
                    return line - 1
            if not ptr:
                return None
            ptr = pointer_parent(ptr)

    def put(self, place: Place, ptr: str, text: str) -> None:
        span = self.spans.get(ptr)
        if place in ("after_start", "after_end") and span is not None:
            line = span[0 if place == "after_start" else 1][0] - 1
            self.after.setdefault(line, []).append(text)
            return
        if place == "close" and span is not None and span[0][0] != span[1][0]:
            self.before.setdefault(span[1][0] - 1, []).append(INDENT + text)
            return
        at = self.line_start(ptr) if place != "end" else None
        self.before.setdefault(len(self.lines) if at is None else at, []).append(text)

    def text(self) -> str:
        out: list[str] = []
        for i in range(len(self.lines) + 1):
            if i < len(self.lines):
                indent = self.lines[i][: len(self.lines[i]) - len(self.lines[i].lstrip())]
            else:
                indent = ""
            out += [indent + c for c in self.before.get(i, [])]
            if i < len(self.lines):
                out.append(" ".join([self.lines[i], *self.after.get(i, [])]))
        return "\n".join(out) + "\n"


def keep_comments(source: str, source_map: SourceMap, printed: str) -> str:
    """``printed`` (the canonical text of the model parsed from ``source``, with
    ``source_map``) with the comments of ``source`` put back in their places."""
    comments = comments_of(source)
    if not comments:
        return printed
    spans = {ptr: _span(loc) for ptr, loc in source_map.items() if loc.line > 0}
    out = _Printed(printed)
    for comment in comments:
        place, ptr = _attach(comment, spans)
        out.put(place, ptr, comment.text)
    return out.text()
