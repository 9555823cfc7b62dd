"""A throw-away PostgreSQL server on a loopback port (Debian's postgresql
package, as backend/tests/test_postgres.py starts it): ``with local_postgres()
as url:`` gives a SQLAlchemy URL; the server and its directory are gone after."""

from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from modd.ports import free_port


def _as_postgres(cmd: list[str]) -> list[str]:
    """initdb refuses to run as root: run as the package's ``postgres`` user."""
    return ["runuser", "-u", "postgres", "--", *cmd] if os.geteuid() == 0 else cmd


@contextmanager
def local_postgres() -> Iterator[str]:
    bins = sorted(Path("/usr/lib/postgresql").glob("*/bin"))
    if not bins or not (bins[-1] / "initdb").exists():
        raise SystemExit("PostgreSQL server binaries are missing: run make setup")
    root = Path(tempfile.mkdtemp(prefix="modd-pg-bench-"))
    if os.geteuid() == 0:
        shutil.chown(root, "postgres")
    data, port = root / "data", free_port()
    initdb = [str(bins[-1] / "initdb"), "-D", str(data), "-U", "modd", "--auth=trust", "-E", "UTF8"]
    subprocess.run(_as_postgres(initdb), check=True, capture_output=True)
    ctl = str(bins[-1] / "pg_ctl")
    opts = f"-h 127.0.0.1 -p {port} -k {root} -c max_connections=200"
    start = [ctl, "-D", str(data), "-o", opts, "-w", "-l", str(root / "pg.log"), "start"]
    subprocess.run(_as_postgres(start), check=True, capture_output=True)
    try:
        yield f"postgresql+psycopg://modd@127.0.0.1:{port}/postgres"
    finally:
        stop = [ctl, "-D", str(data), "-m", "fast", "-w", "stop"]
        subprocess.run(_as_postgres(stop), capture_output=True)
        shutil.rmtree(root, ignore_errors=True)
