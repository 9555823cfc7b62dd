"""SubBroker configuration: a TOML file (docs/subbroker.md, "Configuration
file") or just a model, with the embedded defaults. Nothing is read at import
time; every error names the file and the key.

>>> cfg = config_from_model("scenario1.modd")              # doctest: +SKIP
>>> cfg.drone, cfg.link.endpoint                          # doctest: +SKIP
('usv', ('127.0.0.1', 7171))
"""

from __future__ import annotations

import os
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from modd_contracts.keys import check_name
from modd_contracts.link_wire_gen import DEFAULT_STATUS_PERIOD_S
from modd_model import ModelError, load_model

from ..link.auth import check_key_length
from ..zenoh_auth import read_secret
from ..zenoh_session import DEFAULT_ENDPOINT, ZenohSettings
from .delivery_auth import DeliveryKeyError, check_ref

#: Where the pre-shared key is read from when neither the config nor the model says.
DEFAULT_KEY_REF = "env:MODD_LINK_KEY"


class ConfigError(ValueError):
    """A bad configuration; the message names the file and the key."""


@dataclass(frozen=True)
class LinkOptions:
    """The link to the PubBroker (``[link]``)."""

    endpoint: tuple[str, int] | None = None  # None: the model's PubBroker endpoint
    key: str | None = None  # env:NAME or file:PATH; None: the model's keyRef
    connect_timeout_s: float = 2.0
    backoff_initial_s: float = 0.1
    backoff_max_s: float = 1.0
    liveness_timeout_s: float = 0.0  # 0: 2 x the longest slot gap + 1 s
    ping_count: int = 3
    ping_period_s: float = 0.0  # 0: PING only on connect (keeps the link quiet)
    # STATUS rate asked in CONFIG (0: none); the planner counts the default's
    pubbroker_status_period_s: int = DEFAULT_STATUS_PERIOD_S
    ack_timeout_s: float = 5.0
    plan_budget_s: float = 5.0  # a deploy not planned within it is refused (REJECTED)
    # transport (docs/subbroker.md): "" is the model's (tcp, udp or serial); for serial the
    # base station's device (the model's `device` when "") and its baud rate
    transport: str = ""
    device: str = ""
    baud: int = 0  # 0: the model's (57600)


@dataclass(frozen=True)
class DeliveryOptions:
    """Where values go (``[delivery]``)."""

    zenoh: bool = True
    tcp: bool = True  # to each subscriber's endpoint, when the model gives one
    tcp_queue: int = 1000  # values kept per TCP subscriber while it is away
    status_period_s: float = 1.0  # modd/<drone>/status
    #: The TCP delivery key: env:NAME or file:PATH (relative to the config
    #: file); empty: $MODD_DELIVERY_KEY, else ~/.config/modd/delivery.key.
    key: str = ""


@dataclass(frozen=True)
class SubBrokerConfig:
    """Everything a SubBroker needs, resolved."""

    model: dict[str, Any]
    drone: str
    link: LinkOptions = field(default_factory=LinkOptions)
    zenoh: ZenohSettings = field(
        default_factory=lambda: ZenohSettings(mode="router", listen=(DEFAULT_ENDPOINT,))
    )
    delivery: DeliveryOptions = field(default_factory=DeliveryOptions)
    state_dir: Path | None = None  # where a deployed model is kept across restarts
    record_dir: Path | None = None  # base-station record (default <state_dir>/records)
    #: ``modd up --simulate``'s rehearsal folder: its ``link-cut`` cuts the link (rehearsal.py).
    rehearsal_dir: Path | None = None
    source: str = "<defaults>"
    #: Resume the deployment and dynamic subscriptions kept in state_dir (else
    #: run the configured model; ``modd-subbroker --no-resume``).
    resume: bool = True
    #: The on-board model file an acked deploy is handed to (modd.onboard), when the
    #: drone's processes run on this machine; None: the deploy ends at the PubBroker.
    onboard_model: Path | None = None
    #: an acked deploy's model goes to the PubBroker over the link (ONBOARD)
    onboard_over_link: bool = False
    #: This base station's name when several may serve the drone (docs/fleet.md): the
    #: stations elect the one that holds the link; "" connects as before.
    station: str = ""

    @property
    def endpoint(self) -> tuple[str, int]:
        """The PubBroker's link endpoint."""
        if self.link.endpoint is not None:
            return self.link.endpoint
        return endpoint_of(self.model)

    @property
    def credentials_dir(self) -> Path:
        """Where the zenoh credentials and the deploy key are kept (made at
        first start): ``[zenoh] credentials_dir``, else ``<state_dir>/credentials``,
        else ``credentials`` beside the config file, else the user's state
        directory (``$XDG_STATE_HOME/modd/<drone>/credentials``)."""
        if self.zenoh.credentials_dir:
            return Path(self.zenoh.credentials_dir)
        if self.state_dir is not None:
            return self.state_dir / "credentials"
        if self.source.endswith(".toml"):
            return Path(self.source).parent / "credentials"
        state = os.environ.get("XDG_STATE_HOME") or str(Path.home() / ".local" / "state")
        return Path(state) / "modd" / self.drone / "credentials"

    @property
    def transport(self) -> str:
        """tcp, udp or serial: ``[link] transport``, else the model's."""
        t = self.link.transport or self.model.get("link", {}).get("transport", "tcp")
        if t not in ("tcp", "udp", "serial"):
            raise ConfigError(
                f"{self.source}: link.transport: expected tcp, udp or serial, got {t!r}"
            )
        return str(t)

    @property
    def device(self) -> str:
        """The serial device of the base station's radio."""
        dev = self.link.device or self.model.get("link", {}).get("device", "")
        if not dev:
            raise ConfigError(
                f"{self.source}: a serial link needs [link] device (or the model's link device)"
            )
        return str(dev)

    @property
    def key_ref(self) -> str:
        return self.link.key or self.model.get("link", {}).get("keyRef") or DEFAULT_KEY_REF


def endpoint_of(model: Mapping[str, Any]) -> tuple[str, int]:
    ep = model.get("pubBroker", {}).get("endpoint")
    if not ep:
        raise ConfigError("the model gives no PubBroker endpoint and [link] endpoint is not set")
    return str(ep["host"]), int(ep["port"])


def parse_endpoint(text: str, where: str) -> tuple[str, int]:
    """``"host:port"`` -> ``(host, port)``."""
    host, sep, port = text.rpartition(":")
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise ConfigError(f"{where}: expected host:port, got {text!r}")
    return host, int(port)


def resolve_key(ref: str) -> bytes:
    """The pre-shared key from ``env:NAME`` or ``file:PATH`` (one trailing
    newline stripped), at least 16 bytes; ConfigError naming the reference otherwise."""
    kind, _, name = ref.partition(":")
    if kind == "env":
        value = os.environ.get(name)
        if not value:
            raise ConfigError(f"link key {ref}: environment variable {name} is not set")
        key = value.encode()
    elif kind == "file":
        # a regular file of at most 64 KiB, no final symlink (docs/security.md)
        try:
            key = read_secret(name, "link key")
        except ValueError as exc:
            raise ConfigError(f"link key {ref}: {exc}") from exc
    else:
        raise ConfigError(f"link key {ref!r}: expected env:NAME or file:PATH")
    try:
        return check_key_length(key, ref)
    except ValueError as exc:
        raise ConfigError(f"link key: {exc}") from exc


def _drone(model: Mapping[str, Any]) -> str:
    return str(model["drone"]["name"])


def _load(path: Path) -> dict[str, Any]:
    try:
        return load_model(path)
    except ModelError as exc:
        raise ConfigError(str(exc)) from exc
    except OSError as exc:
        raise ConfigError(f"{path}: {exc.strerror}") from exc


def config_from_model(model_path: str | Path, **overrides: Any) -> SubBrokerConfig:
    """A configuration with every default, for ``modd-subbroker --model FILE``."""
    model = _load(Path(model_path))
    return replace(
        SubBrokerConfig(model=model, drone=model["drone"]["name"], source=str(model_path)),
        **overrides,
    )


def _table(data: Mapping[str, Any], name: str, source: str) -> dict[str, Any]:
    value = data.get(name, {})
    if not isinstance(value, dict):
        raise ConfigError(f"{source}: [{name}] must be a table")
    return value


def _options(cls: type[Any], data: Mapping[str, Any], where: str) -> Any:
    defaults = cls()
    known = set(defaults.__dataclass_fields__)
    values: dict[str, Any] = {}
    for key, value in data.items():
        if key not in known:
            raise ConfigError(f"{where}: unknown key {key!r}; known: {', '.join(sorted(known))}")
        expected = type(getattr(defaults, key))
        if key == "endpoint":
            value = parse_endpoint(str(value), f"{where}.endpoint")
        elif expected is float and isinstance(value, int) and not isinstance(value, bool):
            value = float(value)
        elif getattr(defaults, key) is not None and not isinstance(value, expected):
            raise ConfigError(f"{where}.{key}: expected {expected.__name__}, got {value!r}")
        values[key] = value
    return replace(defaults, **values)


def load_config(path: str | Path) -> SubBrokerConfig:
    """Read a SubBroker TOML file; relative paths in it are relative to it."""
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text())
    except OSError as exc:
        raise ConfigError(f"{path}: {exc.strerror}") from exc
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{path}: {exc}") from exc
    known = {"model", "drone", "state_dir", "record_dir", "link", "zenoh", "delivery", "station"}
    for key in data:
        if key not in known:
            raise ConfigError(f"{path}: unknown key {key!r}; known: {', '.join(sorted(known))}")
    if "model" not in data:
        raise ConfigError(f"{path}: missing key 'model' (path of the .modd or .json model)")
    model = _load(path.parent / str(data["model"]))
    drone = str(data.get("drone", model["drone"]["name"]))
    if drone != model["drone"]["name"]:
        raise ConfigError(f"{path}: drone {drone!r} but the model is for {_drone(model)!r}")
    try:
        zenoh = ZenohSettings.from_mapping(_table(data, "zenoh", str(path)), f"{path}: zenoh")
    except ValueError as exc:
        raise ConfigError(str(exc)) from exc
    if zenoh.credentials_dir:
        zenoh = replace(zenoh, credentials_dir=str(path.parent / zenoh.credentials_dir))
    state = data.get("state_dir")
    src = str(path)
    delivery = _options(DeliveryOptions, _table(data, "delivery", src), f"{path}: delivery")
    if delivery.key:
        try:
            check_ref(delivery.key, f"{path}: delivery.key")
        except DeliveryKeyError as exc:
            raise ConfigError(str(exc)) from exc
        if delivery.key.startswith("file:"):
            delivery = replace(delivery, key="file:" + str(path.parent / delivery.key[5:]))
    return SubBrokerConfig(
        model=model,
        drone=drone,
        link=_options(LinkOptions, _table(data, "link", src), f"{path}: link"),
        zenoh=zenoh,
        delivery=delivery,
        state_dir=path.parent / str(state) if state else None,
        record_dir=path.parent / str(data["record_dir"]) if data.get("record_dir") else None,
        source=str(path),
        station=station_name(data.get("station", ""), f"{path}: station"),
    )


def station_name(value: object, where: str) -> str:
    """A station's name: an identifier (it is a chunk of a zenoh key), or "" for none."""
    if value == "":
        return ""
    try:
        return check_name("station", value)
    except ValueError as exc:
        raise ConfigError(f"{where}: {exc}") from exc
