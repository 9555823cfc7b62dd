"""`modd up` gives up a run and says why: `watch` tells which process, its exit
code, the reason and its log; `modd up` puts it on the zenoh status as a status
document of the contract (status.schema.json), link `stopped`."""

from __future__ import annotations

import json
import threading
import time
from pathlib import Path

import pytest
from modd.ports import free_port
from modd.supervise import watch
from modd.zenoh_auth import CredentialStore
from modd.zenoh_session import client_settings, open_session
from modd_contracts.schema import validate
from modd_launch.announce import announce_stop, settings_for, stopped_status


def test_giving_up_says_which_process_and_why_in_a_status_of_the_contract() -> None:
    """What `modd up` puts on the zenoh status when it gives up (launcher's announce)."""
    told: list[dict[str, object]] = []

    class Dies:
        name, log, restartable = "subbroker", Path("/tmp/sb.log"), True

        def start(self, env: dict[str, str]) -> None: ...

        def exit_code(self) -> int | None:
            return 1

        def pid(self) -> int | None:
            return 7

    now = [0.0]

    def sleep(s: float) -> None:
        now[0] += s

    code = watch(
        [Dies()],
        {},
        lambda: False,
        say=lambda _l: None,
        clock=lambda: now[0],
        sleep=sleep,
        gave_up=told.append,
    )
    assert code == 1 and len(told) == 1
    (info,) = told
    assert info["process"] == "subbroker" and info["exit_code"] == 1
    assert "5 restarts within 300 s" in str(info["reason"]) and info["log"] == "/tmp/sb.log"
    doc = stopped_status("usv", info)
    assert validate("status", json.loads(json.dumps(doc))) == []
    assert doc["link"] == "stopped" and doc["supervisor"] == info


@pytest.mark.e2e
def test_a_viewer_gets_the_stopped_status_where_the_subbroker_was(tmp_path: Path) -> None:
    """The SubBroker is gone; `modd up` opens a router on its endpoint with its
    credentials and puts the stopped status: a viewer (its own credentials) gets it."""
    store = CredentialStore(tmp_path)
    store.ensure()
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    info = {
        "state": "GAVE_UP",
        "process": "pubbroker",
        "exit_code": 1,
        "reason": "r",
        "log": "/tmp/pb.log",
        "at_ns": 1,
    }
    args = (settings_for([endpoint], []), store, "usv", info, 3.0)
    told = threading.Thread(target=announce_stop, args=args)
    told.start()
    time.sleep(0.5)
    got: list[dict[str, object]] = []
    viewer = open_session(client_settings(endpoint, store.cred_file("viewer")))
    viewer.declare_subscriber(
        "modd/usv/status", lambda s: got.append(json.loads(s.payload.to_bytes()))
    )
    told.join()
    viewer.close()  # type: ignore[no-untyped-call]
    assert got and got[-1]["supervisor"] == info and got[-1]["link"] == "stopped"
    assert validate("status", got[-1]) == []
