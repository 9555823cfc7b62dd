"""A client the SubBroker's zenoh router turns away is told why in its own
words: credentials are needed (or these were refused) and where `make run` and
`modd up` keep a viewer's, not zenoh's "Unable to connect to any of [...]" with
a Rust source path. Against a real router with the SubBroker's authentication
and access control (an in-process zenoh session listening on loopback), and
through the CLI (`modd backfill`) as a user runs it."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from modd.zenoh_auth import Credentials, CredentialStore
from modd.zenoh_session import client_settings, open_session


def _refused(endpoint: str, who: Credentials | None) -> str:
    with pytest.raises(ValueError) as info:
        open_session(client_settings(endpoint, who))
    return str(info.value)


def test_no_credentials_says_they_are_needed_and_where(
    router: tuple[str, CredentialStore, Any],
) -> None:
    endpoint, _, _ = router
    said = _refused(endpoint, None)
    assert f"the router at {endpoint} needs credentials and none were given" in said
    assert "data/credentials/viewer.cred" in said and "--credentials" in said
    assert "Unable to connect" not in said and ".rs:" not in said


def test_wrong_credentials_are_named(router: tuple[str, CredentialStore, Any]) -> None:
    endpoint, _, _ = router
    said = _refused(endpoint, Credentials("viewer", "not-the-password"))
    assert "refused the credentials of user 'viewer'" in said and "viewer.cred" in said


def test_nothing_listening_is_not_blamed_on_credentials(unused_endpoint: str) -> None:
    said = _refused(unused_endpoint, None)
    assert "nothing answers at" in said and "needs credentials" not in said


def test_the_right_credentials_open(router: tuple[str, CredentialStore, Any]) -> None:
    endpoint, store, _ = router
    session = open_session(client_settings(endpoint, store.cred_file("viewer")))
    session.close()  # type: ignore[no-untyped-call]


def test_modd_backfill_without_credentials(router: tuple[str, CredentialStore, Any]) -> None:
    endpoint, _, _ = router
    res = subprocess.run(
        [
            str(Path(sys.executable).parent / "modd"),
            "backfill",
            "--drone",
            "usv",
            "--subscriber",
            "sub_1",
            "--gaps",
            "--connect",
            endpoint,
        ],
        capture_output=True,
        text=True,
        timeout=60,
        env={"PATH": "/usr/bin:/bin"},
    )
    assert res.returncode == 2
    assert "needs credentials" in res.stderr and "viewer.cred" in res.stderr, res.stderr
    assert "Traceback" not in res.stderr and ".rs:" not in res.stderr
