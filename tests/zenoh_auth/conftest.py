"""A zenoh router with the SubBroker's authentication and access control
(an in-process session listening on loopback, identity ``subbroker``)."""

from __future__ import annotations

import socket
from collections.abc import Iterator

import pytest
import zenoh
from modd.zenoh_auth import CredentialStore
from modd.zenoh_session import ZenohSettings, open_session, secured


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@pytest.fixture
def unused_endpoint() -> str:
    """A loopback endpoint where nothing listens."""
    return f"tcp/127.0.0.1:{free_port()}"


@pytest.fixture(scope="module")
def router(
    tmp_path_factory: pytest.TempPathFactory,
) -> Iterator[tuple[str, CredentialStore, zenoh.Session]]:
    store = CredentialStore(tmp_path_factory.mktemp("zenoh") / "credentials")
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    settings = secured(ZenohSettings(mode="router", listen=(endpoint,)), store, "subbroker", "usv")
    session = open_session(settings)
    try:
        yield endpoint, store, session
    finally:
        session.close()  # type: ignore[no-untyped-call]
