"""Tables for the terminal, in Markdown so that docs/benchmarks.md can take them as they
are printed."""

from __future__ import annotations

from collections.abc import Sequence


def table(header: Sequence[str], rows: Sequence[Sequence[object]]) -> str:
    """A Markdown table; columns whose cells are all numbers are right-aligned."""
    cells = [[str(h) for h in header]] + [[fmt(c) for c in r] for r in rows]
    widths = [max(len(r[i]) for r in cells) for i in range(len(header))]
    right = [all(numeric(r[i]) for r in cells[1:]) for i in range(len(header))]

    def line(r: list[str]) -> str:
        return (
            "| "
            + " | ".join(
                c.rjust(w) if right[i] else c.ljust(w)
                for i, (c, w) in enumerate(zip(r, widths, strict=True))
            )
            + " |"
        )

    sep = (
        "| "
        + " | ".join(("-" * (w - 1) + ":" if right[i] else "-" * w) for i, w in enumerate(widths))
        + " |"
    )
    return "\n".join([line(cells[0]), sep, *(line(r) for r in cells[1:])])


def numeric(cell: str) -> bool:
    return cell in ("", "—") or cell[0].isdigit() or cell[0] == "-" and cell[1:2].isdigit()


def fmt(x: object) -> str:
    if isinstance(x, float):
        if x != x:
            return "—"
        if abs(x) >= 1000:
            return f"{x:,.0f}"
        if abs(x) >= 100:
            return f"{x:.1f}"
        return f"{x:.2f}"
    if isinstance(x, int) and not isinstance(x, bool):
        return f"{x:,}"
    return str(x)


def ratio(a: float, b: float) -> str:
    return f"{a / b:.2f}×" if b else "—"
