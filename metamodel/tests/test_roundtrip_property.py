"""Property-based round trips: for any model document, print → parse gives the
same document, and printing is a fixed point."""

from __future__ import annotations

import string
from typing import Any

from hypothesis import given, settings
from hypothesis import strategies as st
from modd_model import dumps, load_text, parse_text
from modd_model.numbers import canonical_decimal
from modd_model.vocabulary import AGGREGATIONS, KNOWN_UNITS, VALUE_TYPES

names = st.from_regex(r"[A-Za-z_][A-Za-z0-9_]{0,10}", fullmatch=True).filter(
    # words of the language cannot be names where the grammar expects a keyword
    lambda s: s not in {"measures"}
)
free_text = st.text(alphabet=string.printable + "éµ°", max_size=30)
decimals = st.builds(
    lambda i, f: canonical_decimal(f"{i}.{f}" if f else str(i)),
    st.integers(0, 5000),
    st.sampled_from(["", "0", "5", "25", "04", "123456"]),
)
endpoints = st.fixed_dictionaries(
    {
        "host": st.sampled_from(["127.0.0.1", "localhost", "127.0.0.9"]),
        "port": st.integers(1, 65535),
    }
)


def _optional(d: dict[str, Any], **opts: Any) -> st.SearchStrategy[dict[str, Any]]:
    return st.fixed_dictionaries(d, optional=opts)


units = st.one_of(st.sampled_from(KNOWN_UNITS), free_text.filter(bool))
finite = st.floats(allow_nan=False, allow_infinity=False)
sources = _optional(
    {"message": st.from_regex(r"[A-Z][A-Z0-9_]{0,20}", fullmatch=True), "field": names},
    scale=finite,
    offset=finite,
)
variables = _optional(
    {"name": names, "unit": units},
    type=st.sampled_from(VALUE_TYPES),
    description=free_text,
    source=sources,
)
sensors = _optional(
    {"name": names, "variables": st.lists(variables, min_size=1, max_size=3)},
    description=free_text,
    kind=st.sampled_from(["generic", "mavlink"]),
)
topic_names = st.builds(lambda a, b, c: f"{a}.{b}.{c}", names, names, names)


@st.composite
def documents(draw: st.DrawFn) -> dict[str, Any]:
    doc: dict[str, Any] = {"schemaVersion": "1.0"}
    doc["drone"] = draw(
        _optional({"name": names, "sensors": st.lists(sensors, max_size=3)}, description=free_text)
    )
    doc["pubBroker"] = draw(
        _optional(
            {"endpoint": endpoints, "logPath": free_text.filter(bool)},
            name=names,
            ingress=_optional({}, unixSocket=free_text.filter(bool), tcpPort=st.integers(1, 65535)),
        )
    )
    doc["subBroker"] = draw(
        _optional({"endpoint": endpoints, "configPath": free_text.filter(bool)}, name=names)
    )
    link = draw(
        _optional(
            {},
            transport=st.just("tcp"),
            keyRef=st.just("env:MODD_PSK"),
            expectedRttS=decimals,
            maxBuffer=st.integers(1, 10_000),
            pingS=decimals,
            alpha=decimals,
            beta=decimals,
        )
    )
    if draw(st.booleans()):
        doc["link"] = link
    doc["publishers"] = draw(
        st.lists(
            _optional(
                {
                    "name": names,
                    "periodS": decimals,
                    "topics": st.lists(topic_names, min_size=1, max_size=3),
                },
                endpoint=endpoints,
            ),
            max_size=3,
        )
    )
    doc["subscribers"] = draw(
        st.lists(
            _optional(
                {
                    "name": names,
                    "topic": topic_names,
                    "periodS": decimals,
                    "aggregation": st.sampled_from(AGGREGATIONS),
                },
                endpoint=endpoints,
            ),
            max_size=4,
        )
    )
    return doc


@settings(max_examples=150, deadline=None)
@given(documents())
def test_print_then_parse_is_identity(doc: dict[str, Any]) -> None:
    text = dumps(doc, "modd")
    parsed, _ = parse_text(text, "gen.modd")
    assert parsed == doc
    assert dumps(parsed, "modd") == text


@settings(max_examples=100, deadline=None)
@given(documents())
def test_json_round_trip(doc: dict[str, Any]) -> None:
    result = load_text(dumps(doc, "json"), "gen.json", "json")
    assert result.model == doc


@settings(max_examples=200, deadline=None)
@given(st.text(alphabet=string.printable, max_size=200))
def test_parser_never_crashes_on_junk(text: str) -> None:
    result = load_text(text, "junk.modd")
    for d in result.diagnostics:
        assert d.location is not None or d.pointer
