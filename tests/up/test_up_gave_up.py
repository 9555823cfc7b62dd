"""`modd up` gives up a run and says why: `watch` tells which process, its exit
code, the reason and its log; `modd up` puts it on the zenoh status as a status
document of the contract (status.schema.json), link `stopped`."""

from __future__ import annotations

import json
from pathlib import Path

from modd.supervise import watch
from modd_contracts.schema import validate
from modd_launch.announce import stopped_status


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
