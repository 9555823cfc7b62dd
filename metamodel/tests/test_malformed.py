"""Malformed models, syntax and semantics: each gives an error that says where
(file:line:col and JSON pointer) and what is wrong; all errors at once."""

from __future__ import annotations

import json

import pytest
from modd_model import load_text

BASE = """\
Drone usv {
    Sensors {
        Sensor imu measures {
            ax(METER_PER_SECOND_SQUARED);
            ay(METER_PER_SECOND_SQUARED);
            flag(NONE, bool);
        }
    }
}
PubBroker("127.0.0.1":7171, "/logs");
SubBroker("127.0.0.1":7272, "/conf");
Publishers {
    Publisher pub_1("127.0.0.1":7373, 0.04, "usv.imu.ax", "usv.imu.ay", "usv.imu.flag");
}
Subscriptions {
    Subscriber sub_1("127.0.0.1":7401, "usv.imu.ax", 2.0, AVERAGE);
    Subscriber sub_2("127.0.0.1":7402, "usv.imu.ay", 0.25, MIN);
}
"""

# (case id, old text, new text, message fragment, line of the error)
CASES = [
    (
        "missing-semicolon-variable",
        "ax(METER_PER_SECOND_SQUARED);",
        "ax(METER_PER_SECOND_SQUARED)",
        "expected ';'",
        5,
    ),
    ("missing-brace", "    }\n}\nPubBroker", "    }\nPubBroker", "unexpected 'PubBroker'", 9),
    ("unknown-keyword", "Publishers {", "Publisher {", "unexpected 'Publisher'", 12),
    ("typo-sensor", "Sensor imu", "Sensr imu", "unexpected 'Sensr'", 3),
    ("missing-measures", "Sensor imu measures", "Sensor imu", "expected", 3),
    ("bad-char", "ay(METER", "ay$(METER", "unexpected character '$'", 5),
    ("unterminated-string", '"/logs");', '"/logs);', "closing quote missing", 10),
    ("endpoint-without-port", '"127.0.0.1":7171,', '"127.0.0.1",', "unexpected", 10),
    ("publisher-missing-comma", '0.04, "usv.imu.ax"', '0.04 "usv.imu.ax"', "expected ','", 13),
    ("subscriber-missing-aggregation", "2.0, AVERAGE);", "2.0);", "expected ','", 16),
    ("negative-period", "0.25, MIN", "-0.25, MIN", "unsigned decimal number", 17),
    (
        "eof-inside-block",
        '    Subscriber sub_2("127.0.0.1":7402, "usv.imu.ay", 0.25, MIN);\n}\n',
        "",
        "unexpected end of file",
        16,
    ),
    (
        "unknown-unit",
        "ay(METER_PER_SECOND_SQUARED)",
        "ay(METER_PER_SECOND_SQUARD)",
        "'METER_PER_SECOND_SQUARD' is not a UDUNITS-2 unit",
        5,
    ),
    (
        "unknown-standard-name",
        "ay(METER_PER_SECOND_SQUARED)",
        "ay(METER_PER_SECOND_SQUARED) { standardName = sea_acceleration; }",
        "'sea_acceleration' is not a CF standard name",
        5,
    ),
    (
        "unit-against-standard-name",
        "ay(METER_PER_SECOND_SQUARED)",
        "ay(METER_PER_SECOND_SQUARED) { standardName = sea_water_temperature; }",
        "does not convert to 'K'",
        5,
    ),
    ("unknown-type", "flag(NONE, bool)", "flag(NONE, boolean)", "unknown value type", 6),
    ("unknown-aggregation", "0.25, MIN", "0.25, MODE", "unknown aggregation 'MODE'", 17),
    (
        "unknown-topic-sub",
        '"usv.imu.ay", 0.25',
        '"usv.imu.az", 0.25',
        "unknown topic 'usv.imu.az'",
        17,
    ),
    (
        "unknown-topic-pub",
        '"usv.imu.ay", "usv.imu.flag"',
        '"usv.imu.ay", "usv.imu.gz"',
        "unknown topic 'usv.imu.gz'",
        13,
    ),
    ("wrong-drone-prefix", '"usv.imu.ax", 2.0', '"auv.imu.ax", 2.0', "start with 'usv.'", 16),
    ("malformed-topic-name", '"usv.imu.ax", 2.0', '"usv.imu", 2.0', "not well-formed", 16),
    (
        "duplicate-sensor",
        "    }\n}\nPubBroker",
        "        Sensor imu measures { gx(RADIAN); }\n    }\n}\nPubBroker",
        "sensor 'imu'",
        8,
    ),
    (
        "duplicate-variable",
        "ay(METER_PER_SECOND_SQUARED);",
        "ax(METER_PER_SECOND_SQUARED);",
        "variable of sensor 'imu' 'ax'",
        5,
    ),
    (
        "duplicate-subscriber",
        "Subscriber sub_2",
        "Subscriber sub_1",
        "subscriber 'sub_1' is already defined",
        17,
    ),
    ("zero-period", "0.25, MIN", "0, MIN", "greater than zero", 17),
    ("sub-faster-than-pub", "0.25, MIN", "0.01, MIN", "shorter than the publication period", 17),
    ("sub-period-below-microsecond", "0.25, MIN", "0.2500001, MIN", "finer than a microsecond", 17),
    (
        "average-on-bool",
        '"usv.imu.ay", 0.25, MIN',
        '"usv.imu.flag", 0.25, AVERAGE',
        "AVERAGE is not defined for the bool topic",
        17,
    ),
    (
        "endpoint-clash-subscriber-broker",
        '"127.0.0.1":7402',
        '"127.0.0.1":7272',
        "already used",
        17,
    ),
    ("endpoint-clash-brokers", '"127.0.0.1":7272', '"127.0.0.1":7171', "already used", 11),
    ("port-out-of-range", "7402", "70402", "70402 is greater than the maximum", 17),
    (
        "no-publisher-for-topic",
        '"usv.imu.ay", "usv.imu.flag"',
        '"usv.imu.flag"',
        "no publisher publishes 'usv.imu.ay'",
        17,
    ),
    ("second-drone", "PubBroker(", "Drone b { }\nPubBroker(", "a second Drone block", 10),
    ("missing-subbroker", 'SubBroker("127.0.0.1":7272, "/conf");\n', "", "no SubBroker block", 1),
    (
        "unknown-link-setting",
        "Publishers {",
        "Link { pingg = 1; }\nPublishers {",
        "unknown setting 'pingg'",
        12,
    ),
    (
        "link-setting-wrong-kind",
        "Publishers {",
        "Link { key = 12; }\nPublishers {",
        "takes a string",
        12,
    ),
    (
        "link-key-not-a-reference",
        "Publishers {",
        'Link { key = "hunter2"; }\nPublishers {',
        "not well-formed",
        12,
    ),
    (
        "max-buffer-fraction",
        "Publishers {",
        "Link { maxBuffer = 2.5; }\nPublishers {",
        "whole number",
        12,
    ),
    (
        "empty-sensor",
        "Sensor imu measures {",
        "Sensor empty measures { }\n        Sensor imu measures {",
        "should be non-empty",
        3,
    ),
    ("fractional-port", "7402", "7402.5", "whole number", 17),
    (
        "unknown-sensor-kind",
        "Sensor imu measures",
        "Sensor imu kind can measures",
        "unknown sensor kind 'can'",
        3,
    ),
    (
        "mavlink-without-source",
        "Sensor imu measures",
        "Sensor imu kind mavlink measures",
        "needs a source",
        4,
    ),
    (
        "source-on-generic-sensor",
        "ax(METER_PER_SECOND_SQUARED);",
        "ax(METER_PER_SECOND_SQUARED) from RAW_IMU.xacc;",
        "is not of kind mavlink",
        4,
    ),
    (
        "mavlink-zero-scale",
        "Sensor imu measures {\n            ax(METER_PER_SECOND_SQUARED);\n"
        "            ay(METER_PER_SECOND_SQUARED);\n            flag(NONE, bool);",
        "Sensor imu kind mavlink measures {\n            ax(METER_PER_SECOND_SQUARED) from "
        "RAW_IMU.xacc scale 0;\n            ay(METER_PER_SECOND_SQUARED) from RAW_IMU.yacc;\n"
        "            flag(NONE, bool) from HEARTBEAT.base_mode;",
        "scale must be",
        4,
    ),
    (
        "mavlink-lowercase-message",
        "ax(METER_PER_SECOND_SQUARED);",
        "ax(METER_PER_SECOND_SQUARED) from raw_imu.xacc;",
        "not well-formed",
        4,
    ),
]


@pytest.mark.parametrize("case_id,old,new,fragment,line", CASES, ids=[c[0] for c in CASES])
def test_malformed_input_gives_located_error(
    case_id: str, old: str, new: str, fragment: str, line: int
) -> None:
    assert old in BASE, f"{case_id}: the mutation does not apply"
    text = BASE.replace(old, new, 1)
    result = load_text(text, "mission.modd")
    assert not result.ok
    matching = [d for d in result.errors if fragment in d.message]
    assert matching, [str(d) for d in result.diagnostics]
    d = matching[0]
    assert d.location is not None and d.location.file == "mission.modd"
    assert d.location.line == line, str(d)
    assert d.location.col >= 1
    assert str(d).startswith(f"mission.modd:{line}:{d.location.col}: error: ")


def test_at_least_thirty_cases() -> None:
    assert len(CASES) >= 30


def test_base_is_valid() -> None:
    result = load_text(BASE, "mission.modd")
    assert result.ok, [str(d) for d in result.diagnostics]


def test_syntax_error_shows_line_and_caret() -> None:
    result = load_text(BASE.replace("0.04, ", "0.04 "), "m.modd")
    text = str(result.errors[0])
    lines = text.splitlines()
    assert lines[0].startswith("m.modd:13:44: error: unexpected")
    assert lines[1].strip().startswith("Publisher pub_1(")
    assert lines[2].index("^") - 4 == 43  # caret under column 44


def test_all_errors_reported_at_once() -> None:
    text = (
        BASE.replace("0.25, MIN", "0.25, MODE")
        .replace('"usv.imu.ax", 2.0', '"usv.imu.zz", 2.0')
        .replace("ay(METER_PER_SECOND_SQUARED)", "ay(WOMBAT)")
    )
    messages = [d.message for d in load_text(text, "m.modd").errors]
    assert any("MODE" in m for m in messages)
    assert any("usv.imu.zz" in m for m in messages)
    assert any("WOMBAT" in m for m in messages)


def test_warning_for_topic_nobody_publishes() -> None:
    text = BASE.replace("flag(NONE, bool);", "flag(NONE, bool);\n            spare(METER);")
    result = load_text(text, "m.modd")
    assert result.ok
    (warning,) = result.diagnostics
    assert warning.severity == "warning" and "spare" in warning.message
    assert warning.pointer == "/drone/sensors/0/variables/3"
    assert warning.location is not None and warning.location.line == 7


JSON_CASES = [
    ('"periodS": "0.25"', '"periodS": 0.25', "/subscribers/1/periodS", "is not of type 'string'"),
    ('"aggregation": "MIN"', '"aggregation": "min"', "/subscribers/1/aggregation", "is not one of"),
    ('"port": 7402', '"port": "7402"', "/subscribers/1/endpoint/port", "is not of type"),
    ('"schemaVersion": "1.0"', '"schemaVersion": "2.0"', "/schemaVersion", "was expected"),
    ('"logPath": "/logs"', '"logPath": "/logs", "colour": "red"', "/pubBroker", "unknown property"),
]


@pytest.mark.parametrize("old,new,pointer,fragment", JSON_CASES)
def test_json_errors_carry_pointer_and_file(
    old: str, new: str, pointer: str, fragment: str
) -> None:
    base = load_text(BASE, "m.modd").model
    text = json.dumps(base)
    assert old in text
    result = load_text(text.replace(old, new, 1), "mission.json", "json")
    matching = [d for d in result.errors if d.pointer == pointer and fragment in d.message]
    assert matching, [str(d) for d in result.diagnostics]
    assert str(matching[0]).startswith("mission.json: error: ")


def test_invalid_json_is_located() -> None:
    result = load_text('{\n  "drone": ,\n}', "bad.json", "json")
    (err,) = result.errors
    assert err.location is not None and (err.location.line, err.location.col) == (2, 12)


def test_text_diagnostics_carry_where_the_located_text_ends() -> None:
    """The editor underlines the whole word: ``[col, end_col)`` of the
    diagnostic is the bad word in the text (the oracle: where it stands)."""
    from pathlib import Path

    demo = Path(__file__).resolve().parents[1] / "examples" / "demo.modd"
    text = demo.read_text().replace("0.25, AVERAGE);", "0.25, AVERAGED);", 1)
    found = [d.to_json() for d in load_text(text, "demo.modd").diagnostics]
    bad = [d for d in found if str(d["pointer"]).endswith("/aggregation")]
    assert len(bad) == 1, found
    d = bad[0]
    line = text.splitlines()[int(str(d["line"])) - 1]
    assert d["end_line"] == d["line"]
    assert line[int(str(d["col"])) - 1 : int(str(d["end_col"])) - 1] == "AVERAGED"
    assert line.index("AVERAGED") == int(str(d["col"])) - 1


@pytest.mark.parametrize("depth", [65, 1_000, 200_000])
def test_json_text_nested_too_deep_is_a_located_error(depth: int) -> None:
    """Before: ``json.loads`` raised RecursionError from about 1,000 levels on
    (the workbench answered 500); now an error at line 1 of the file."""
    text = '{"drone": ' + "[" * depth + "]" * depth + "}"
    result = load_text(text, "deep.json", "json")
    assert result.model is None
    [diag] = result.diagnostics
    assert diag.severity == "error" and f"nested {depth + 1} levels" in diag.message
    assert diag.location is not None and diag.location.file == "deep.json"
    assert diag.location.line == 1


def test_json_text_at_the_depth_bound_is_parsed() -> None:
    text = '{"drone": ' + "[" * 63 + "]" * 63 + "}"
    result = load_text(text, "ok.json", "json")
    assert result.model is not None and "nested" not in str(result.diagnostics)
