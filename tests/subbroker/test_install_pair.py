"""Pairing a freshly installed drone (issue 43, item 4), with the amd64 `modd-drone`
of `make package` in a clean Debian root (as the install test, test_install_root.py):
installed offline, nothing configured; a bundle the workbench's own code makes
(modd_backend.pairing.make_bundle, the Deploy panel's) is imported with the installed
`/usr/bin/modd-pair` as root (a copy with one byte flipped refused first, nothing
written); the files are the service user's where secret (link.key 0600 `modd`); the
installed PubBroker then runs as `modd` from /etc/modd alone, links up with a
SubBroker that reads the link key the workbench kept, and acknowledges a signed
deploy. Run with `make package-test`; skips when the package is not built."""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

import pytest
from modd.subbroker.client import request
from modd.zenoh_session import wait_connected
from modd_backend.pairing import make_bundle
from modd_model import load_model
from subbroker_harness import (
    SCENARIOS,
    SUBBROKER,
    Proc,
    free_port,
    model_copy,
    processes,
    signed,
    subbroker_config,
    wait_port,
)
from test_install_root import as_modd, fresh_root, in_root, install_offline, modd_ids, ok

pytestmark = [pytest.mark.e2e, pytest.mark.slow]


def paired_model(tmp: Path, link: int) -> tuple[dict[str, Any], Path]:
    """Scenario 1 flown by the installed drone: its link on a free port, its archive and
    ingress socket where the units may write (/var/lib/modd)."""
    model = load_model(model_copy(tmp, "scenario1.modd"))
    broker = model["pubBroker"]
    broker["endpoint"] = {"host": "127.0.0.1", "port": link}
    broker["logPath"] = "/var/lib/modd/archive"
    broker["ingress"] = {**broker.get("ingress", {}), "unixSocket": "/var/lib/modd/ingress.sock"}
    path = tmp / "paired.json"
    path.write_text(json.dumps(model))
    return model, path


def test_a_freshly_installed_drone_pairs_then_acks_a_deploy(
    tmp_path: Path, zenoh_client: Any
) -> None:
    drone = fresh_root(tmp_path, "drone", "modd-drone")
    print(install_offline(drone, "modd-drone"))
    uid, _ = modd_ids(drone)
    assert not (drone / "etc/modd/pubbroker.json").exists()  # nothing configured yet
    link, zport = free_port(), free_port()
    model, model_path = paired_model(tmp_path, link)
    made = make_bundle(model, tmp_path / "station" / "station.key", tmp_path / "station" / "keys")
    (drone / "tmp" / "code").write_text(made.code + "\n")
    bad = bytearray(made.data)
    bad[len(bad) // 2] ^= 0x10
    (drone / "tmp" / "tampered.modd-pair").write_bytes(bytes(bad))
    refused = in_root(
        drone,
        "/usr/bin/modd-pair",
        "/tmp/tampered.modd-pair",
        "--code-file",
        "/tmp/code",
        net=False,
    )
    assert refused.returncode == 1 and "altered" in refused.stderr, refused
    assert not (drone / "etc/modd/pubbroker.json").exists()
    (drone / "tmp" / made.filename).write_bytes(made.data)
    out = ok(
        in_root(
            drone,
            "/usr/bin/modd-pair",
            f"/tmp/{made.filename}",
            "--code-file",
            "/tmp/code",
            net=False,
        )
    )
    assert "owner modd" in out and made.bundle.fingerprint in out, out
    key = (drone / "etc/modd/link.key").stat()
    assert (key.st_mode & 0o777, key.st_uid) == (0o600, uid)
    assert made.code not in out and made.link_key_file.read_text().strip() not in out
    ok(in_root(drone, "/bin/chown", "-R", "modd:modd", "/var/lib/modd"))

    pb = as_modd(
        drone, tmp_path, "pb", "/usr/bin/modd-pubbroker", "--config", "/etc/modd/pubbroker.json"
    )
    with processes(pb):
        wait_port(link, 20)
        config = subbroker_config(tmp_path, model_path, link, zport)
        sb = Proc(
            "sb",
            [*SUBBROKER, "--config", str(config), "--key", f"file:{made.link_key_file}"],
            tmp_path / "sb.log",
            env={"MODD_LINK_KEY": "not-the-paired-key-at-all"},
        )
        with processes(sb):
            wait_port(zport, 60)
            session = zenoh_client(zport)
            assert wait_connected(session)
            assert sb.wait_log("config 1 running", 60), sb.log() + pb.log()
            s2 = (SCENARIOS / "scenario2.modd").read_text()
            reply = request(session, "modd/usv/deploy", signed({"text": s2, "filename": "s2.modd"}))
            time.sleep(0.5)
    assert reply["status"] == "ACKED" and reply["config_id"] == 2, (reply, sb.log())
    assert "config 2 accepted" in pb.log(), pb.log()
