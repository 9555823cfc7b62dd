"""A listening session's bounds against idle connections (docs/security.md,
"Idle connections"), read back from zenoh's own configuration object."""

from __future__ import annotations

import json
from pathlib import Path

import zenoh
from modd.zenoh_session import ZenohSettings, client_settings, zenoh_config

UNICAST = "transport/unicast"


def unicast(config: zenoh.Config) -> dict[str, object]:
    value: dict[str, object] = json.loads(config.get_json(UNICAST))
    return value


def test_a_listening_session_bounds_pending_connections() -> None:
    got = unicast(zenoh_config(ZenohSettings(mode="router", listen=("tcp/127.0.0.1:7447",))))
    default = unicast(zenoh.Config())
    assert default["accept_timeout"] == 10000 and default["accept_pending"] == 100
    assert got["accept_timeout"] == 2000 and got["accept_pending"] == 2000
    assert got["max_sessions"] == 256 and got["max_links"] == 1


def test_a_client_keeps_zenohs_defaults() -> None:
    assert unicast(zenoh_config(client_settings("tcp/127.0.0.1:7447"))) == unicast(zenoh.Config())


def test_settings_and_a_config_file_override_the_limits(tmp_path: Path) -> None:
    s = ZenohSettings(
        mode="router", listen=("tcp/127.0.0.1:7447",), extra={f"{UNICAST}/accept_timeout": "5000"}
    )
    assert unicast(zenoh_config(s))["accept_timeout"] == 5000
    f = tmp_path / "zenoh.json5"
    f.write_text("{transport: {unicast: {accept_pending: 50}}}")
    got = unicast(
        zenoh_config(
            ZenohSettings(mode="router", listen=("tcp/127.0.0.1:7447",), config_file=str(f))
        )
    )
    assert got["accept_pending"] == 50 and got["accept_timeout"] == 2000


def test_the_docker_routers_config_has_the_same_limits(tmp_path: Path) -> None:
    import importlib.util

    from modd.zenoh_auth import CredentialStore

    path = Path(__file__).resolve().parents[3] / "docker" / "credentials.py"
    spec = importlib.util.spec_from_file_location("docker_credentials", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    cfg = module.router_config(CredentialStore(tmp_path / "cred"), "usv")
    got = unicast(zenoh.Config.from_json5(json.dumps(cfg)))
    assert got["accept_timeout"] == 2000 and got["accept_pending"] == 2000
