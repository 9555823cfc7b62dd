"""The window record as kept in ``windows.json``, read strictly: every field is
checked for its type and range, and the first one that is not as written is
named by its JSON pointer (ValueError), so that a damaged or hostile file is
set aside with a clear message rather than stopping the base station
(docs/subbroker.md, "State files"). Bounded: at most :data:`MAX_EPOCHS`
epochs (the newest), :data:`MAX_DUE` streams due per epoch and
:data:`MAX_SPANS` intervals per stream are taken; the file's size and depth
are bounded before it is parsed (:mod:`.kept`).

>>> read_record({"epochs": [], "received": [], "filled": []})
Traceback (most recent call last):
ValueError: /received: an object expected, not a list
"""

from __future__ import annotations

import itertools
from typing import Any

from modd_contracts import labels
from modd_contracts.aggregations_gen import NAMES
from modd_plan.streams import StreamKey

from .fanout import period_us
from .window_record import MAX_EPOCHS, MAX_SPANS, Due, Epoch, Intervals, WindowRecord

#: Streams due in one epoch (subscribers × streams) taken from a kept record.
MAX_DUE = 20_000
_NS_MAX = 1 << 63
_PERIOD_MAX_US = 86_400 * 1_000_000  # a window of at most a day
_NAMES = frozenset(NAMES)  # the labels without a parameter: most streams


_KINDS: dict[type, str] = {dict: "an object", list: "a list", str: "a string"}


def _kind(v: Any) -> str:
    return "null" if v is None else _KINDS.get(type(v), type(v).__name__)


def _obj(v: Any, at: str) -> dict[str, Any]:
    if not isinstance(v, dict):
        raise ValueError(f"{at}: an object expected, not {_kind(v)}")
    return v


def _list(v: Any, at: str, length: int | None = None) -> list[Any] | tuple[Any, ...]:
    if not isinstance(v, list | tuple) or (length is not None and len(v) != length):
        what = f"a list of {length}" if length is not None else "a list"
        raise ValueError(f"{at}: {what} expected, not {_kind(v)}")
    return v


def _int(v: Any, at: str, lo: int = 0, hi: int = _NS_MAX) -> int:
    if not isinstance(v, int) or isinstance(v, bool) or not lo <= v < hi:
        raise ValueError(f"{at}: an integer in [{lo}, {hi}) expected, not {v!r:.40}")
    return v


def _str(v: Any, at: str) -> str:
    if not isinstance(v, str) or len(v) > 1024:
        raise ValueError(f"{at}: a string (up to 1024 characters) expected, not {_kind(v)}")
    return v


def _stream(v: Any, at: str) -> StreamKey:
    text = _str(v, at)
    try:
        key = StreamKey.parse(text)
        if key.aggregation not in _NAMES:
            labels.parse(key.aggregation)  # ValueError: not an aggregation's label
        if not 0 < period_us(key) <= _PERIOD_MAX_US:
            raise ValueError("period out of range")
    except (ValueError, ArithmeticError) as exc:
        raise ValueError(f"{at}: not a stream key ({text!r:.60}: {exc})") from None
    return key


def _spans(v: Any, at: str) -> list[tuple[int, int]]:
    raw = _list(v, at)[-MAX_SPANS:]
    spans = []
    for n, pair in enumerate(raw):
        a, b = _list(pair, f"{at}/{n}", 2)
        spans.append((_int(a, f"{at}/{n}/0"), _int(b, f"{at}/{n}/1")))
    if any(b < a for a, b in spans) or any(x[1] > y[0] for x, y in itertools.pairwise(spans)):
        raise ValueError(f"{at}: intervals out of order")
    return spans


def read_record(doc: Any) -> WindowRecord:
    """The record kept in ``doc`` (parsed JSON); ValueError naming the first bad field."""
    top = _obj(doc, "")
    rec = WindowRecord()
    epochs = _list(top.get("epochs"), "/epochs")
    first = max(0, len(epochs) - MAX_EPOCHS)  # written in epoch order: the newest last
    for n, raw in enumerate(epochs[first:], first):
        e = _obj(raw, f"/epochs/{n}")
        due = []
        for m, d in enumerate(_list(e.get("due"), f"/epochs/{n}/due")[:MAX_DUE]):
            at = f"/epochs/{n}/due/{m}"
            s, k, src, u, t = _list(d, at, 5)
            due.append(Due(_str(s, at), _stream(k, at), _stream(src, at), _str(u, at), _str(t, at)))
        mission = _str(e.get("mission"), f"/epochs/{n}/mission")
        cid = _int(e.get("config_id"), f"/epochs/{n}/config_id", 0, 256)
        ns = _int(e.get("epoch_ns"), f"/epochs/{n}/epoch_ns")
        rec.epochs.append(Epoch(mission, cid, ns, due))
    by_ns = {e.epoch_ns: e for e in rec.epochs}  # the same epoch twice: the later one
    rec.epochs = sorted(by_ns.values(), key=lambda e: e.epoch_ns)
    for name in ("received", "derived"):
        if name == "derived" and name not in top:
            continue
        for k, spans in _obj(top.get(name), f"/{name}").items():
            at = f"/{name}/{k[:60]}"
            getattr(rec, name)[_stream(k, at)] = Intervals(_spans(spans, at))
    for n, f in enumerate(_list(top.get("filled"), "/filled")):
        s, k, spans = _list(f, f"/filled/{n}", 3)
        at = f"/filled/{n}"
        rec.filled[(_str(s, at), _stream(k, at))] = Intervals(_spans(spans, at))
    if "derived" not in top:  # a record of an earlier version counted them by their source
        rec.derived_from_sources()
    return rec
