"""The type mapping and naming filters the templates rely on."""

from __future__ import annotations

import pytest
from modd_gen import filters


@pytest.mark.parametrize(
    "vt,cpp,enum,py",
    [
        ("float32", "float", "Float32", "float"),
        ("float64", "double", "Float64", "float"),
        ("int", "int64_t", "Int", "int"),
        ("bool", "bool", "Bool", "bool"),
    ],
)
def test_type_mapping(vt: str, cpp: str, enum: str, py: str) -> None:
    assert filters.cpp_type(vt) == cpp
    assert filters.cpp_value_type(vt) == enum
    assert filters.py_type(vt) == py


def test_every_schema_value_type_is_mapped() -> None:
    from modd_model.vocabulary import VALUE_TYPES

    for vt in VALUE_TYPES:
        filters.cpp_type(vt), filters.cpp_value_type(vt), filters.py_type(vt)
        filters.cpp_sample_literal(vt)


def test_identifiers_avoid_keywords() -> None:
    assert filters.cpp_ident("class") == "class_"
    assert filters.cpp_ident("accel_x") == "accel_x"
    assert filters.py_ident("lambda") == "lambda_"
    assert filters.py_ident("None") == "None_"


def test_string_literals_escape() -> None:
    assert filters.cpp_string('a "b"\\') == '"a \\"b\\"\\\\"'
    assert filters.py_string("it's") == '"it\'s"'


@pytest.mark.parametrize(
    "period,us,ms",
    [("0.04", 40000, 40), ("2.0", 2000000, 2000), ("0.0005", 500, 1), ("0.0015", 1500, 2)],
)
def test_periods(period: str, us: int, ms: int) -> None:
    assert filters.period_us(period) == us
    assert filters.period_ms(period) == ms


# -- escaping of model strings -------------------------------------------------

HOSTILE = [
    'm\n#include <cstdlib>\nint p=std::system("id>PWNED");//',
    "*/ /* \"\"\" ''' \\",
    "${HOME} $(id) `id` ??/ ??=",
    "\r\x0b\x0c\x1b\x7f\x85\u2028\u2029\u202e",
    "µS/cm 米/秒² Ωμέγα ∑ 🚁",
    "a\\",
    "\\",
    '"',
    "x|y <b>&amp;</b> [a](b) *c* _d_",
    "\U0001f681\\\n",
    "",
]


def _c_literal_value(literal: str) -> bytes:
    """An independent decoder of the escapes cpp_string emits (plain ASCII,
    \\" \\\\ \\? and three-digit octal)."""
    assert literal[0] == literal[-1] == '"'
    body, out, i = literal[1:-1], bytearray(), 0
    while i < len(body):
        c = body[i]
        assert 0x20 <= ord(c) < 0x7F, repr(c)
        if c == "\\":
            nxt = body[i + 1]
            if nxt in '"\\?':
                out.append(ord(nxt))
                i += 2
            else:
                out.append(int(body[i + 1 : i + 4], 8))
                i += 4
        else:
            assert c != '"'
            out.append(ord(c))
            i += 1
    return bytes(out)


@pytest.mark.parametrize("text", HOSTILE)
def test_cpp_string_holds_exactly_the_text(text: str) -> None:
    literal = filters.cpp_string(text)
    assert "\n" not in literal and "??" not in literal
    assert _c_literal_value(literal) == text.encode("utf-8")


@pytest.mark.parametrize("text", HOSTILE)
def test_python_literal_and_docstring_hold_exactly_the_text(text: str) -> None:
    import ast

    assert ast.literal_eval(filters.py_string(text)) == text
    doc = '"""x ' + filters.py_docstring(text) + ' y"""'
    assert ast.literal_eval(doc) == f"x {text} y"
    assert "\n" not in filters.py_docstring(text)


@pytest.mark.parametrize("text", HOSTILE)
def test_comment_stays_on_its_line(text: str) -> None:
    out = filters.comment(text)
    assert out.isprintable(), repr(out)  # no line break of any kind, no control character
    assert not out.endswith("\\") and "??" not in out
    if text.isprintable() and not any(c in text for c in '\\"`') and "??" not in text:
        assert out == text  # plain text is printed as is


@pytest.mark.parametrize("text", HOSTILE)
def test_markdown_text_stays_in_its_cell(text: str) -> None:
    import re

    for out in (filters.md_text(text), filters.md_code(text)):
        assert out.isprintable(), repr(out)
        assert not re.search(r"(?<!\\)\|", out), out  # every | escaped
        assert "<" not in out or out.startswith("`")


def test_identifiers_are_ascii_whatever_the_name() -> None:
    assert filters.cpp_ident("a\nb") == "a_b"
    assert filters.cpp_ident("ünï") == "_n_"
    assert filters.py_ident("1x") == "_1x"


def test_numbers_are_checked() -> None:
    assert filters.decimal("0.25") == "0.25"
    with pytest.raises(ValueError):
        filters.decimal("1\n")
    with pytest.raises(ValueError):
        filters.port("7401")


def test_every_template_expression_is_filtered() -> None:
    """A template prints no value raw: every {{ }} ends with a filter (except the
    constant banner and loop counters)."""
    import re
    from pathlib import Path

    import modd_gen

    templates = Path(modd_gen.__file__).parent / "templates"
    raw = []
    for path in sorted(templates.rglob("*.j2")):
        for expr in re.findall(r"{{-?\s*(.*?)\s*-?}}", path.read_text(encoding="utf-8")):
            if expr not in ("banner", "loop.index0") and "|" not in expr:
                raw.append(f"{path.name}: {{{{ {expr} }}}}")
    assert raw == []
