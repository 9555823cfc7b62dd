"""The type mapping and naming filters the templates rely on."""

from __future__ import annotations

import pytest
from modd_gen import filters


@pytest.mark.parametrize("vt,cpp,enum,py", [("float32", "float", "Float32", "float"),
                                            ("float64", "double", "Float64", "float"),
                                            ("int", "int64_t", "Int", "int"),
                                            ("bool", "bool", "Bool", "bool")])
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


@pytest.mark.parametrize("period,us,ms", [("0.04", 40000, 40), ("2.0", 2000000, 2000),
                                          ("0.0005", 500, 1), ("0.0015", 1500, 2)])
def test_periods(period: str, us: int, ms: int) -> None:
    assert filters.period_us(period) == us
    assert filters.period_ms(period) == ms
