"""Zenoh over TLS and mutual TLS on loopback (docs/security.md, "TLS"), with
certificates this test makes (openssl): a router (as the SubBroker runs one)
with user/password authentication listens on tls/; a client that trusts the
CA and gives its certificate reads values; one without a client certificate
is refused under mutual TLS, and one trusting another CA is refused."""

from __future__ import annotations

import shutil
import subprocess
import time
from pathlib import Path

import pytest
from modd.ports import free_port
from modd.zenoh_auth import CredentialStore, acl
from modd.zenoh_gate import AcceptGate, start_gates
from modd.zenoh_session import ZenohSettings, client_settings, open_session, wait_connected

pytestmark = pytest.mark.skipif(shutil.which("openssl") is None, reason="needs openssl")


def openssl(*args: str, cwd: Path) -> None:
    subprocess.run(["openssl", *args], cwd=cwd, check=True, capture_output=True, timeout=60)


def make_ca(d: Path, name: str) -> None:
    openssl(
        "req",
        "-x509",
        "-newkey",
        "rsa:2048",
        "-nodes",
        "-days",
        "1",
        "-subj",
        f"/CN={name}",
        "-keyout",
        f"{name}.key",
        "-out",
        f"{name}.pem",
        cwd=d,
    )


def make_cert(d: Path, ca: str, name: str) -> None:
    ext = d / f"{name}.ext"
    ext.write_text("subjectAltName=DNS:localhost,IP:127.0.0.1\n")
    openssl(
        "req",
        "-newkey",
        "rsa:2048",
        "-nodes",
        "-subj",
        f"/CN={name}",
        "-keyout",
        f"{name}.key",
        "-out",
        f"{name}.csr",
        cwd=d,
    )
    openssl(
        "x509",
        "-req",
        "-in",
        f"{name}.csr",
        "-CA",
        f"{ca}.pem",
        "-CAkey",
        f"{ca}.key",
        "-CAcreateserial",
        "-days",
        "1",
        "-extfile",
        ext.name,
        "-out",
        f"{name}.pem",
        cwd=d,
    )


def tls(d: Path, ca: str, role: str, cert: str | None) -> dict[str, str]:
    out = {"transport/link/tls/root_ca_certificate": f'"{d / ca}.pem"'}
    if cert is not None:  # both sides say enable_mtls, or the client sends no certificate
        out[f"transport/link/tls/{role}_private_key"] = f'"{d / cert}.key"'
        out[f"transport/link/tls/{role}_certificate"] = f'"{d / cert}.pem"'
        out["transport/link/tls/enable_mtls"] = "true"
    return out


@pytest.mark.parametrize("gated", [False, True], ids=["bare", "behind-the-gate"])
def test_mutual_tls_with_credentials(tmp_path: Path, gated: bool) -> None:
    """Also behind the SubBroker's accept gate (modd.zenoh_gate), which relays TLS as is."""
    for ca in ("ca", "other_ca"):
        make_ca(tmp_path, ca)
    make_cert(tmp_path, "ca", "router")
    make_cert(tmp_path, "ca", "viewer")
    make_cert(tmp_path, "other_ca", "stranger")
    store = CredentialStore(tmp_path / "credentials").ensure()
    endpoint = f"tls/127.0.0.1:{free_port()}"
    settings = ZenohSettings(
        mode="router",
        listen=(endpoint,),
        dictionary_file=str(store.dictionary),
        access_control=acl("usv"),
        extra=tls(tmp_path, "ca", "listen", "router"),
    )
    gates: list[AcceptGate] = []
    if gated:
        settings, gates = start_gates(settings)
        assert settings.listen != (endpoint,) and len(gates) == 1
    router = open_session(settings)
    sessions = [router]
    try:

        def client(ca: str, cert: str | None) -> object:
            base = client_settings(endpoint, store.cred_file("viewer"))
            s = open_session(
                ZenohSettings(
                    mode="client",
                    connect=base.connect,
                    credentials=base.credentials,
                    extra=tls(tmp_path, ca, "connect", cert),
                )
            )
            sessions.append(s)
            return s

        viewer = client("ca", "viewer")
        assert wait_connected(viewer)  # type: ignore[arg-type]
        got: list[bytes] = []
        viewer.declare_subscriber(  # type: ignore[attr-defined]
            "modd/usv/sub/*", lambda s: got.append(s.payload.to_bytes())
        )
        deadline = time.monotonic() + 5
        while not got and time.monotonic() < deadline:
            router.put("modd/usv/sub/sub_1", b"over tls")
            time.sleep(0.1)
        assert got and got[0] == b"over tls"
        with pytest.raises(ValueError, match="cannot open"):
            client("ca", None)  # no client certificate: mutual TLS refuses it
        with pytest.raises(ValueError, match="cannot open"):
            client("other_ca", "stranger")  # does not trust the router's CA
    finally:
        for s in reversed(sessions):
            s.close()  # type: ignore[no-untyped-call]
        for gate in gates:
            gate.stop()
