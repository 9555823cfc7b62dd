"""``modd-backend backup`` and ``restore``: a consistent copy of the store
while the service runs, and putting one back (docs/operations.md, "Backing up
the store and the archives").

SQLite: the online backup API (a consistent snapshot even while backends
write; restoring writes the copy into the live file the same way, under
SQLite's own locks). PostgreSQL: ``pg_dump --format=custom`` and
``pg_restore --clean``; the password travels in ``PGPASSWORD``, never in argv.

    modd-backend backup --data ./data store.backup
    modd-backend restore --data ./data store.backup
"""

from __future__ import annotations

import argparse
import os
import shutil
import sqlite3
import subprocess
import sys
from pathlib import Path

from sqlalchemy.engine import make_url

from .db import sqlite_path
from .settings import Settings


def _pg_command(tool: str, url: str) -> tuple[list[str], dict[str, str]]:
    """The libpq form of a SQLAlchemy URL, without its password (in the environment)."""
    u = make_url(url)
    env = dict(os.environ)
    if u.password:
        env["PGPASSWORD"] = str(u.password)
    conn = u.set(drivername="postgresql", password=None).render_as_string(hide_password=False)
    exe = shutil.which(tool)
    if exe is None:
        raise SystemExit(f"modd-backend: {tool} not found (apt-get install postgresql-client)")
    return [exe, "--dbname", conn], env


def backup(url: str, out: Path) -> None:
    """Write a consistent copy of the store at ``url`` to ``out`` (replaced atomically)."""
    tmp = out.with_name(f".{out.name}.tmp")
    path = sqlite_path(url)
    try:
        if path is not None:
            if not path.exists():
                raise SystemExit(f"modd-backend: no database at {path}")
            with sqlite3.connect(path) as src, sqlite3.connect(tmp) as dst:
                src.backup(dst)
            # sqlite3's context manager commits but does not close
            src.close()
            dst.close()
        elif url.startswith("postgresql"):
            cmd, env = _pg_command("pg_dump", url)
            subprocess.run([*cmd, "--format=custom", "--file", str(tmp)], env=env, check=True)
        else:
            raise SystemExit(f"modd-backend: cannot back up {make_url(url).drivername}")
        os.chmod(tmp, 0o600)
        os.replace(tmp, out)
    finally:
        tmp.unlink(missing_ok=True)


def restore(url: str, src: Path) -> None:
    """Put the copy ``src`` back into the store at ``url`` (its contents replaced)."""
    if not src.is_file():
        raise SystemExit(f"modd-backend: no backup at {src}")
    path = sqlite_path(url)
    if path is not None:
        path.parent.mkdir(parents=True, exist_ok=True)
        with sqlite3.connect(src) as copy, sqlite3.connect(path) as live:
            copy.backup(live)
        copy.close()
        live.close()
    elif url.startswith("postgresql"):
        cmd, env = _pg_command("pg_restore", url)
        subprocess.run([*cmd, "--clean", "--if-exists", "--no-owner", "--single-transaction",
                        str(src)], env=env, check=True)
    else:
        raise SystemExit(f"modd-backend: cannot restore {make_url(url).drivername}")


def main(argv: list[str]) -> int:
    """``modd-backend backup|restore [--data DIR] [--database-url URL] FILE``."""
    command, rest = argv[0], argv[1:]
    p = argparse.ArgumentParser(prog=f"modd-backend {command}",
                                description=f"{command} the workbench's store")
    p.add_argument("--data", type=Path, default=Path("data"), help="data directory")
    p.add_argument("--database-url", default=os.environ.get("MODD_DATABASE_URL"),
                   help="SQLAlchemy URL (default: $MODD_DATABASE_URL, else SQLite in --data)")
    p.add_argument("file", type=Path, help="the backup file")
    a = p.parse_args(rest)
    url = Settings(data_dir=a.data, database_url=a.database_url).effective_database_url
    try:
        (backup if command == "backup" else restore)(url, a.file)
    except subprocess.CalledProcessError as exc:
        print(f"modd-backend: {command} failed: {exc}", file=sys.stderr)
        return 1
    print(f"modd-backend: {command} {'to' if command == 'backup' else 'from'} {a.file}: done")
    return 0
