"""Generated files say so in their name (docs/architecture.md, "Decisions"):
``*_gen.py``, ``*.gen.ts``, ``*.gen.hpp``. Every code file the one typegen
writes carries the suffix, and no other file of the sources carries a
generated header without it."""

from __future__ import annotations

from pathlib import Path

from modd_contracts import typegen

REPO = Path(__file__).resolve().parents[2]
SUFFIXES = {".py": "_gen.py", ".ts": ".gen.ts", ".hpp": ".gen.hpp"}
#: Where hand-written and generated code live side by side.
SOURCES = (
    "metamodel/src",
    "runtime/python/src",
    "runtime/cpp/include",
    "runtime/cpp/src",
    "backend/src",
    "generators/src",
    "launcher/src",
    "frontend/src",
)


def _marked(name: str) -> bool:
    return any(name.endswith(s) for s in SUFFIXES.values())


def test_every_generated_code_file_is_named_so() -> None:
    code = [p for p in typegen.OUTPUTS.values() if p.suffix in SUFFIXES]
    assert len(code) >= 10
    unmarked = [str(p.relative_to(REPO)) for p in code if not _marked(p.name)]
    assert not unmarked, f"generated without the suffix: {unmarked}"


def test_no_unmarked_file_says_it_is_generated() -> None:
    found = []
    for root in SOURCES:
        for path in (REPO / root).rglob("*"):
            if path.suffix not in SUFFIXES or "node_modules" in path.parts or _marked(path.name):
                continue
            # a generated file's header opens it (three lines at most)
            head = "\n".join(path.read_text(encoding="utf-8", errors="replace").splitlines()[:3])
            if "Generated" in head and "not edit" in head:
                found.append(str(path.relative_to(REPO)))
    assert not found, f"a generated header in a file not named *_gen / *.gen: {found}"
