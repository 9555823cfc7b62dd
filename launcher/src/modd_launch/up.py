"""``modd up MODEL [--simulate] [--part drone|station|all]``: run a model on this
machine — the on-board PubBroker, the base-station SubBroker and, with
``--simulate``, a simulated drone (simulated sensors and autopilot, and the
MAVLink bridge) — from configs generated from the model. A process that dies
is restarted with a backoff, as systemd does on a drone (:mod:`modd.supervise`:
1 s doubling to 30 s, at most 5 restarts in 5 minutes, then the run stops).
Stops everything (by PID, in reverse order) on Ctrl-C or SIGTERM.

Options:

- Sensors of ``kind nmea``, ``ascii`` or ``modbus`` are read by ``modd-sensors``
  from their devices (with ``--simulate``: from the simulator's pseudo-terminals,
  linked under ``<workdir>/devices``); each sensor's health is kept in
  ``<workdir>/sensors.json`` (docs/sensors.md). It runs even when the model has
  none (idle, it follows the on-board model file: a deploy that adds the first
  instrument needs no restart).
- ``--simulate``: also run ``modd-sim`` (the simulated drone) against the
  PubBroker's ingress and the MAVLink bridge ``modd-mavlink`` (idle while the
  model has no ``kind mavlink`` sensor) reading the simulator's autopilot over UDP
  on a loopback port picked free for this run, so that two runs at once do
  not collide (docs/mavlink.md).
- ``--part drone|station|all`` (default ``all``): which side of the link runs
  here. ``drone`` runs the PubBroker (and, with ``--simulate``, the simulator
  and the bridge); ``station`` runs the SubBroker only, which connects to the
  PubBroker at the link endpoint the model declares; ``all`` runs both.
- ``--zenoh-listen ENDPOINT`` / ``--zenoh-connect ENDPOINT`` (repeatable):
  the SubBroker's zenoh endpoints (e.g. ``--zenoh-connect tcp/127.0.0.1:7447``
  to join a zenoh router); ignored by ``--part drone``.
- ``--workdir DIR``: the run directory.
- ``--credentials DIR``: the SubBroker's zenoh credentials and deploy key
  (default ``<workdir>/credentials``), made 0600 at first start; ``modd up``
  prints which file a viewer connects with, never a password
  (docs/security.md).

- ``--vehicle NAME`` (repeatable): of a model with a ``Campaign``, run these
  vehicles only (default: every one). A campaign runs as one supervised run
  (:mod:`modd_launch.campaign_up`, docs/operations.md "A campaign").

Link endpoints are always the model's. With ``--part all`` and no key in the
environment, a random link key is made for the run; with ``--part drone`` or
``station`` both sides must share the key the model's ``keyRef`` names (by
default ``$MODD_LINK_KEY``), else ``modd up`` refuses to start.

The run directory (``--workdir``, default ``<runtime dir>/<drone>`` where the
runtime dir is ``$XDG_RUNTIME_DIR/modd-up`` or ``/tmp/modd-up-<uid>``) holds
the generated configs, the archive, the ingress socket and each process's log,
so that a run never writes to the paths of a real drone's model. It is private
(0700): one owned by another user, or reached through a symbolic link, is
refused."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from .drone import (  # noqa: F401  (prepare, rehearsal_dir, Process: importable from here as before)
    Process,
    UpError,
    credentials,
    prepare,
    ready,
    rehearsal_dir,
    run_dir,
    supervised,
    viewer_hint,
)


def run(args: argparse.Namespace) -> int:
    from modd_model import load_or_report
    from modd_model.campaign import vehicles

    model = load_or_report(args.model)
    if model is None:
        return 1
    if vehicles(model):
        from .campaign_up import run_campaign

        return run_campaign(args, model)
    if args.vehicle and set(args.vehicle) != {model["drone"]["name"]}:
        print(
            f"modd up: {args.model} has no Campaign: --vehicle names a campaign's vehicles",
            file=sys.stderr,
        )
        return 1
    try:
        workdir = run_dir(args.workdir, model["drone"]["name"])
        store = credentials(args, workdir / "credentials")
        local, stack, env = ready(args, model, workdir)
    except (ValueError, UpError) as exc:
        print(f"modd up: {exc}", file=sys.stderr)
        return 1

    def running() -> None:
        station = args.part == "station"
        where = f"logs in {workdir}" if station else f"archive in {workdir / 'archive'}"
        drone = local["drone"]["name"]
        print(f"modd up: drone {drone} ({args.part}) running; {where}; Ctrl-C to stop", flush=True)
        if args.part != "drone":
            print(viewer_hint(args, store), flush=True)

    code, gave_up = supervised(stack, env, running)
    if gave_up and args.part != "drone":  # the workbench is told why the run stopped
        from .announce import announce_stop, settings_for

        announce_stop(
            settings_for(args.zenoh_listen or [], args.zenoh_connect or []),
            store,
            local["drone"]["name"],
            gave_up[0],
        )
    return code


def register(sub: Any) -> None:
    p = sub.add_parser("up", help="run a model locally: PubBroker, SubBroker, simulated sensors")
    p.add_argument("model", metavar="MODEL", help=".modd or .json model")
    p.add_argument(
        "--simulate",
        action="store_true",
        help="also run the simulated drone (sensors, autopilot) and the MAVLink bridge",
    )
    p.add_argument(
        "--workdir",
        metavar="DIR",
        help="run directory, private "
        "(default $XDG_RUNTIME_DIR/modd-up/<drone> or /tmp/modd-up-<uid>/<drone>)",
    )
    p.add_argument(
        "--credentials",
        metavar="DIR",
        help="zenoh credentials and deploy key, "
        "made at first start (default <workdir>/credentials)",
    )
    p.add_argument(
        "--part",
        choices=("drone", "station", "all"),
        default="all",
        help="drone: PubBroker (+ simulator and bridge); station: SubBroker; all: both (default)",
    )
    p.add_argument(
        "--zenoh-listen",
        action="append",
        default=None,
        metavar="ENDPOINT",
        help="the SubBroker's zenoh listen endpoint (repeatable; default tcp/127.0.0.1:7447)",
    )
    p.add_argument(
        "--zenoh-connect",
        action="append",
        default=None,
        metavar="ENDPOINT",
        help="a zenoh endpoint the SubBroker connects to (repeatable)",
    )
    p.add_argument(
        "--resume",
        action="store_true",
        help="resume the deployment (and dynamic subscriptions) a workbench made "
        "in an earlier run of this drone, instead of running MODEL",
    )
    p.add_argument(
        "--link",
        choices=("tcp", "udp", "serial"),
        default=None,
        help="the link's transport for this run (default: the model's); serial "
        "runs the radio emulator between two pseudo-terminals",
    )
    p.add_argument(
        "--radio",
        metavar="SPEC",
        default=None,
        help="an emulated radio in the path (udp or serial), e.g. "
        '"rate=3600,loss=0.05,latency_ms=80" (modd-radio --help)',
    )
    p.add_argument(
        "--vehicle",
        action="append",
        default=None,
        metavar="NAME",
        help="a campaign: run this vehicle (repeatable; default every vehicle)",
    )
    p.set_defaults(func=run)
