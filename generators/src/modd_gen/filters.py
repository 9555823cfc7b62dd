"""Type mapping and naming for the templates (Jinja filters). Templates lay
out text only; every decision about types and names is made here, and tested."""

from __future__ import annotations

import html
import json
import re
from typing import Any

_CPP_TYPES = {"float32": "float", "float64": "double", "int": "int64_t", "bool": "bool"}
_CPP_VALUE_TYPES = {"float32": "Float32", "float64": "Float64", "int": "Int", "bool": "Bool"}
_PY_TYPES = {"float32": "float", "float64": "float", "int": "int", "bool": "bool"}
_CPP_KEYWORDS = {
    "and",
    "auto",
    "bool",
    "break",
    "case",
    "char",
    "class",
    "const",
    "default",
    "delete",
    "do",
    "double",
    "else",
    "enum",
    "float",
    "for",
    "if",
    "int",
    "long",
    "namespace",
    "new",
    "not",
    "or",
    "private",
    "public",
    "return",
    "short",
    "signed",
    "sizeof",
    "static",
    "struct",
    "switch",
    "template",
    "this",
    "throw",
    "try",
    "union",
    "unsigned",
    "using",
    "virtual",
    "void",
    "while",
    "xor",
}
_PY_KEYWORDS = {
    "and",
    "as",
    "assert",
    "async",
    "await",
    "break",
    "class",
    "continue",
    "def",
    "del",
    "elif",
    "else",
    "except",
    "finally",
    "for",
    "from",
    "global",
    "if",
    "import",
    "in",
    "is",
    "lambda",
    "nonlocal",
    "not",
    "or",
    "pass",
    "raise",
    "return",
    "try",
    "while",
    "with",
    "yield",
    "None",
    "True",
    "False",
}


def cpp_type(value_type: str) -> str:
    """C++ type of a sample: ``cpp_type("float32") == "float"``."""
    return _CPP_TYPES[value_type]


def cpp_value_type(value_type: str) -> str:
    """The ``modd::ValueType`` enumerator: ``cpp_value_type("int") == "Int"``."""
    return _CPP_VALUE_TYPES[value_type]


def py_type(value_type: str) -> str:
    return _PY_TYPES[value_type]


def _ident(name: str) -> str:
    ident = re.sub(r"[^A-Za-z0-9_]", "_", name)
    return "_" + ident if not ident or ident[0].isdigit() else ident


def cpp_ident(name: str) -> str:
    """A C++ (and CMake target) identifier for a model name: ASCII letters, digits
    and _ only, whatever the name holds; keywords get a _: ``cpp_ident("new") == "new_"``."""
    ident = _ident(name)
    return ident + "_" if ident in _CPP_KEYWORDS else ident


def py_ident(name: str) -> str:
    """A Python identifier for a model name: ``py_ident("class") == "class_"``."""
    ident = _ident(name)
    return ident + "_" if ident in _PY_KEYWORDS else ident


# Model strings reach generated text in four kinds of place: string literals
# (C++, Python), comments (C++ //, Python #, CMake #, TOML #), docstrings and
# Markdown. Each gets its own filter; a template prints no model string raw.


def cpp_string(text: str) -> str:
    """A C++ string literal holding exactly ``text`` (as UTF-8), in plain ASCII: quote,
    backslash and ? (trigraphs) escaped, every other byte outside printable ASCII
    as a three-digit octal escape (never \\x, which would swallow a following hex
    digit; never \\u, which may not name a control character).

    >>> cpp_string('a"b\\n')
    '"a\\\\"b\\\\012"'
    """
    out = []
    for byte in text.encode("utf-8"):
        ch = chr(byte)
        if ch in '"\\?':
            out.append("\\" + ch)
        elif 0x20 <= byte < 0x7F:
            out.append(ch)
        else:
            out.append(f"\\{byte:03o}")
    return '"' + "".join(out) + '"'


def py_string(text: str) -> str:
    """A Python string literal holding exactly ``text`` (``repr`` escapes every
    non-printable character, so the literal is one line)."""
    return repr(text)


_SHORT_ESCAPES = {"\n": "\\n", "\r": "\\r", "\t": "\\t"}


def _escaped(text: str, quote: str) -> str:
    """``text`` with backslash, ``quote`` and every non-printable character escaped
    the Python/C way (printable non-ASCII text is kept, readable)."""
    out = []
    for ch in text:
        if ch == "\\" or ch == quote:
            out.append("\\" + ch)
        elif ch.isprintable():
            out.append(ch)
        elif ch in _SHORT_ESCAPES:
            out.append(_SHORT_ESCAPES[ch])
        elif ord(ch) < 0x100:
            out.append(f"\\x{ord(ch):02x}")
        elif ord(ch) < 0x10000:
            out.append(f"\\u{ord(ch):04x}")
        else:
            out.append(f"\\U{ord(ch):08x}")
    return "".join(out)


def _plain(text: str) -> bool:
    return text.isprintable() and not any(c in text for c in '\\"`') and "??" not in text


def comment(value: object) -> str:
    """Text for a one-line comment (C++ //, Python/CMake/TOML #): printed as is when
    it is plain (printable, no backslash, quote, backquote or ``??``), otherwise
    quoted with escapes, so that it can neither end the line, nor splice the next
    one (a C++ comment ending in a backslash), nor hold a control character.

    >>> comment("m/s"), comment("m\\n#x")
    ('m/s', '"m\\\\n#x"')
    """
    text = str(value)
    if _plain(text):
        return text
    return '"' + _escaped(text, '"').replace("??", "?\\?") + '"'


def py_docstring(text: str) -> str:
    """Text inside a triple-quoted Python docstring: the string value of the
    docstring holds exactly ``text`` (quotes and backslashes escaped, so that
    neither ``\"\"\"`` nor a trailing backslash can close it)."""
    return _escaped(text, '"')


_MD_SPECIAL = re.compile(r"([\\`*_{}\[\]#!|~])")


def md_text(text: str) -> str:
    """Text for Markdown (a paragraph or a table cell): Markdown punctuation
    backslash-escaped, ``<``, ``>`` and ``&`` as entities (no HTML), every
    non-printable character escaped, so that the text stays on its line and in
    its cell.

    >>> print(md_text("a|b <i>\\n"))
    a\\|b &lt;i&gt;\\\\n
    """
    text = _escaped(text, "") if not text.isprintable() else text
    text = text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")
    return _MD_SPECIAL.sub(r"\\\1", text)


def md_code(text: str) -> str:
    """An inline code span holding ``text``: fenced with one backquote more than
    the longest run inside it, ``|`` escaped (tables), non-printables escaped."""
    if not text.isprintable():
        text = _escaped(text, "")
    run = max((len(m) for m in re.findall(r"`+", text)), default=0)
    fence = "`" * (run + 1)
    pad = " " if text.startswith("`") or text.endswith("`") or run else ""
    return fence + pad + text.replace("|", "\\|") + pad + fence


def decimal(text: str) -> str:
    """A decimal number from the model (a period), checked: it is printed as a
    number literal, so it must be one."""
    from modd_model.numbers import is_decimal

    if not is_decimal(text):
        raise ValueError(f"not a decimal number: {text!r}")
    return text


def port(value: object) -> int:
    """A TCP port from the model, checked to be one."""
    if not isinstance(value, int) or isinstance(value, bool) or not 0 < value < 65536:
        raise ValueError(f"not a TCP port: {value!r}")
    return value


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


def xml_text(text: str) -> str:
    """Text for an XML element's content: ``&``, ``<``, ``>`` and quotes as
    entities, control characters refused (XML 1.0 cannot hold them).

    >>> xml_text('a<b & "c"')
    'a&lt;b &amp; &quot;c&quot;'
    """
    if any(ord(c) < 0x20 and c not in "\t\n\r" for c in text):
        raise ValueError(f"{text!r}: control characters cannot appear in XML")
    return html.escape(text, quote=True).replace("&#x27;", "&apos;")


FILTERS = {
    "cpp_type": cpp_type,
    "cpp_value_type": cpp_value_type,
    "py_type": py_type,
    "cpp_ident": cpp_ident,
    "py_ident": py_ident,
    "cpp_string": cpp_string,
    "py_string": py_string,
    "comment": comment,
    "py_docstring": py_docstring,
    "md_text": md_text,
    "md_code": md_code,
    "decimal": decimal,
    "port": port,
    "cpp_sample_literal": cpp_sample_literal,
    "period_ms": period_ms,
    "period_us": period_us,
    "to_json": to_json,
    "xml_text": xml_text,
}
