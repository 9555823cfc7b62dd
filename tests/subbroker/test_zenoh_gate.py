"""One source churning connections to the SubBroker's zenoh port does not keep a viewer
from another source out (issue 38, docs/security.md "Connections per source"): while
127.0.0.2 opens thousands of connections that never authenticate (closed at once, or
2,500 held), a viewer from 127.0.0.1 opens a session and receives a live value within
2 s, again and again; the churner is refused by the SubBroker's accept gate, which logs
it, and the SubBroker holds no more file descriptors after than before. Against the real
PubBroker and SubBroker CLI."""

from __future__ import annotations

import os
import threading
import time
from pathlib import Path

import pytest
from churn import Churner
from modd.zenoh_session import client_settings, open_session
from subbroker_harness import scenario1_running, shared_credentials

pytestmark = pytest.mark.usefixtures("needs_pubbroker")

ROUNDS = 6  # viewer sessions at least
THREADS = int(os.environ.get("MODD_CHURN_THREADS", "4"))
CHURN = 2500
MIN_CHURN_S = 15.0
REFUSALS: list[
    str
] = []  # what viewers were told  # connections the churner opens at least, meanwhile


def viewer_value_in(port: int, timeout_s: float = 10.0) -> float:
    """Seconds from opening a viewer's session to its first live value (or timeout_s)."""
    cred = shared_credentials().cred_file("viewer")
    got = threading.Event()
    start = time.monotonic()
    try:
        session = open_session(
            client_settings(f"tcp/127.0.0.1:{port}", cred), busy_wait_s=timeout_s
        )
    except ValueError as exc:
        REFUSALS.append(str(exc))
        return timeout_s
    try:
        session.declare_subscriber("modd/usv/sub/**", lambda _s: got.set())
        got.wait(max(0.0, timeout_s - (time.monotonic() - start)))
        return time.monotonic() - start if got.is_set() else timeout_s
    finally:
        session.close()  # type: ignore[no-untyped-call]


def fds(pid: int) -> int:
    return len(os.listdir(f"/proc/{pid}/fd"))


def run(tmp_path: Path, gate: bool, hold: int) -> tuple[list[float], Churner, int, str]:
    """Viewer open times under churn, the churner, fds after minus before, the log."""
    REFUSALS.clear()
    off = "" if gate else "[zenoh.gate]\nenabled = false\n"
    with scenario1_running(tmp_path, 120, config_extra=off) as station:
        sb, pb, zport = station.sb, station.pb, station.port
        assert viewer_value_in(zport) < 2.0, "no live value before the churn"
        time.sleep(0.5)
        before = fds(sb.pid)
        with Churner(zport, hold=hold, threads=THREADS) as churner:
            time.sleep(1.0)
            took: list[float] = []
            start = time.monotonic()
            while (
                len(took) < ROUNDS
                or time.monotonic() - start < MIN_CHURN_S
                or (churner.opened < CHURN and time.monotonic() - start < 90)
            ):
                took.append(viewer_value_in(zport))
        time.sleep(3.0)  # the last ones held past the accept timeout are closed
        after = fds(sb.pid)
        assert sb.alive() and pb.alive()
        return took, churner, after - before, sb.log()


@pytest.mark.parametrize("hold", [0, 2500], ids=["open-close", "held"])
def test_a_churning_source_does_not_keep_a_viewer_out(tmp_path: Path, hold: int) -> None:
    took, churner, leaked, log = run(tmp_path, gate=True, hold=hold)
    print(
        f"hold {hold}: viewer value in {[round(t, 3) for t in took]} s; churner opened "
        f"{churner.opened}, refused {churner.refused}, errors {churner.errors}; fds {leaked:+d}"
    )
    assert churner.opened >= 2000, f"the churner opened only {churner.opened}"
    assert max(took) < 2.0, f"viewer value times under churn: {took}"
    assert churner.refused > 0 and churner.reasons, "the gate never refused the churner"
    assert "zenoh gate at" in log and "refusing connections from 127.0.0.2" in log
    assert leaked <= 4, f"the SubBroker holds {leaked} more file descriptors after the churn"


@pytest.mark.slow
def test_without_the_gate_for_comparison(tmp_path: Path) -> None:
    """The same churn against the bare zenoh listener (``[zenoh.gate] enabled = false``):
    the figures of docs/reliability.md. A viewer zenoh turns away is told the real reason
    (was: that its credentials were refused)."""
    took, churner, leaked, _ = run(tmp_path, gate=False, hold=2500)
    print(
        f"no gate: viewer value in {[round(t, 3) for t in took]} s; churner opened "
        f"{churner.opened}; fds {leaked:+d}; viewers told {REFUSALS}"
    )
    assert not any("refused the credentials" in said for said in REFUSALS), REFUSALS
