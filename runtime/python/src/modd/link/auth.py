"""The pre-shared-key handshake (docs/protocol.md, "Handshake").

The base station (client) sends HELLO with its nonce, the PubBroker answers CHALLENGE with
its own, the client proves the key with AUTH, the broker proves it back in AUTH_OK.

Example::

    sock = socket.create_connection(("127.0.0.1", 7171))
    ok, splitter = client_handshake(sock, b"secret")
"""

from __future__ import annotations

import hashlib
import hmac
import os
import socket
import struct
import time

from modd_contracts.link_wire_gen import MIN_KEY_BYTES as MIN_KEY_BYTES  # as the PubBroker's

from modd.link import codec
from modd.link.frames import (
    VERSION,
    Auth,
    AuthOk,
    Challenge,
    ErrorCode,
    ErrorMsg,
    Hello,
    ProtocolError,
)
from modd.zenoh_auth import read_secret

CLIENT_LABEL = b"MODD1C"
SERVER_LABEL = b"MODD1S"
HELLO_LABEL = b"MODDHL"
_KEYED_HALF = 8


def check_key_length(key: bytes, reference: str) -> bytes:
    """``key`` if it holds at least :data:`MIN_KEY_BYTES` bytes, else ValueError naming
    ``reference`` and the length."""
    if len(key) < MIN_KEY_BYTES:
        raise ValueError(
            f"key reference {reference} gives a key of {len(key)} bytes; a link key "
            f"needs at least {MIN_KEY_BYTES} (e.g. openssl rand -hex 16)"
        )
    return key


def client_proof(key: bytes, client_nonce: bytes, server_nonce: bytes) -> bytes:
    return hmac.new(key, CLIENT_LABEL + server_nonce + client_nonce, hashlib.sha256).digest()


def keyed_nonce(key: bytes, random: bytes | None = None) -> bytes:
    """A HELLO nonce the PubBroker knows for the key holder's (docs/protocol.md, "Keyed
    HELLO"): 8 bytes, then HMAC(key, "MODDHL" || those 8 bytes)[0:8]. The 8 bytes are
    ``random`` when given, else this clock in seconds (big-endian u32: the PubBroker prefers
    the newest attempt) and 4 random bytes. The HELLO keeps its layout; a keyless flood can
    then neither spend its CHALLENGE budget nor evict it."""
    head = random
    if head is None:
        head = struct.pack(">I", int(time.time()) & 0xFFFFFFFF) + os.urandom(4)
    if len(head) != _KEYED_HALF:
        raise ValueError(f"a keyed nonce starts with {_KEYED_HALF} random bytes, not {len(head)}")
    return head + hmac.new(key, HELLO_LABEL + head, hashlib.sha256).digest()[:_KEYED_HALF]


def is_keyed_nonce(key: bytes, nonce: bytes) -> bool:
    """Whether ``nonce`` is :func:`keyed_nonce`'s under ``key`` (constant time)."""
    if len(nonce) != 2 * _KEYED_HALF:
        return False
    return hmac.compare_digest(keyed_nonce(key, nonce[:_KEYED_HALF]), nonce)


def server_proof(key: bytes, client_nonce: bytes, server_nonce: bytes) -> bytes:
    return hmac.new(key, SERVER_LABEL + client_nonce + server_nonce, hashlib.sha256).digest()


def resolve_key(reference: str) -> bytes:
    """`env:NAME` or `file:PATH` (trailing newline stripped), as the PubBroker reads it."""
    if reference.startswith("env:"):
        value = os.environ.get(reference[4:])
        if value is None:
            raise ValueError(f"key reference {reference}: environment variable not set")
        key = value.encode()
    elif reference.startswith("file:"):
        # a regular file of at most 64 KiB, no final symlink (docs/security.md)
        key = read_secret(reference[5:], "link key").rstrip(b"\r\n")
    else:
        raise ValueError(f"key reference {reference!r} is neither env:NAME nor file:PATH")
    return check_key_length(key, reference)


def read_frame(sock: socket.socket, splitter: codec.FrameSplitter) -> codec.RawFrame:
    """Blocks until the next whole frame; raises ConnectionError if the peer closes."""
    while (f := splitter.pop()) is None:
        data = sock.recv(4096)
        if not data:
            raise ConnectionError("link closed")
        splitter.buf += data
    return f


def client_handshake(
    sock: socket.socket, key: bytes, nonce: bytes | None = None
) -> tuple[AuthOk, codec.FrameSplitter]:
    """Runs the handshake on a connected socket. Returns AUTH_OK and the splitter holding any
    bytes received after it. Raises ProtocolError if the broker refuses or cannot prove the key."""
    splitter = codec.FrameSplitter()
    client_nonce = nonce if nonce is not None else keyed_nonce(key)
    sock.sendall(codec.encode(Hello(VERSION, client_nonce)))
    msg = codec.decode(read_frame(sock, splitter))
    if isinstance(msg, ErrorMsg):
        raise ProtocolError(ErrorCode(msg.code), f"broker refused HELLO: {msg.message}")
    if not isinstance(msg, Challenge):
        raise ProtocolError(ErrorCode.BAD_FRAME, f"expected CHALLENGE, got {type(msg).__name__}")
    sock.sendall(codec.encode(Auth(client_proof(key, client_nonce, msg.nonce))))
    ok = codec.decode(read_frame(sock, splitter))
    if isinstance(ok, ErrorMsg):
        raise ProtocolError(ErrorCode(ok.code), f"broker refused AUTH: {ok.message}")
    if not isinstance(ok, AuthOk):
        raise ProtocolError(ErrorCode.BAD_FRAME, f"expected AUTH_OK, got {type(ok).__name__}")
    if not hmac.compare_digest(ok.mac, server_proof(key, client_nonce, msg.nonce)):
        raise ProtocolError(ErrorCode.AUTH_FAILED, "the broker does not know the key")
    return ok, splitter
