"""One drone's run for ``modd up`` (:mod:`modd_launch.up`, the command, and
:mod:`modd_launch.campaign_up`, a campaign's vehicles): its processes from configs
generated from its model, started in order, restarted when they die and stopped in
reverse (:mod:`modd.supervise`), its run directory, credentials and link key."""

from __future__ import annotations

import argparse
import json
import os
import secrets
import shutil
import signal
import subprocess
import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from modd import uplink
from modd.ports import free_port
from modd.supervise import tied_to_parent, watch
from modd.zenoh_auth import CredentialStore, private_dir
from modd.zenoh_session import DEFAULT_ENDPOINT

REPO = Path(__file__).resolve().parents[3]
STOP_TIMEOUT_S = 10.0


def pubbroker_binary() -> Path:
    """``$MODD_PUBBROKER``, else the repository's build, else ``modd-pubbroker`` on PATH."""
    if env := os.environ.get("MODD_PUBBROKER"):
        return Path(env)
    built = REPO / "build" / "bin" / "modd-pubbroker"
    if built.is_file():
        return built
    found = shutil.which("modd-pubbroker")
    if found:
        return Path(found)
    raise FileNotFoundError("modd-pubbroker not found: run `make build`, or set MODD_PUBBROKER")


@dataclass
class Process:
    name: str
    argv: list[str]
    log: Path
    popen: subprocess.Popen[bytes] | None = None
    restartable: bool = True  # the serial radio is not: its pseudo-terminals would change
    # sent by the kernel when modd up dies: SIGTERM lets the brokers close their files;
    # the simulator and the bridge hold nothing to save and go at once
    death_signal: int = signal.SIGTERM
    # added to the run's environment: a campaign vehicle's own link key
    env: dict[str, str] = field(default_factory=dict)

    def exit_code(self) -> int | None:
        return self.popen.poll() if self.popen is not None else None

    def pid(self) -> int | None:
        return self.popen.pid if self.popen is not None else None

    def start(self, env: dict[str, str]) -> None:
        self.log.parent.mkdir(parents=True, exist_ok=True)
        with self.log.open("ab") as out:
            self.popen = subprocess.Popen(
                self.argv,
                stdout=out,
                stderr=subprocess.STDOUT,
                env={**env, **self.env},
                start_new_session=True,  # Ctrl-C in a terminal reaches modd up alone
                preexec_fn=tied_to_parent(self.death_signal),  # a killed modd up takes them along
            )

    def stop(self) -> int | None:
        """SIGTERM, then SIGKILL after STOP_TIMEOUT_S; the exit code."""
        p = self.popen
        if p is None:
            return None
        if p.poll() is None:
            p.send_signal(signal.SIGTERM)
            try:
                p.wait(STOP_TIMEOUT_S)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()
        return p.returncode


@dataclass
class Stack:
    """The processes of one local run, started in order and stopped in reverse."""

    processes: list[Process] = field(default_factory=list)

    def start(self, env: dict[str, str]) -> None:
        for p in self.processes:
            if p.popen is not None:
                continue  # started before the others (the radio emulator)
            p.start(env)
            assert p.popen is not None
            print(f"modd up: started {p.name} (pid {p.popen.pid}), log {p.log}", flush=True)

    def stop(self) -> None:
        for p in reversed(self.processes):
            code = p.stop()
            print(f"modd up: stopped {p.name} (exit {code})", flush=True)


def prepare(
    model: dict[str, Any],
    workdir: Path,
    transport: str | None = None,
    devices: tuple[str, str] | None = None,
) -> tuple[dict[str, Any], Path]:
    """The model as run locally (archive and config dirs under workdir, the
    run's transport) and the directory of the generated operator configs."""
    from modd_gen import generate, write_artifacts

    local = json.loads(json.dumps(model))
    if transport is not None:
        uplink.apply(local, transport, devices)
    local["pubBroker"]["logPath"] = str(workdir / "archive")
    local["pubBroker"].setdefault("ingress", {})["unixSocket"] = str(workdir / "ingress.sock")
    local["subBroker"]["configPath"] = str(workdir / "state")
    write_artifacts(workdir / "generated", generate(local, "operator"))
    return local, workdir / "generated" / "operator"


def simulation(
    model: dict[str, Any], model_json: Path, bin_dir: Path, logs: Path, onboard: Path
) -> list[Process]:
    """The MAVLink bridge, then the simulator, whose autopilot (when the model has
    mavlink sensors) the bridge reads on a loopback UDP port of this run (bridge first:
    it listens). The bridge runs even when the model has no mavlink sensor: idle, it
    applies a deploy that adds the first without a restart."""
    sim = bin_dir / "modd-sim"
    bridge = bin_dir / "modd-mavlink"
    for binary, what in ((sim, "the drone simulator"), (bridge, "the MAVLink bridge")):
        if not binary.exists():
            raise FileNotFoundError(f"{binary} not found: {what} is not installed")
    port = free_port("udp")
    bridge_argv = [str(bridge), "--model", str(onboard), "--connect", f"udpin:127.0.0.1:{port}"]
    sim_argv = [str(sim), "--model", str(model_json), "--mavlink", f"udpout:127.0.0.1:{port}"]
    return [
        Process(
            "bridge",
            [*bridge_argv, *following(model)],
            logs / "bridge.log",
            death_signal=signal.SIGKILL,
        ),
        Process("simulator", sim_argv, logs / "simulator.log", death_signal=signal.SIGKILL),
    ]


def build_stack(
    args: argparse.Namespace, model: dict[str, Any], workdir: Path, configs: Path
) -> Stack:
    logs = workdir / "logs"
    bin_dir = Path(sys.executable).parent
    drone, station = args.part in ("drone", "all"), args.part in ("station", "all")
    stack = Stack()
    if drone:
        stack.processes.append(
            Process(
                "pubbroker",
                [str(pubbroker_binary()), "--config", str(configs / "pubbroker.json")],
                logs / "pubbroker.log",
            )
        )
    if station:
        sub = [
            str(bin_dir / "modd-subbroker"),
            "--config",
            str(configs / "subbroker.toml"),
            "--credentials",
            str(args.credentials_dir),
            "--record-dir",
            str(workdir / "records"),
        ]  # the base-station record
        for endpoint in args.zenoh_listen or ():
            sub += ["--zenoh-listen", endpoint]
        for endpoint in args.zenoh_connect or ():
            sub += ["--zenoh-connect", endpoint]
        if not args.resume:
            sub.append("--no-resume")  # what runs is MODEL, not an earlier run's deployment
        if getattr(args, "relay", None):
            sub += ["--link", "{}:{}".format(*args.relay)]
        if getattr(
            args, "simulate", False
        ):  # a simulated drone: its link can be cut for a rehearsal
            sub += ["--rehearsal-dir", str(rehearsal_dir(workdir))]
        stack.processes.append(Process("subbroker", sub, logs / "subbroker.log"))
    onboard = onboard_model(configs, workdir) if drone else None
    # an acked deploy reaches the on-board processes over the link (ONBOARD): the
    # PubBroker writes it to the on-board model file, modd-sensors and modd-mavlink follow
    if onboard is not None:
        pub_process = next(p for p in stack.processes if p.name == "pubbroker")
        pub_process.argv += ["--onboard-model", str(onboard)]
    if station:
        sub_process = next(p for p in stack.processes if p.name == "subbroker")
        sub_process.argv.append("--onboard-over-link")
    if onboard is not None:  # nmea, ascii, modbus: read by modd-sensors, idle while the
        # model has none (a deploy that adds the first needs no restart)
        sensors = [str(bin_dir / "modd-sensors"), "--model", str(onboard)]
        sensors += ["--status-file", str(workdir / "sensors.json"), *following(model)]
        if args.simulate:
            sensors += ["--device-dir", str(workdir / "devices")]
        stack.processes.append(Process("sensors", sensors, logs / "sensors.log"))
    if args.simulate and drone:
        assert onboard is not None
        stack.processes += simulation(model, configs / "model.json", bin_dir, logs, onboard)
    return stack


def onboard_model(configs: Path, workdir: Path) -> Path:
    """The on-board processes' model file (modd.onboard), the generated model at start;
    a deploy the PubBroker acks replaces it, and modd-sensors and modd-mavlink follow."""
    folder = workdir / "onboard"
    folder.mkdir(mode=0o700, exist_ok=True)
    shutil.rmtree(folder / "applied", ignore_errors=True)  # an earlier run's answers
    path = folder / "model.json"
    shutil.copyfile(configs / "model.json", path)
    return path


def following(model: dict[str, Any]) -> list[str]:
    """--watch and the run's ingress (a deployed model names the drone's own, not the run's)."""
    from modd_model.ingress import ingress_of

    return ["--watch", "--ingress", ingress_of(model).address]


class UpError(Exception):
    """Why ``modd up`` cannot start, said as it is (``modd up: <message>``)."""


def credentials(args: argparse.Namespace, default: Path) -> CredentialStore:
    """The SubBrokers' credentials (``--credentials``, else ``default``), made at first start
    (ValueError for a directory that cannot be used); sets ``args.credentials_dir``."""
    args.credentials_dir = Path(args.credentials or default).absolute()
    store = CredentialStore(args.credentials_dir)
    if args.part != "drone":
        for name in store.ensure().remade:
            print(
                f"modd up: {store.dir / name} was missing and was made anew with a new "
                "secret: copies of it handed out before no longer work",
                file=sys.stderr,
                flush=True,
            )
    return store


def ready(
    args: argparse.Namespace, model: dict[str, Any], workdir: Path
) -> tuple[dict[str, Any], Stack, dict[str, str]]:
    """One drone's run, ready to start: the model as run, its processes (the radio
    emulator, already started when the run needs one, first) and what the run adds to
    the environment (a link key made for it). UpError when it cannot run; nothing of
    it is left running then."""
    try:
        radio, devices = start_radio(args, model, workdir)
    except (uplink.LinkSetupError, FileNotFoundError) as exc:
        raise UpError(str(exc)) from exc
    try:
        if args.simulate:  # simulated instruments on pseudo-terminals of this run, never real ones
            from modd.sim.instruments import simulated_devices

            model = simulated_devices(model, workdir / "devices")
        local, configs = prepare(model, workdir, args.transport, devices)
        if args.part != "drone":
            print(kept_note(workdir / "state", args.resume), end="", flush=True)
        key = link_key(args, local)
        stack = build_stack(args, local, workdir, configs)
    except (UpError, FileNotFoundError) as exc:
        if radio is not None:
            radio.stop()
        raise UpError(str(exc)) from exc
    if radio is not None:
        stack.processes.insert(0, radio)  # stopped last
    return local, stack, key


def link_key(args: argparse.Namespace, local: dict[str, Any]) -> dict[str, str]:
    """The environment variable of the link key the run makes (``--part all`` and none in
    the environment: a random key for this run only), or nothing; UpError when a part
    run here alone has none (the other part runs elsewhere: a key made up here could
    never match its key)."""
    key_ref = local.get("link", {}).get("keyRef") or "env:MODD_LINK_KEY"
    kind, _, name = key_ref.partition(":")
    if kind != "env" or os.environ.get(name):
        return {}
    if args.part != "all":
        raise UpError(
            f"--part {args.part} needs the link key in ${name} (the model's "
            f"keyRef {key_ref}), the same on the drone and the station"
        )
    return {name: secrets.token_hex(16)}


def supervised(
    stack: Stack, key: dict[str, str], running: Callable[[], None]
) -> tuple[int, list[dict[str, Any]]]:
    """Start the stack, say it runs (``running``), restart what dies (modd.supervise)
    until Ctrl-C or SIGTERM, then stop it all: the exit code and, when the run gave
    up, which process and why."""
    stopping = False

    def on_signal(_sig: int, _frame: object) -> None:
        nonlocal stopping
        stopping = True

    signal.signal(signal.SIGINT, on_signal)
    signal.signal(signal.SIGTERM, on_signal)
    env = {**os.environ, **key}
    stack.start(env)
    running()
    code = 1
    gave_up: list[dict[str, Any]] = []
    try:
        code = watch(
            stack.processes,
            env,
            lambda: stopping,
            say=lambda line: print(line, file=sys.stderr, flush=True),
            gave_up=gave_up.append,
        )
    finally:
        stack.stop()
    return code, gave_up


def kept_note(state: Path, resume: bool) -> str:
    """What happens to a deployment an earlier run kept in ``state``."""
    from modd.subbroker.kept import StateDir

    kept = StateDir(state).load_deployment()
    if kept is None:
        return ""
    where = state / "deployed.json"
    if resume:
        return (
            f"modd up: --resume: the SubBroker resumes the deployment kept in {where} "
            f"({kept[1].describe()}), not MODEL\n"
        )
    return (
        f"modd up: running MODEL; the deployment kept in {where} ({kept[1].describe()}) "
        "is not resumed (--resume resumes it)\n"
    )


def start_radio(
    args: argparse.Namespace, model: dict[str, Any], workdir: Path
) -> tuple[Process | None, tuple[str, str] | None]:
    """Check --link/--radio; start the emulator when the run needs one (serial
    with both parts here: always, it makes the pseudo-terminals; udp: with
    --radio). Returns it (started) and, over serial, the (base, drone) devices."""
    args.relay = None
    transport = uplink.check(args.link, args.radio, model)
    args.transport = transport if args.link or args.radio else None  # None: the model's own
    needs = (transport == "serial" and args.part == "all") or (
        transport == "udp" and args.radio is not None
    )
    if args.radio is not None and args.part != "all":
        raise uplink.LinkSetupError("--radio needs both ends of the link here (--part all)")
    if not needs:
        return None, None
    ep = model["pubBroker"]["endpoint"]
    argv, args.relay = uplink.radio_argv(
        Path(sys.executable).parent, transport, args.radio, (str(ep["host"]), int(ep["port"]))
    )
    radio = Process(
        "radio", argv, workdir / "logs" / "radio.log", restartable=transport != "serial"
    )
    if radio.log.exists():
        radio.log.unlink()  # the devices line of an earlier run must not be read
    radio.start(dict(os.environ))
    assert radio.popen is not None
    print(f"modd up: started radio (pid {radio.popen.pid}), log {radio.log}", flush=True)
    if transport != "serial":
        return radio, None
    try:
        return radio, uplink.wait_devices(radio.log)
    except uplink.LinkSetupError:
        radio.stop()
        raise


def rehearsal_dir(workdir: Path) -> Path:
    """``<workdir>/rehearsal``, made private and with the link restored (an earlier run's cut
    is not carried over): where ``modd link cut`` and the workbench cut the simulated link."""
    from modd.subbroker.rehearsal import FOLDER, set_cut

    folder = private_dir(workdir / FOLDER)
    set_cut(folder, False)
    return folder


def run_dir(workdir: str | None, drone: str) -> Path:
    """The run directory, private to this user (0700; ValueError when another
    user owns it or a symbolic link leads there)."""
    if workdir:
        return private_dir(Path(workdir).absolute())
    runtime = os.environ.get("XDG_RUNTIME_DIR")
    base = Path(runtime) / "modd-up" if runtime else Path(f"/tmp/modd-up-{os.getuid()}")
    private_dir(base)
    return private_dir(base / drone)


def viewer_hint(args: argparse.Namespace, store: CredentialStore) -> str:
    """How a viewer connects (which file holds its credentials), never a password."""
    endpoint = (args.zenoh_listen or [DEFAULT_ENDPOINT])[0]
    return (
        f"modd up: zenoh {endpoint} requires credentials; a viewer connects with "
        f"modd.subscribe(DRONE, SUBSCRIBER, connect={endpoint!r}, "
        f"credentials={str(store.cred_file('viewer'))!r}) (the workbench: "
        f"modd-backend --zenoh-credentials {store.cred_file('backend')} "
        f"--deploy-key {store.deploy_key_file})"
    )
