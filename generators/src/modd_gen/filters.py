"""Type mapping and naming for the templates (Jinja filters). Templates lay
out text only; every decision about types and names is made here, and tested."""

from __future__ import annotations

import json
import re
from typing import Any

_CPP_TYPES = {"float32": "float", "float64": "double", "int": "int64_t", "bool": "bool"}
_CPP_VALUE_TYPES = {"float32": "Float32", "float64": "Float64", "int": "Int", "bool": "Bool"}
_PY_TYPES = {"float32": "float", "float64": "float", "int": "int", "bool": "bool"}
_CPP_KEYWORDS = {"and", "auto", "bool", "break", "case", "char", "class", "const", "default",
                 "delete", "do", "double", "else", "enum", "float", "for", "if", "int", "long",
                 "namespace", "new", "not", "or", "private", "public", "return", "short",
                 "signed", "sizeof", "static", "struct", "switch", "template", "this", "throw",
                 "try", "union", "unsigned", "using", "virtual", "void", "while", "xor"}
_PY_KEYWORDS = {"and", "as", "assert", "async", "await", "break", "class", "continue", "def",
                "del", "elif", "else", "except", "finally", "for", "from", "global", "if",
                "import", "in", "is", "lambda", "nonlocal", "not", "or", "pass", "raise",
                "return", "try", "while", "with", "yield", "None", "True", "False"}


def cpp_type(value_type: str) -> str:
    """C++ type of a sample: ``cpp_type("float32") == "float"``."""
    return _CPP_TYPES[value_type]


def cpp_value_type(value_type: str) -> str:
    """The ``modd::ValueType`` enumerator: ``cpp_value_type("int") == "Int"``."""
    return _CPP_VALUE_TYPES[value_type]


def py_type(value_type: str) -> str:
    return _PY_TYPES[value_type]


def cpp_ident(name: str) -> str:
    """A C++ identifier for a model name (names are already identifiers; keywords get a _)."""
    ident = re.sub(r"\W", "_", name)
    return ident + "_" if ident in _CPP_KEYWORDS else ident


def py_ident(name: str) -> str:
    ident = re.sub(r"\W", "_", name)
    return ident + "_" if ident in _PY_KEYWORDS else ident


def cpp_string(text: str) -> str:
    """A C++ string literal (JSON escaping is valid C++ for these characters)."""
    return json.dumps(text, ensure_ascii=True)


def py_string(text: str) -> str:
    return repr(text)


def cpp_sample_literal(value_type: str) -> str:
    """A placeholder reading of the right type, used by the generated skeletons."""
    return {"float32": "0.0f", "float64": "0.0", "int": "int64_t{0}", "bool": "false"}[value_type]


def period_ms(period_s: str) -> int:
    """A decimal period in whole milliseconds, rounded up to at least 1."""
    from modd_model.numbers import to_fraction

    ms = to_fraction(period_s) * 1000
    return max(1, int(ms) if ms.denominator == 1 else int(ms) + 1)


def period_us(period_s: str) -> int:
    from modd_model.numbers import to_micros

    return to_micros(period_s)


def to_json(value: Any) -> str:
    return json.dumps(value, indent=2, ensure_ascii=False)


FILTERS = {
    "cpp_type": cpp_type,
    "cpp_value_type": cpp_value_type,
    "py_type": py_type,
    "cpp_ident": cpp_ident,
    "py_ident": py_ident,
    "cpp_string": cpp_string,
    "py_string": py_string,
    "cpp_sample_literal": cpp_sample_literal,
    "period_ms": period_ms,
    "period_us": period_us,
    "to_json": to_json,
}
