"""A TLS identity made at start-up for the servers the backend runs on
loopback and reaches only through its own authenticated proxy (the Foxglove
live and replay servers: foxgloveproxy.py).

Why TLS on loopback: ``foxglove-sdk``'s server has no hook to authenticate a
client, and binding to loopback does not stop a web page, which may open a
WebSocket to any port of 127.0.0.1. A browser refuses a ``wss://`` server
whose certificate it does not trust, and no script can make it accept one;
plain ``ws://`` is refused by the server. So no page of any origin reads
these ports, while the backend's proxy trusts exactly this certificate. The
key lives in this process's memory only (never written to disk).

>>> tls = LoopbackTls.generate()
>>> tls.cert_pem.startswith(b"-----BEGIN CERTIFICATE-----")
True
"""

from __future__ import annotations

import datetime
import ipaddress
import ssl
from dataclasses import dataclass

#: The address the certificate names (the servers bind to it).
LOOPBACK = "127.0.0.1"


@dataclass(frozen=True)
class LoopbackTls:
    cert_pem: bytes
    key_pem: bytes  # PKCS#8, what the SDK takes

    @classmethod
    def generate(cls, days: int = 3650) -> LoopbackTls:
        """A self-signed P-256 certificate for 127.0.0.1 and its key."""
        from cryptography import x509
        from cryptography.hazmat.primitives import hashes, serialization
        from cryptography.hazmat.primitives.asymmetric import ec
        from cryptography.x509.oid import NameOID

        key = ec.generate_private_key(ec.SECP256R1())
        name = x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, "modd-backend loopback")])
        now = datetime.datetime.now(datetime.UTC)
        ski = x509.SubjectKeyIdentifier.from_public_key(key.public_key())
        cert = (
            x509.CertificateBuilder()
            .subject_name(name)
            .issuer_name(name)
            .public_key(key.public_key())
            .serial_number(x509.random_serial_number())
            .not_valid_before(now - datetime.timedelta(minutes=5))
            .not_valid_after(now + datetime.timedelta(days=days))
            .add_extension(
                x509.SubjectAlternativeName([x509.IPAddress(ipaddress.ip_address(LOOPBACK))]),
                critical=False,
            )
            .add_extension(x509.BasicConstraints(ca=False, path_length=None), critical=True)
            .add_extension(ski, critical=False)
            .add_extension(
                x509.AuthorityKeyIdentifier.from_issuer_subject_key_identifier(ski), critical=False
            )
            .sign(key, hashes.SHA256())
        )
        return cls(
            cert.public_bytes(serialization.Encoding.PEM),
            key.private_bytes(
                serialization.Encoding.PEM,
                serialization.PrivateFormat.PKCS8,
                serialization.NoEncryption(),
            ),
        )

    def client_context(self) -> ssl.SSLContext:
        """An SSL context trusting this certificate alone (for the proxy)."""
        ctx = ssl.create_default_context(cadata=self.cert_pem.decode("ascii"))
        ctx.check_hostname = True
        return ctx
