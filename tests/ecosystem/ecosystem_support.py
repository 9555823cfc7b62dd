"""Ecosystem tests: other readers and viewers on MoDD's data (docs/ecosystem.md).
Node scripts run with the frontend's node_modules (npm devDependencies)."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

HERE = Path(__file__).parent
REPO = HERE.parents[1]
NODE_MODULES = REPO / "frontend" / "node_modules"
sys.path.insert(0, str(REPO / "tests" / "runtime"))


def node_json(script: str, *args: str, timeout: float = 60.0) -> Any:
    """Runs ``node HERE/script args`` and parses the JSON it prints last."""
    node = shutil.which("node")
    if node is None or not (NODE_MODULES / "@mcap" / "core").is_dir():
        # make test installs both (scripts/setup.sh): missing is a setup bug, not a skip
        pytest.fail("node or the frontend's npm packages are missing (run scripts/setup.sh)")
    env = dict(os.environ, NODE_PATH=str(NODE_MODULES))
    version = subprocess.run([node, "--version"], capture_output=True, text=True, check=True)
    major = int(version.stdout.strip().lstrip("v").split(".")[0])
    flags = ["--experimental-websocket"] if major < 22 else []  # global WebSocket from 22 on
    proc = subprocess.run(
        [node, *flags, str(HERE / script), *args],
        capture_output=True,
        text=True,
        timeout=timeout,
        env=env,
        check=False,
    )
    if proc.returncode != 0:
        raise AssertionError(f"{script} failed ({proc.returncode}): {proc.stderr[-2000:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def foxglove_links(base: str, user: str, password: str) -> dict[str, Any]:
    """The workbench's Foxglove URLs (each with a single-use ticket) for ``user``."""
    import httpx2 as httpx

    token = httpx.post(
        f"{base}/api/auth/login", json={"username": user, "password": password}, timeout=30
    ).json()["token"]
    r = httpx.post(
        f"{base}/api/foxglove/links", headers={"Authorization": f"Bearer {token}"}, timeout=30
    )
    assert r.status_code == 200, r.text
    out: dict[str, Any] = r.json()
    return out
