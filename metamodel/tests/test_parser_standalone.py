"""The .modd parser is lark's standalone LALR parser generated from modd.lark
(so that ``modd`` does not import lark nor build the tables at each start):
the committed module must be what the tool generates from the grammar now,
and it must parse as lark itself does."""

from __future__ import annotations

import hashlib
from pathlib import Path
from typing import Any

SRC = Path(__file__).resolve().parents[1] / "src" / "modd_model"
SCENARIOS = Path(__file__).resolve().parents[3] / "shared" / "scenarios"


def test_generated_parser_is_fresh() -> None:
    """The header names the grammar it was generated from (lark's output is
    not byte-for-byte reproducible, so its hash is what is compared)."""
    digest = hashlib.sha256((SRC / "modd.lark").read_bytes()).hexdigest()
    header = (SRC / "_modd_parser_gen.py").read_text(encoding="utf-8").splitlines()[:3]
    assert f"modd.lark sha256 {digest}" in "\n".join(header), (
        "modd.lark changed: regenerate _modd_parser_gen.py with the command in its header "
        "and put the grammar's new sha256 in it"
    )


def _shape(node: Any) -> Any:
    """A tree as plain data: rule names, tokens with their positions."""
    if isinstance(node, str) and hasattr(node, "type"):  # a Token
        tok: Any = node
        return (
            "token",
            tok.type,
            str(tok),
            tok.line,
            tok.column,
            tok.end_line,
            tok.end_column,
            tok.start_pos,
            tok.end_pos,
        )
    meta = node.meta
    return (
        str(node.data),
        [_shape(c) for c in node.children],
        (meta.line, meta.column, meta.end_line, meta.end_column) if not meta.empty else None,
    )


def test_standalone_parses_as_lark() -> None:
    from lark import Lark
    from modd_model.parser import _parser

    reference = Lark(
        (SRC / "modd.lark").read_text(encoding="utf-8"),
        parser="lalr",
        propagate_positions=True,
        maybe_placeholders=False,
    )
    texts = [p.read_text(encoding="utf-8") for p in sorted(SCENARIOS.glob("*.modd"))]
    texts += [
        p.read_text(encoding="utf-8")
        for p in sorted((Path(__file__).parent / "data").glob("*.modd"))
    ]
    assert len(texts) >= 3
    for text in texts:
        assert _shape(_parser().parse(text)) == _shape(reference.parse(text))
        assert [(t.type, str(t)) for t in _parser().lex(text, dont_ignore=True)] == [
            (t.type, str(t)) for t in reference.lex(text, dont_ignore=True)
        ]
