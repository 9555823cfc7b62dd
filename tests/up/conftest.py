"""What the `modd up` tests share: the `modd` command, free loopback ports,
and waiting for a line in a process's log."""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from pathlib import Path

import pytest
from modd.ports import free_port as _free_port

FreePort = Callable[[], int]
WaitFor = Callable[[Path, str, float], None]


@pytest.fixture(scope="session")
def modd_cmd() -> str:
    return str(Path(sys.executable).parent / "modd")


@pytest.fixture(scope="session")
def free_port() -> FreePort:
    return _free_port


@pytest.fixture(scope="session")
def wait_for() -> WaitFor:
    """Waits until ``text`` appears in the file at ``path``; fails with the file's content."""

    def wait(path: Path, text: str, timeout: float) -> None:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if path.exists() and text in path.read_text(errors="replace"):
                return
            time.sleep(0.1)
        content = path.read_text(errors="replace") if path.exists() else "(no log)"
        raise AssertionError(f"{text!r} never appeared in {path}:\n{content}")

    return wait
