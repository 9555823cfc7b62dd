"""Where the TCP delivery key comes from (docs/subbroker.md, "TCP delivery
handshake"): the SubBroker's ``[delivery] key`` setting wins over
``$MODD_DELIVERY_KEY`` and the user's default file; a relative ``file:``
is relative to the config file; a malformed or unreadable key is a clear
error at start, not at the first subscriber."""

from __future__ import annotations

import hashlib
import hmac
import os
import socket
import subprocess
import sys
from pathlib import Path

import pytest
from modd.ports import free_port
from modd.subbroker.config import ConfigError, load_config
from modd.subbroker.delivery import TcpDelivery
from modd.subbroker.delivery_auth import GREETING, LABEL, DeliveryKeyError, load_key


def _config(tmp: Path, scenarios_dir: Path, delivery: str) -> Path:
    path = tmp / "sb.toml"
    path.write_text(
        f'model = "{scenarios_dir / "scenario1.modd"}"\n'
        f'[zenoh]\nlisten = ["tcp/127.0.0.1:{free_port()}"]\n'
        f'credentials_dir = "cred"\n[delivery]\n{delivery}\n'
    )
    return path


def test_key_setting_read_relative_to_the_config(tmp_path: Path, scenarios_dir: Path) -> None:
    config = load_config(_config(tmp_path, scenarios_dir, 'key = "file:keys/delivery.key"'))
    assert config.delivery.key == f"file:{tmp_path / 'keys' / 'delivery.key'}"
    assert (
        load_config(_config(tmp_path, scenarios_dir, 'key = "env:MY_KEY"')).delivery.key
        == "env:MY_KEY"
    )
    for bad in ('key = "plain-secret"', 'key = "file:"', "key = 3"):
        with pytest.raises(ConfigError, match="delivery"):
            load_config(_config(tmp_path, scenarios_dir, bad))


def test_configured_key_proves_itself(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A subscriber's challenge is answered with the configured key, not with
    $MODD_DELIVERY_KEY's (the oracle: Python's hmac over the greeting)."""
    key_file = tmp_path / "delivery.key"
    key_file.write_text("the configured key\n")
    key_file.chmod(0o600)
    monkeypatch.setenv("MODD_DELIVERY_KEY", "env:OTHER_KEY")
    monkeypatch.setenv("OTHER_KEY", "another key")
    server = socket.create_server(("127.0.0.1", 0))
    server.settimeout(10)
    delivery = TcpDelivery({"sub_1": server.getsockname()}, key_ref=f"file:{key_file}")
    try:
        conn, _ = server.accept()
        conn.settimeout(10)
        nonce = os.urandom(16).hex()
        conn.sendall(GREETING + nonce.encode() + b"\n")
        answer = conn.makefile("rb").readline().decode().strip()
        want = hmac.new(b"the configured key", LABEL + nonce.encode(), hashlib.sha256).hexdigest()
        assert answer == f"AUTH {want}"
        conn.close()
    finally:
        delivery.close()
        server.close()


def test_unreadable_configured_key_stops_the_subbroker_at_start(
    tmp_path: Path, scenarios_dir: Path
) -> None:
    config = _config(tmp_path, scenarios_dir, 'key = "file:missing.key"\ntcp = true')
    proc = subprocess.run(
        [sys.executable, "-m", "modd.subbroker.cli", "--config", str(config)],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
        env={**os.environ, "MODD_LINK_KEY": "link-key-for-tests"},
    )
    assert proc.returncode == 2, proc.stderr
    assert "missing.key" in proc.stderr


def test_a_fifo_as_the_delivery_key_is_refused_at_once(tmp_path: Path) -> None:
    """A FIFO planted where the key file is: the open blocked until a writer
    came (the SubBroker hung at start); now refused as not a regular file."""
    fifo = tmp_path / "delivery.key"
    os.mkfifo(fifo)
    with pytest.raises(DeliveryKeyError, match="not a regular file"):
        load_key(f"file:{fifo}")
