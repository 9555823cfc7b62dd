"""``modd up CAMPAIGN`` of a model with a ``Campaign`` (docs/dsl.md, "Campaigns"):
every vehicle (or those ``--vehicle`` names) brought up on this machine as one
supervised run, each as ``modd up`` runs one drone — its expanded model
(:func:`modd_model.campaign.expand`), its own PubBroker on the vehicle's endpoint,
instruments (simulated with ``--simulate``), SubBroker, link key and run directory
``<workdir>/<vehicle>`` — under one restart policy (docs/operations.md, "A campaign").

Zenoh: one station router (``python -m modd.station``, the access control of every
drone) listens on ``--zenoh-listen`` (default ``tcp/127.0.0.1:7447``) and each
vehicle's SubBroker joins it as a client, so that a viewer or the backend connects
to one endpoint for every drone (``modd/<drone>/...`` keys). With ``--zenoh-connect``
instead, no router runs here: the SubBrokers join the one given. The credentials
directory (``--credentials``, default ``<workdir>/credentials``) is the campaign's:
one ``backend.cred`` and ``deploy.key`` reach every drone.

Failure, as for one drone: a process that dies is restarted with the backoff of
:mod:`modd.supervise` while the other vehicles run; one that dies more often than
the policy allows stops the whole campaign (every vehicle, by PID), reported by
vehicle and process, and its drone's status says why. A vehicle that cannot start
(no link key for ``--part drone``, a binary missing) fails the up before anything
runs.

>>> connect_to("tcp/0.0.0.0:7447")
'tcp/127.0.0.1:7447'
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from modd.zenoh_auth import CredentialStore, private_dir
from modd.zenoh_session import DEFAULT_ENDPOINT

from .drone import Process, Stack, UpError, credentials, ready, run_dir, supervised, viewer_hint

#: How long the station router may take to listen before the up fails.
ROUTER_WAIT_S = 20.0
ROUTER_UP = "station router up"


@dataclass
class Vehicle:
    """One vehicle's part of the run."""

    name: str
    workdir: Path
    local: dict[str, Any]
    processes: list[Process]


def selected(model: dict[str, Any], names: list[str] | None) -> dict[str, dict[str, Any]]:
    """The drone models of the vehicles to run (``--vehicle``, else every one)."""
    from modd_model.campaign import expand

    drones = expand(model)
    for name in names or []:
        if name not in drones:
            known = ", ".join(drones)
            raise UpError(f"--vehicle {name}: the campaign has no such vehicle ({known})")
    return {n: m for n, m in drones.items() if not names or n in names}


def connect_to(endpoint: str) -> str:
    """Where a client on this machine reaches a router listening on ``endpoint``."""
    for any_host, local in (("/0.0.0.0:", "/127.0.0.1:"), ("/[::]:", "/[::1]:")):
        endpoint = endpoint.replace(any_host, local)
    return endpoint


def start_router(args: argparse.Namespace, top: Path, store: CredentialStore) -> Process:
    """The campaign's station router, started and listening (UpError otherwise)."""
    argv = [sys.executable, "-m", "modd.station", "--credentials", str(store.dir)]
    for endpoint in args.zenoh_listen or [DEFAULT_ENDPOINT]:
        argv += ["--listen", endpoint]
    router = Process("station", argv, top / "logs" / "station.log")
    router.log.unlink(missing_ok=True)  # an earlier run's "up" line must not be read
    router.start(dict(os.environ))
    print(f"modd up: started station (pid {router.pid()}), log {router.log}", flush=True)
    deadline = time.monotonic() + ROUTER_WAIT_S
    while ROUTER_UP not in router.log.read_text(errors="replace"):
        if router.exit_code() is not None or time.monotonic() > deadline:
            router.stop()
            raise UpError(f"the station router did not start; see {router.log}")
        time.sleep(0.1)
    return router


def vehicle(
    args: argparse.Namespace, name: str, model: dict[str, Any], top: Path, connect: list[str]
) -> Vehicle:
    """One vehicle made ready (its radio, when it needs one, started): its processes
    named ``<vehicle>/<process>``, its SubBroker a client of the campaign's router."""
    own = argparse.Namespace(**vars(args))
    own.zenoh_listen, own.zenoh_connect = None, list(connect)
    workdir = private_dir(top / name)
    try:
        local, stack, key = ready(own, model, workdir)
    except UpError as exc:
        raise UpError(f"vehicle {name}: {exc}") from exc
    for p in stack.processes:
        if p.name == "subbroker":
            p.argv += ["--zenoh-mode", "client"]  # its router is the campaign's
        p.name, p.env = f"{name}/{p.name}", key
    return Vehicle(name, workdir, local, stack.processes)


def status_line(v: Vehicle, part: str) -> str:
    """What runs for one drone, in one line."""
    ep = v.local["pubBroker"]["endpoint"]
    pids = ", ".join(f"{p.name.split('/', 1)[1]} {p.pid()}" for p in v.processes)
    values = f"; values on modd/{v.name}/sub/*" if part != "drone" else ""
    return (
        f"modd up: drone {v.name} ({part}) running: PubBroker {ep['host']}:{ep['port']}"
        f"{values}; pids {pids}; run directory {v.workdir}"
    )


def run_campaign(args: argparse.Namespace, model: dict[str, Any]) -> int:
    """Bring up the campaign's vehicles as one supervised run; the exit code."""
    campaign = str(model["campaign"]["name"])
    processes: list[Process] = []
    try:
        chosen = selected(model, args.vehicle)
        if args.zenoh_listen and args.zenoh_connect:
            raise UpError(
                "a campaign: --zenoh-listen (its router runs here) or --zenoh-connect "
                "(its SubBrokers join a router running elsewhere), not both"
            )
        top = run_dir(args.workdir, campaign)
        store = credentials(args, top / "credentials")
        own_router = args.part != "drone" and not args.zenoh_connect
        listen = list(args.zenoh_listen or [DEFAULT_ENDPOINT]) if own_router else []
        if own_router:
            processes.append(start_router(args, top, store))
        connect = args.zenoh_connect or [connect_to(e) for e in listen]
        vehicles = []
        for name, drone in chosen.items():
            vehicles.append(vehicle(args, name, drone, top, connect))
            processes += vehicles[-1].processes
    except (ValueError, UpError) as exc:
        Stack([p for p in processes if p.popen is not None]).stop()  # the router, radios
        print(f"modd up: {exc}", file=sys.stderr)
        return 1

    def running() -> None:
        for v in vehicles:
            print(status_line(v, args.part), flush=True)
        where = f"; zenoh {', '.join(listen or connect)}" if listen or connect else ""
        print(
            f"modd up: campaign {campaign}: {len(vehicles)} drones running "
            f"({', '.join(v.name for v in vehicles)}){where}; Ctrl-C to stop",
            flush=True,
        )
        if args.part != "drone":
            hint = argparse.Namespace(zenoh_listen=[(listen or connect)[0]])
            print(viewer_hint(hint, store), flush=True)

    code, gave_up = supervised(Stack(processes), {}, running)
    if gave_up:
        said_stop(args, gave_up[0], campaign, store, (listen, connect if not listen else []))
    return code


def said_stop(
    args: argparse.Namespace,
    why: dict[str, Any],
    campaign: str,
    store: CredentialStore,
    endpoints: tuple[list[str], list[str]],
) -> None:
    """The run gave up: which vehicle, on stderr and on its drone's status key."""
    drone, slash, _ = str(why["process"]).partition("/")
    what = f"vehicle {drone}" if slash else "the station router"
    print(
        f"modd up: {what} failed; every drone of campaign {campaign} was stopped",
        file=sys.stderr,
        flush=True,
    )
    if slash and args.part != "drone":  # the workbench is told why that drone stopped
        from .announce import announce_stop, settings_for

        announce_stop(settings_for(*endpoints), store, drone, why)
