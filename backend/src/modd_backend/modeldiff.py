"""A structural diff of two models, for "what is deployed against what is
edited". Lists of named objects (sensors, variables, publishers,
subscribers) are matched by name, so that a reordering is no change and a
renamed subscriber is one removal plus one addition.

>>> diff({"a": 1, "b": [{"name": "x", "p": 1}]}, {"a": 2, "b": [{"name": "x", "p": 2}]})
[{'op': 'replace', 'pointer': '/a', 'before': 1, 'after': 2}, \
{'op': 'replace', 'pointer': '/b/0/p', 'before': 1, 'after': 2}]
"""

from __future__ import annotations

from typing import Any

Change = dict[str, Any]


def _esc(part: str | int) -> str:
    return str(part).replace("~", "~0").replace("/", "~1")


def _named(items: list[Any]) -> dict[str, int] | None:
    names: list[str] = []
    for item in items:
        name = item.get("name") if isinstance(item, dict) else None
        if not isinstance(name, str):
            return None
        names.append(name)
    if len(set(names)) != len(names):
        return None
    return {n: k for k, n in enumerate(names)}


def diff(before: Any, after: Any, pointer: str = "") -> list[Change]:
    """Changes turning ``before`` into ``after``; pointers index ``after``
    (``before`` for removals)."""
    if isinstance(before, dict) and isinstance(after, dict):
        out: list[Change] = []
        for key in list(before) + [k for k in after if k not in before]:
            p = f"{pointer}/{_esc(key)}"
            if key not in after:
                out.append({"op": "remove", "pointer": p, "before": before[key]})
            elif key not in before:
                out.append({"op": "add", "pointer": p, "after": after[key]})
            else:
                out.extend(diff(before[key], after[key], p))
        return out
    if isinstance(before, list) and isinstance(after, list):
        return _diff_lists(before, after, pointer)
    if before == after and type(before) is type(after):
        return []
    return [{"op": "replace", "pointer": pointer, "before": before, "after": after}]


def _diff_lists(before: list[Any], after: list[Any], pointer: str) -> list[Change]:
    old, new = _named(before), _named(after)
    out: list[Change] = []
    if old is not None and new is not None:
        for name, i in old.items():
            if name not in new:
                out.append({"op": "remove", "pointer": f"{pointer}/{i}", "before": before[i]})
        for name, j in new.items():
            if name in old:
                out.extend(diff(before[old[name]], after[j], f"{pointer}/{j}"))
            else:
                out.append({"op": "add", "pointer": f"{pointer}/{j}", "after": after[j]})
        return out
    for k in range(max(len(before), len(after))):
        p = f"{pointer}/{k}"
        if k >= len(after):
            out.append({"op": "remove", "pointer": p, "before": before[k]})
        elif k >= len(before):
            out.append({"op": "add", "pointer": p, "after": after[k]})
        else:
            out.extend(diff(before[k], after[k], p))
    return out
