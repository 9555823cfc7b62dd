"""Restoring a PostgreSQL backup without running anything from it.

A ``pg_dump`` archive is SQL text: handed to ``pg_restore --dbname`` it runs
whatever its author wrote (a function, a materialised view whose refresh
calls ``COPY ... FROM PROGRAM``: commands on the database server, as its OS
user, when the restoring role is a superuser). So the archive never reaches
the database: ``pg_restore --data-only --file -`` turns it into text (no
connection), :func:`parse_dump` reads that text and refuses anything but the
rows of this project's tables (their columns, known names only) and the
values of their sequences, and :func:`load` writes those rows with ``COPY
... FROM STDIN`` statements built here, in one transaction: every table
emptied, the rows copied, the sequences set, every session removed.

>>> dump = parse_dump("SET lock_timeout = 0;\\nCOPY public.users (id, username) FROM stdin;\\n"
...     "1\\tann\\n\\\\.\\nSELECT pg_catalog.setval('public.users_id_seq', 1, true);\\n")
>>> dump.rows["users"], dump.sequences
((['id', 'username'], ['1\\tann']), [('users_id_seq', 1, True)])
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Any

_COPY = re.compile(r"COPY public\.([a-z_]+) \(([a-z_, ]+)\) FROM stdin;")
_SETVAL = re.compile(r"SELECT pg_catalog\.setval\('public\.([a-z_]+)', ([0-9]+), (true|false)\);")
#: Lines of pg_restore's data-only text read and ignored (settings, comments).
_HARMLESS = re.compile(
    r"(--.*|SET [a-z_]+ = [A-Za-z0-9_' .-]*;"
    r"|SELECT pg_catalog\.set_config\('search_path', '', false\);"
    r"|\\(un)?restrict [A-Za-z0-9]+|)"
)


class DumpRefused(ValueError):
    """The archive holds more than this project's rows (the message says what)."""


def _tables() -> dict[str, list[str]]:
    """Table name -> column names of this project's store (dependency order)."""
    from .tables import Base

    return {t.name: [c.name for c in t.columns] for t in Base.metadata.sorted_tables}


@dataclass
class Dump:
    rows: dict[str, tuple[list[str], list[str]]] = field(default_factory=dict)
    sequences: list[tuple[str, int, bool]] = field(default_factory=list)


def parse_dump(text: str) -> Dump:
    """The rows and sequence values of a data-only dump's text, or
    DumpRefused at the first line that is anything else."""
    tables, out = _tables(), Dump()
    lines = iter(enumerate(text.split("\n"), 1))
    for n, line in lines:
        if (m := _COPY.fullmatch(line)) is not None:
            table, columns = m[1], [c.strip() for c in m[2].split(",")]
            if table == "alembic_version":
                _skip_copy(lines)
                continue
            if table not in tables or not set(columns) <= set(tables[table]):
                raise DumpRefused(
                    f"line {n}: rows of {table!r} ({', '.join(columns)}) are "
                    "not of this workbench's tables"
                )
            out.rows[table] = (columns, _copy_rows(lines))
        elif (s := _SETVAL.fullmatch(line)) is not None:
            known = {f"{t}_{c}_seq" for t, cs in tables.items() for c in cs}
            if s[1] not in known:
                raise DumpRefused(f"line {n}: sequence {s[1]!r} is not of this workbench")
            out.sequences.append((s[1], int(s[2]), s[3] == "true"))
        elif not _HARMLESS.fullmatch(line):
            raise DumpRefused(f"line {n}: {line[:80]!r} is not data of this workbench's tables")
    return out


def _copy_rows(lines: Any) -> list[str]:
    rows: list[str] = []
    for _n, line in lines:
        if line == "\\.":
            return rows
        rows.append(line)
    raise DumpRefused("the archive ends inside a table's rows")


def _skip_copy(lines: Any) -> None:
    _copy_rows(lines)


def load(conn: Any, dump: Dump) -> None:
    """Replace the store's rows by the dump's, on a psycopg connection, in
    one transaction (the caller commits); no session survives."""
    from psycopg import sql

    tables = [t for t in _tables() if t != "alembic_version"]
    with conn.cursor() as cur:
        cur.execute(
            sql.SQL("TRUNCATE {} RESTART IDENTITY").format(
                sql.SQL(", ").join(sql.Identifier(t) for t in tables)
            )
        )
        for table in tables:
            if table not in dump.rows:
                continue
            columns, rows = dump.rows[table]
            stmt = sql.SQL("COPY {} ({}) FROM STDIN").format(
                sql.Identifier(table), sql.SQL(", ").join(sql.Identifier(c) for c in columns)
            )
            with cur.copy(stmt) as copy:
                for row in rows:
                    copy.write(row.encode("utf-8") + b"\n")
        for name, value, called in dump.sequences:
            cur.execute("SELECT setval(%s::regclass, %s, %s)", (name, value, called))
        cur.execute("DELETE FROM sessions")
