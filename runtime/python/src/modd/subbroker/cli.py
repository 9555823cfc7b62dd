"""``modd-subbroker``: run the base-station SubBroker.

    modd-subbroker --config subbroker.toml
    modd-subbroker --model mission.modd [--link 127.0.0.1:7171] [--key env:MODD_LINK_KEY]
                   [--zenoh-listen tcp/127.0.0.1:7447] [--no-tcp-delivery]

SIGTERM or SIGINT stops it cleanly; SIGUSR1 prints every thread's stack to stderr.
Exit codes: 0 stopped, 2 bad usage or config.
"""

from __future__ import annotations

import argparse
import faulthandler
import logging
import signal
import sys
import threading
from dataclasses import replace
from pathlib import Path

from ..shutdown import stop_on_signals
from ..zenoh_session import ZenohSettings
from .config import (
    ConfigError,
    SubBrokerConfig,
    config_from_model,
    load_config,
    parse_endpoint,
    station_name,
)


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="modd-subbroker",
        description="MoDD base-station SubBroker: link to the PubBroker, delivery over zenoh "
        "and TCP, dynamic subscriptions and deploy (docs/subbroker.md).",
    )
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--config", help="SubBroker TOML configuration file")
    src.add_argument("--model", help="model (.modd or .json) to run with the defaults")
    p.add_argument("--link", help="PubBroker link endpoint host:port (default: the model's)")
    p.add_argument("--key", help="pre-shared key reference env:NAME or file:PATH")
    p.add_argument(
        "--zenoh-listen",
        action="append",
        default=None,
        metavar="ENDPOINT",
        help="zenoh listen endpoint (repeatable; default tcp/127.0.0.1:7447)",
    )
    p.add_argument(
        "--zenoh-connect",
        action="append",
        default=None,
        metavar="ENDPOINT",
        help="zenoh endpoint to connect to (repeatable)",
    )
    p.add_argument("--zenoh-mode", choices=("peer", "client", "router"), default=None)
    p.add_argument(
        "--credentials",
        metavar="DIR",
        default=None,
        help="zenoh credentials and deploy key directory, made at first start "
        "(default: <state_dir>/credentials; docs/security.md)",
    )
    p.add_argument(
        "--record-dir",
        metavar="DIR",
        default=None,
        help="base-station MCAP record of every delivered value "
        "(default: <state_dir>/records; none without a state_dir)",
    )
    p.add_argument(
        "--rehearsal-dir",
        metavar="DIR",
        default=None,
        help="a folder whose file link-cut, while there, cuts the link to the PubBroker "
        "for a rehearsed outage (modd up --simulate gives <workdir>/rehearsal; modd link cut)",
    )
    p.add_argument(
        "--no-tcp-delivery",
        action="store_true",
        help="do not deliver to the subscribers' TCP endpoints",
    )
    p.add_argument(
        "--status-period",
        type=float,
        default=None,
        metavar="S",
        help="seconds between status puts (default 1)",
    )
    p.add_argument(
        "--no-resume",
        action="store_true",
        help="run the configured model, not the deployment (and dynamic "
        "subscriptions) kept in the state directory",
    )
    p.add_argument(
        "--onboard-model",
        metavar="PATH",
        default=None,
        help="when the drone's processes run on this machine (modd up --part all): write "
        "each acked deploy's model there for modd-sensors and modd-mavlink --watch, and "
        "put what they did in the deploy's reply (docs/sensors.md)",
    )
    p.add_argument(
        "--onboard-over-link",
        action="store_true",
        help="send each acked deploy's model to the PubBroker over the link (ONBOARD, "
        "docs/protocol.md; a PubBroker started with --onboard-model writes it for "
        "modd-sensors and modd-mavlink --watch) and put their answers in the reply; "
        "an older PubBroker refuses the frame",
    )
    p.add_argument(
        "--station",
        metavar="NAME",
        default=None,
        help="this base station's name when several stations may serve the drone: they "
        "elect the one that holds the link (docs/fleet.md)",
    )
    p.add_argument("--log-level", default="INFO")
    return p


def build_config(args: argparse.Namespace) -> SubBrokerConfig:
    """The configuration the command line asks for."""
    cfg = load_config(args.config) if args.config else config_from_model(args.model)
    link = cfg.link
    if args.link:
        link = replace(link, endpoint=parse_endpoint(args.link, "--link"))
    if args.key:
        link = replace(link, key=args.key)
    z = cfg.zenoh
    if args.zenoh_listen or args.zenoh_connect or args.zenoh_mode:
        listen = z.listen
        if args.zenoh_listen:
            listen = tuple(args.zenoh_listen)
        elif args.zenoh_mode == "client":
            listen = ()  # a client of a router listens nowhere: two on one host must not collide
        z = ZenohSettings(
            mode=args.zenoh_mode or z.mode,
            listen=listen,
            connect=tuple(args.zenoh_connect) if args.zenoh_connect else z.connect,
            config_file=z.config_file,
            extra=z.extra,
            credentials_dir=z.credentials_dir,
        )
    if args.credentials:
        z = replace(z, credentials_dir=args.credentials)
    delivery = cfg.delivery
    if args.no_tcp_delivery:
        delivery = replace(delivery, tcp=False)
    if args.status_period is not None:
        delivery = replace(delivery, status_period_s=args.status_period)
    if args.record_dir:
        cfg = replace(cfg, record_dir=Path(args.record_dir))
    if args.onboard_model:
        cfg = replace(cfg, onboard_model=Path(args.onboard_model))
    if args.onboard_over_link:
        cfg = replace(cfg, onboard_over_link=True)
    if args.rehearsal_dir:
        cfg = replace(cfg, rehearsal_dir=Path(args.rehearsal_dir))
    if args.station:
        cfg = replace(cfg, station=station_name(args.station, "--station"))
    return replace(
        cfg, link=link, zenoh=z, delivery=delivery, resume=cfg.resume and not args.no_resume
    )


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    logging.basicConfig(
        level=args.log_level.upper(),
        format="%(asctime)s modd-subbroker %(levelname)s %(name)s: %(message)s",
    )
    # `kill -USR1 <pid>` prints every thread's stack to stderr: what a stuck SubBroker waits on
    faulthandler.register(signal.SIGUSR1, all_threads=True)
    try:
        config = build_config(args)
        from .broker import SubBroker

        broker = SubBroker(config)
        broker.start()
    except (ConfigError, ValueError) as exc:
        print(f"modd-subbroker: {exc}", file=sys.stderr)
        return 2
    done = threading.Event()
    stop_on_signals(done)
    done.wait()
    logging.getLogger("modd.subbroker").info("stopping")
    broker.stop()
    return 0


if __name__ == "__main__":
    sys.exit(main())
