"""Pairing, across processes: the operator's bundle from a running workbench
(``modd-backend``), imported with ``modd-pair`` into a fresh configuration
directory; the C++ PubBroker started from those files alone links up with the
base station's SubBroker (which reads the link key the workbench kept for
that drone) and acknowledges a deploy from the workbench. A tampered copy and
a wrong code are refused by ``modd-pair`` and write nothing."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from modd_model import load_model

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from support.loopback import (  # noqa: E402
    DEMO,
    PUBBROKER,
    VENV_BIN,
    Proc,
    free_port,
    router_and_watch,
    start_client_subbroker,
    start_signed_in_backend,
    started,  # noqa: F401  (the fixture)
    wait_port,
)

ADMIN_PASSWORD = "pairing-admin-password"


def mission(tmp: Path, link: int) -> dict[str, Any]:
    """The demo mission with its link on a free port and its files under ``tmp``."""
    model = load_model(DEMO)
    broker = model["pubBroker"]
    broker["endpoint"]["port"] = link
    broker["logPath"] = str(tmp / "drone-archive")
    broker["ingress"] = {**broker.get("ingress", {}), "unixSocket": str(tmp / "ingress.sock")}
    return model


def modd_pair(bundle: Path, config_dir: Path, code: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [
            str(VENV_BIN / "modd-pair"),
            str(bundle),
            "--config-dir",
            str(config_dir),
            "--code-file",
            "-",
        ],
        input=code + "\n",
        capture_output=True,
        text=True,
        timeout=60,
    )


def refusals(tmp: Path, bundle: bytes, code: str) -> None:
    """A byte flipped in the middle, and the wrong code: refused, nothing written."""
    bad = bytearray(bundle)
    bad[len(bad) // 2] ^= 0x01
    (tmp / "tampered.modd-pair").write_bytes(bytes(bad))
    r = modd_pair(tmp / "tampered.modd-pair", tmp / "tampered-etc", code)
    assert r.returncode == 1 and "altered" in r.stderr, r
    wrong = "Z" * 20 if code[0] != "Z" else "Y" * 20
    r = modd_pair(tmp / "usv.modd-pair", tmp / "wrong-etc", wrong)
    assert r.returncode == 1 and "wrong pairing code" in r.stderr, r
    assert not (tmp / "tampered-etc").exists() and not (tmp / "wrong-etc").exists()


@pytest.mark.timeout(120)
def test_a_paired_drone_acknowledges_the_workbench_s_deploy(
    tmp_path: Path,
    started: list[Proc],  # noqa: F811
) -> None:
    link = free_port()
    with router_and_watch() as (router, watch):
        backend = start_signed_in_backend(tmp_path, router, ADMIN_PASSWORD, started)
        model = mission(tmp_path, link)
        r = backend.request("POST", "/projects", json={"name": "paired", "model": {"model": model}})
        assert r.status_code == 201, r.text
        project = r.json()["id"]
        made = backend.request("POST", f"/projects/{project}/pairing", json={})
        assert made.status_code == 200, made.text
        assert made.headers["cache-control"] == "no-store"
        pairing = made.json()
        bundle = pairing["bundle"].encode()
        (tmp_path / "usv.modd-pair").write_bytes(bundle)
        refusals(tmp_path, bundle, pairing["code"])

        etc = tmp_path / "fresh-etc"
        imported = modd_pair(tmp_path / "usv.modd-pair", etc, pairing["code"])
        assert imported.returncode == 0, imported.stderr
        assert pairing["fingerprint"] in imported.stdout
        assert "systemctl restart" in imported.stdout
        assert (etc / "link.key").stat().st_mode & 0o777 == 0o600
        # the drone runs from what the bundle wrote, and nothing else
        started.append(
            Proc(
                "pubbroker",
                [str(PUBBROKER), "--config", str(etc / "pubbroker.json")],
                tmp_path / "pubbroker.log",
                env={"MODD_LINK_KEY": "not-the-paired-key"},
            )
        )
        wait_port(link, 10.0)
        station_model = tmp_path / "station-model.json"
        station_model.write_text(json.dumps(model))
        started.append(
            start_client_subbroker(
                tmp_path, "subbroker", station_model, link, pairing["link_key_file"], router
            )
        )
        watch.wait("usv", lambda s: s["link"] == "up" and s["config_id"], 30)
        r = backend.request("POST", f"/projects/{project}/deployments", json={})
        assert r.status_code == 201, r.text
        record = r.json()
        assert record["status"] == "acked", record
        config_id = record["reply"]["config_id"]
        watch.wait("usv", lambda s: s["config_id"] == config_id, 10)
        for p in started:
            assert p.alive(), f"{p.name} died:\n{p.log()}"
        logs = "".join(p.log() for p in started)
        key = (etc / "link.key").read_text().strip()
        for secret in (pairing["code"], key):
            assert secret not in logs
