"""The link client for the configured transport (docs/subbroker.md,
"Transports"), behind one interface (:class:`~.pump.Link`):
:class:`~.link.LinkClient` over tcp, or :class:`~.dglink.DatagramLinkClient`
over udp (a socket that sends to the PubBroker's endpoint) or serial (the
base station radio's device).

>>> link = link_client(config, key, handler, liveness)   # doctest: +SKIP
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial

from modd_plan.linkbudget import LinkSettings

from .config import SubBrokerConfig
from .dglink import DatagramLinkClient
from .dgport import DatagramPort, SerialPort, UdpPort
from .dgsession import DatagramSession
from .link import LinkClient
from .linkhooks import LinkHandler
from .pump import Link

DEFAULT_BAUD = 57600


def link_client(
    config: SubBrokerConfig, key: bytes, handler: LinkHandler, liveness: Callable[[], float]
) -> Link:
    """The link client the configuration asks for (not started)."""
    transport = config.transport
    if transport == "tcp":
        return LinkClient(config.endpoint, key, config.link, handler, liveness)
    settings = LinkSettings.of(config.model, transport)
    opener: Callable[[], DatagramPort]
    if transport == "udp":
        opener = partial(UdpPort, config.endpoint)
        where = "udp {}:{}".format(*config.endpoint)
    else:
        baud = config.link.baud or int(config.model.get("link", {}).get("baud", DEFAULT_BAUD))
        opener = partial(SerialPort, config.device, baud, settings.max_packet)
        where = f"serial {config.device}"
    session = DatagramSession(
        transport,
        key,
        config.link,
        handler,
        float(settings.accepted_delay),
        liveness,
        settings.max_packet,
        where=where,
    )
    return DatagramLinkClient(opener, session, config.link)
