"""Every free-text field of a model is bounded and free of control characters,
and names are matched whole: a string that could inject into generated code
or configs (a newline in a unit, a TOML table in a path, a trailing newline
after a name) is rejected with an error at its JSON pointer, in Python as in
the schema's own (ECMA-262) reading of its patterns."""

from __future__ import annotations

import copy
from typing import Any

import pytest
from modd_model import load_model, load_text, validate
from modd_model.validate import ecma_regex

ATTACK_UNIT = 'm\n#include <cstdlib>\nint p=std::system("id>PWNED");//'


@pytest.fixture(scope="module")
def base(scenarios_dir: Any) -> dict[str, Any]:
    return load_model(scenarios_dir / "scenario1.modd")


def _set(doc: dict[str, Any], pointer: str, value: Any) -> dict[str, Any]:
    doc = copy.deepcopy(doc)
    *parents, last = pointer.strip("/").split("/")
    node: Any = doc
    for p in parents:
        node = node[int(p)] if isinstance(node, list) else node.setdefault(p, {})
    if isinstance(node, list):
        node[int(last)] = value
    else:
        node[last] = value
    return doc


REJECTED = [
    ("unit-injection", "/drone/sensors/0/variables/0/unit", ATTACK_UNIT),
    ("unit-carriage-return", "/drone/sensors/0/variables/0/unit", "m\rx"),
    ("unit-bidi-override", "/drone/sensors/0/variables/0/unit", "m\u202e/s"),
    ("unit-too-long", "/drone/sensors/0/variables/0/unit", "m" * 65),
    ("name-trailing-newline", "/subscribers/0/name", "sub_1\n"),
    ("drone-trailing-newline", "/drone/name", "usv\n"),
    ("name-too-long", "/subscribers/0/name", "s" * 65),
    ("topic-trailing-newline", "/subscribers/0/topic", "usv.accelerometer.accel_x\n"),
    ("period-trailing-newline", "/subscribers/0/periodS", "2\n"),
    ("host-toml-injection", "/pubBroker/endpoint/host", '127.0.0.1"\n[zenoh.settings]\nx="'),
    ("host-space", "/subBroker/endpoint/host", "a b"),
    ("host-not-an-address", "/subBroker/endpoint/host", "999.1.1.1"),
    ("host-bad-ipv6", "/subBroker/endpoint/host", "1::2::3"),
    (
        "config-path-toml-injection",
        "/subBroker/configPath",
        '/conf"\n[zenoh]\nlisten = ["tcp/0.0.0.0:7447"]\n#',
    ),
    ("log-path-control", "/pubBroker/logPath", "/logs\x1b[2J"),
    ("socket-path-newline", "/pubBroker/ingress/unixSocket", "/run/x.sock\n"),
    ("path-too-long", "/pubBroker/logPath", "/" + "a" * 1024),
    ("key-ref-newline", "/link/keyRef", "env:MODD_KEY\n"),
    ("key-ref-env-not-a-name", "/link/keyRef", "env:A B"),
    ("description-escape", "/drone/description", "the \x1b[31mred\x1b[0m boat"),
    ("description-too-long", "/drone/description", "x" * 1001),
    (
        "mavlink-message-newline",
        "/drone/sensors/0/variables/0/source",
        {"message": "RAW_IMU\n", "field": "xacc"},
    ),
    ("layout-node-id-control", "/layout/nodes", {"a\x00b": {"x": 0, "y": 0}}),
]


@pytest.mark.parametrize("case_id,pointer,value", REJECTED, ids=[c[0] for c in REJECTED])
def test_hostile_string_is_rejected_at_its_pointer(
    base: dict[str, Any], case_id: str, pointer: str, value: Any
) -> None:
    doc = _set(base, pointer, value)
    errors = [d for d in validate(doc) if d.severity == "error"]
    assert errors, f"{case_id}: accepted"
    assert any(d.pointer.startswith(pointer) for d in errors), [str(d) for d in errors]


ACCEPTED = [
    # a unit is checked by UDUNITS-2 too (test_units.py); the long name takes any text
    ("unit-symbols", "/drone/sensors/0/variables/0/unit", "µS/cm"),
    ("long-name-unicode", "/drone/sensors/0/variables/0/longName", "µS/cm · °C · 米/秒²"),
    (
        "long-name-quotes-and-comment",
        "/drone/sensors/0/variables/0/longName",
        "*/ \"m\" 's' \\ ${x} $(id)",
    ),
    ("host-name", "/subBroker/endpoint/host", "base-station.local"),
    ("host-ipv6", "/subBroker/endpoint/host", "::1"),
    ("path-unicode", "/subBroker/configPath", '/données/конфиг "q" $(id)'),
    ("description-multiline", "/drone/description", "line one\nline two\ttabbed"),
    ("key-ref-file", "/link/keyRef", "file:/etc/modd/link key"),
]


@pytest.mark.parametrize("case_id,pointer,value", ACCEPTED, ids=[c[0] for c in ACCEPTED])
def test_printable_text_is_accepted(
    base: dict[str, Any], case_id: str, pointer: str, value: Any
) -> None:
    doc = _set(base, pointer, value)
    assert [str(d) for d in validate(doc) if d.severity == "error"] == []


def test_dsl_escape_cannot_smuggle_a_newline_into_a_unit() -> None:
    text = (
        'Drone usv { Sensors { Sensor imu measures { ax("m\\n#include <cstdlib>"); } } }\n'
        'PubBroker("127.0.0.1":7171, "/logs");\nSubBroker("127.0.0.1":7272, "/conf");\n'
        'Publishers { Publisher pub_1(0.04, "usv.imu.ax"); }\nSubscriptions { }\n'
    )
    result = load_text(text, "m.modd")
    # the grammar keeps the backslash: then the unit holds no newline
    if result.ok and result.model is not None:
        unit = result.model["drone"]["sensors"][0]["variables"][0]["unit"]
        assert "\n" not in unit
    else:
        assert all(d.location is not None for d in result.errors)


def test_schema_patterns_end_at_the_end_of_the_text() -> None:
    """ECMA-262's ``$`` (as in the browser) is the end of the text; Python's is not."""
    assert ecma_regex("^[a-z]+$").search("abc")
    assert not ecma_regex("^[a-z]+$").search("abc\n")
    assert ecma_regex("^[$a]+$").search("$a$")  # a $ inside a class is a character
    assert ecma_regex(r"^\$$").search("$")


def test_decimal_literal_is_matched_whole() -> None:
    """``canonical_decimal`` matched a prefix only: "2.0\\n" and "2.0 " passed."""
    from modd_model.numbers import canonical_decimal

    assert canonical_decimal("2.0") == "2.0"
    for text in ("2.0\n", "2.0 ", " 2.0", "2.0x", "2..0"):
        with pytest.raises(ValueError, match="not a decimal"):
            canonical_decimal(text)
