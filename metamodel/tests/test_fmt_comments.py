"""`modd fmt` keeps comments: every comment of every .modd and .collector file
of the repository survives, the model is unchanged and a second run changes
nothing; comments put at any line of a canonical text (own line or end of a
line) are exactly where they were after formatting."""

from __future__ import annotations

from collections import Counter
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from modd_model import parse_text
from modd_model.comments import INDENT, comments_of, keep_comments
from modd_model.io import decode
from modd_model.printer import print_model

REPO = Path(__file__).resolve().parents[2]
CORPUS_DIRS = ("metamodel", "tests", "generators", "runtime", "docs", "backend")
CORPUS = sorted(
    p
    for d in CORPUS_DIRS
    for ext in ("*.modd", "*.collector")
    for p in (REPO / d).rglob(ext)
    if "node_modules" not in p.parts
)


def fmt(text: str) -> str:
    doc, smap = parse_text(text)
    return keep_comments(text, smap, print_model(doc))


def _text(path: Path) -> str:
    text, _ = decode(path.read_bytes(), str(path))
    assert text is not None
    return text


def _comment_texts(text: str) -> Counter[str]:
    return Counter(c.text for c in comments_of(text))


def test_the_corpus_has_commented_files() -> None:
    commented = [p for p in CORPUS if comments_of(_text(p))]
    assert len(CORPUS) >= 8 and len(commented) >= 3, CORPUS


@pytest.mark.parametrize("path", CORPUS, ids=lambda p: str(p.relative_to(REPO)))
def test_fmt_keeps_every_comment_of_the_corpus(path: Path) -> None:
    text = _text(path)
    out = fmt(text)
    assert _comment_texts(out) == _comment_texts(text)
    assert parse_text(out)[0] == parse_text(text)[0]
    assert fmt(out) == out  # idempotent


def _with_comments(canonical: str, picks: list[tuple[int, bool, bool]]) -> str:
    """``canonical`` with a comment per pick (line, own line or trailing, line
    or block comment) placed where the canonical form puts comments."""
    lines = canonical.splitlines()
    before: dict[int, list[str]] = {}
    after: dict[int, list[str]] = {}
    for n, (line, own, block) in enumerate(picks):
        text = f"/* note {n} */" if block else f"// note {n}"
        if own or line == len(lines):
            at = lines[line] if line < len(lines) else ""
            indent = at[: len(at) - len(at.lstrip())]
            if at.lstrip().startswith("}"):  # the last thing inside a block
                indent += INDENT
            before.setdefault(line, []).append(indent + text)
        else:
            after.setdefault(line, []).append(text)
    out: list[str] = []
    for i in range(len(lines) + 1):
        out += before.get(i, [])
        if i < len(lines):
            out.append(" ".join([lines[i], *after.get(i, [])]))
    return "\n".join(out) + "\n"


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from(CORPUS), st.data())
def test_comments_stay_where_they_were(path: Path, data: st.DataObject) -> None:
    canonical = print_model(parse_text(_text(path))[0])
    n_lines = len(canonical.splitlines())
    picks = data.draw(
        st.lists(
            st.tuples(st.integers(0, n_lines), st.booleans(), st.booleans()), min_size=1, max_size=6
        )
    )
    commented = _with_comments(canonical, picks)
    assert fmt(commented) == commented
    assert parse_text(commented)[0] == parse_text(canonical)[0]
