"""The body guard's depth check (C loops only) against the regex walk it
replaced, on random texts made of brackets, quotes, escapes and the rest."""

from __future__ import annotations

import re

from hypothesis import given, settings
from hypothesis import strategies as st
from modd_model.jsondepth import json_depth

_STRINGS = re.compile(rb'"(?:[^"\\]|\\.)*"', re.DOTALL)
_BRACKETS = re.compile(rb"[\[\]{}]")


def oracle(data: bytes) -> int:
    depth = deepest = 0
    for m in _BRACKETS.finditer(_STRINGS.sub(b'""', data)):
        if m.group() in (b"[", b"{"):
            depth += 1
            deepest = max(deepest, depth)
        else:
            depth -= 1
    return deepest


@settings(max_examples=2000, deadline=None)
@given(
    st.lists(
        st.sampled_from([b"[", b"]", b"{", b"}", b'"', b"\\", b"a", b"\n", b","]), max_size=40
    ).map(b"".join)
)
def test_depth_matches_the_regex_walk(data: bytes) -> None:
    assert json_depth(data) == oracle(data)


def test_depth_of_documents() -> None:
    assert json_depth(b'{"a": [1, {"b": "]]]\\"[["}]}') == 3
    assert json_depth(b"[" * 500 + b"]" * 500) == 500
    assert json_depth(b'"[[[') == oracle(b'"[[[') == 3  # an unmatched quote opens no string
    assert json_depth(b"") == 0
