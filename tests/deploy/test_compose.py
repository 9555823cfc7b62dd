"""docker-compose.yml without Docker: the file is read and checked against the
repository (images, Dockerfiles and what they copy, commands, files, ports,
the environment file), then every project service is started from its own
command on loopback and must become ready (compose.py says how a container's
view is mapped onto this machine)."""

from __future__ import annotations

import fnmatch
import json
import os
import re
import secrets
import signal
import subprocess
import sys
import tempfile
import time
import tomllib
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from modd_model import load_model

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from compose import (  # noqa: E402
    ENV_EXAMPLE,
    REPO,
    Image,
    Loopback,
    copy_sources,
    env_file,
    instructions,
    interpolate,
    load_compose,
    modd_commands,
    project_scripts,
)
from support.loopback import (  # noqa: E402
    VENV_BIN,
    Backend,
    Proc,
    StatusWatch,
    free_port,
    receive_until,
    zenoh_router,
)

SERVICES = {"credentials", "zenoh-router", "backend", "subbroker", "drone"}
ROUTER = "zenoh-router"


@pytest.fixture(scope="module")
def compose() -> dict[str, Any]:
    return load_compose()


def services(compose: dict[str, Any]) -> dict[str, dict[str, Any]]:
    found: dict[str, dict[str, Any]] = compose["services"]
    return found


def dockerfile(service: dict[str, Any]) -> Path | None:
    build = service.get("build")
    if build is None:
        return None
    if isinstance(build, str):
        return REPO / build / "Dockerfile"
    return REPO / str(build.get("context", ".")) / str(build.get("dockerfile", "Dockerfile"))


def image_of(service: dict[str, Any]) -> Image:
    path = dockerfile(service)
    assert path is not None
    return Image.read(path)


def argv_of(service: dict[str, Any]) -> list[str]:
    """What the container runs: ENTRYPOINT + CMD, each from compose or else the image."""
    image = image_of(service)
    entry = service.get("entrypoint", image.entrypoint)
    command = service.get("command", image.cmd)
    assert isinstance(entry, list) and isinstance(command, list), (
        "entrypoint and command must be lists (exec form: signals reach the process)"
    )
    return [str(w) for w in [*entry, *command]]


def image_paths(path: Path) -> set[str]:
    """Paths (relative to WORKDIR) that the final stage copies from another stage:
    build outputs that are not in a checkout."""
    out: set[str] = set()
    for instr, args in instructions(path):
        if instr == "FROM":
            out = set()
        elif instr == "COPY" and "--from=" in args:
            out.add(args.split()[-1].rstrip("/"))
    return out


def dockerignore() -> list[str]:
    lines = (REPO / ".dockerignore").read_text().splitlines()
    return [ln.strip() for ln in lines if ln.strip() and not ln.startswith("#")]


# -- the file, read -----------------------------------------------------------------------


def test_the_services_are_the_router_backend_subbroker_and_drone(compose: dict[str, Any]) -> None:
    assert set(services(compose)) == SERVICES


def test_each_service_has_an_image_or_a_dockerfile(compose: dict[str, Any]) -> None:
    for name, svc in services(compose).items():
        path = dockerfile(svc)
        assert "image" in svc or path is not None, f"{name}: neither image nor build"
        if path is not None:
            assert path.is_file(), f"{name}: {path} does not exist"
        elif not str(svc["image"]).startswith("modd-"):
            tag = str(svc["image"]).rpartition(":")[2]
            assert re.fullmatch(r"\d+(\.\d+)+", tag), f"{name}: pin a version, not {tag!r}"
    assert services(compose)[ROUTER]["image"].startswith("eclipse/zenoh:")


def test_every_copy_source_exists_and_is_in_the_context(compose: dict[str, Any]) -> None:
    files = {p for svc in services(compose).values() if (p := dockerfile(svc))}
    assert files, "no project image"
    ignored = dockerignore()
    for path in files:
        for src in copy_sources(path):
            assert list(REPO.glob(src)), f"{path.name}: COPY {src}: not in the repository"
            hit = [
                pat
                for pat in ignored
                if fnmatch.fnmatch(src, pat) or src.startswith(pat.rstrip("/") + "/")
            ]
            assert not hit, f"{path.name}: COPY {src} is excluded by .dockerignore ({hit})"


def test_every_command_is_something_the_project_provides(compose: dict[str, Any]) -> None:
    scripts, subcommands = project_scripts(), modd_commands()
    for name, svc in services(compose).items():
        if dockerfile(svc) is None:
            continue
        image = image_of(svc)
        checks = [argv_of(svc)]
        if "healthcheck" in svc:
            test = svc["healthcheck"]["test"]
            assert test[0] == "CMD", f"{name}: healthcheck in exec form"
            checks.append(test[1:])
        for argv in checks:
            exe = argv[0]
            if exe == "python":
                if argv[1] != "-c":
                    assert (REPO / argv[1]).is_file(), f"{name}: {argv[1]} is not in the repo"
            elif exe.startswith("/") or "/" in exe:
                rel = os.path.relpath(exe, image.workdir) if exe.startswith("/") else exe
                assert (REPO / rel).exists(), f"{name}: {exe} is not provided"
            else:
                assert exe in scripts, f"{name}: {exe} is no [project.scripts] entry"
                if exe == "modd":
                    assert argv[1] in subcommands, f"{name}: modd has no command {argv[1]}"
    drone = argv_of(services(compose)["drone"])
    assert "up" in subcommands and "--part" in drone  # drone.py runs `modd up ... --part drone`


def test_every_referenced_file_exists(compose: dict[str, Any]) -> None:
    for name, svc in services(compose).items():
        path = dockerfile(svc)
        if path is None:
            continue
        built = image_paths(path)
        for word in argv_of(svc):
            if word.startswith("-") or ":" in word or "/" not in word or word.startswith("/"):
                continue
            assert (REPO / word).exists() or word in built, f"{name}: {word} does not exist"
            if word.endswith(".toml"):  # a SubBroker config: its model too
                model = tomllib.loads((REPO / word).read_text())["model"]
                assert ((REPO / word).parent / model).is_file(), f"{name}: {word}: {model}"


def test_ports_are_published_on_loopback_only(compose: dict[str, Any]) -> None:
    for name, svc in services(compose).items():
        assert svc.get("network_mode") != "host", name
        for port in svc.get("ports", []):
            if isinstance(port, dict):
                assert port.get("host_ip") == "127.0.0.1", f"{name}: {port}"
            else:
                assert str(port).startswith("127.0.0.1:"), f"{name}: {port} is not loopback"


def test_volumes_are_declared_and_secrets_come_from_the_env_file(compose: dict[str, Any]) -> None:
    declared = set(compose.get("volumes") or {})
    for name, svc in services(compose).items():
        for vol in svc.get("volumes", []):
            source = str(vol).split(":")[0]
            if not source.startswith((".", "/")):
                assert source in declared, f"{name}: volume {source} is not declared"
    example = env_file()
    used = set(re.findall(r"\$\{(\w+)", (REPO / "docker-compose.yml").read_text()))
    assert used <= set(example), f"not in .env.example: {used - set(example)}"
    assert all(v == "" for v in example.values()), ".env.example must hold no secret"
    for name in ("drone", "subbroker"):
        assert "MODD_LINK_KEY" in services(compose)[name]["environment"], name
    with pytest.raises(KeyError, match="MODD_LINK_KEY"):  # compose refuses an empty key
        interpolate(services(compose)["drone"]["environment"]["MODD_LINK_KEY"], example)


# -- the services, started --------------------------------------------------------------------


def start_order(compose: dict[str, Any]) -> list[str]:
    """Services after those they depend on."""
    order: list[str] = []

    def visit(name: str) -> None:
        if name not in order:
            for dep in services(compose)[name].get("depends_on", []):
                visit(dep)
            order.append(name)

    for name in services(compose):
        visit(name)
    return order


class Run:
    """The project's services of docker-compose.yml as processes on loopback."""

    def __init__(self, compose: dict[str, Any], tmp: Path) -> None:
        self.compose = compose
        self.lb = Loopback(tmp, set(services(compose)), free_port)
        self.env = {k: v or secrets.token_hex(16) for k, v in env_file(ENV_EXAMPLE).items()}
        self.procs: dict[str, Proc] = {}
        self.tmp = tmp

    def router_port(self) -> int:
        argv = services(self.compose)[ROUTER]["command"]
        listen = self.lb.endpoints(argv[argv.index("--listen") + 1])
        return int(listen.rsplit(":", 1)[1])

    def router_config(self) -> dict[str, Any]:
        """The zenohd configuration the credentials service wrote."""
        svc = services(self.compose)[ROUTER]
        argv = svc["command"]
        for vol in svc.get("volumes", []):
            source, target = str(vol).split(":")[:2]
            self.lb.mount(source, target, Image())
        path = self.lb.path(argv[argv.index("--config") + 1], "/nonexistent")
        # the credentials service was given the mapped path: the dictionary's is too
        config: dict[str, Any] = json.loads(path.read_text())
        return config

    def environment(self, svc: dict[str, Any], image: Image) -> dict[str, str]:
        env = {k: v for k, v in os.environ.items() if not k.startswith("MODD_")}
        for k, v in image.env.items():
            env[k] = v.replace(f"{image.workdir}/.venv/bin", str(VENV_BIN)).replace(
                "$PATH", os.environ["PATH"]
            )
        for k, v in (svc.get("environment") or {}).items():
            env[k] = interpolate(str(v), self.env)
        return env

    def executable(self, word: str) -> str:
        if word == "python":
            return sys.executable
        if word in project_scripts():
            return str(VENV_BIN / word)
        return word

    def start(self, name: str) -> Proc:
        svc = services(self.compose)[name]
        image = image_of(svc)
        for vol in svc.get("volumes", []):
            source, target, *mode = str(vol).split(":")
            self.lb.mount(source, target, image, read_only=mode == ["ro"])
        argv = self.lb.argv(argv_of(svc), image)
        argv[0] = self.executable(argv[0])
        proc = Proc(name, argv, self.tmp / f"{name}.log", env=self.environment(svc, image))
        self.procs[name] = proc
        return proc

    def healthcheck(self, name: str, timeout_s: float) -> None:
        svc = services(self.compose)[name]
        argv = self.lb.argv(svc["healthcheck"]["test"][1:], image_of(svc))
        argv[0] = self.executable(argv[0])
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline and self.procs[name].alive():
            if subprocess.run(argv, capture_output=True, timeout=10).returncode == 0:
                return
            time.sleep(0.3)
        raise AssertionError(f"{name}: healthcheck never passed:\n{self.procs[name].log()}")

    def stop(self) -> dict[str, int | None]:
        return {name: p.stop() for name, p in reversed(self.procs.items())}


@pytest.fixture
def run(compose: dict[str, Any]) -> Iterator[Run]:
    # a short folder of its own, not tmp_path: the services' paths sit under it
    # (.../root/var/lib/modd/drone/ingress.sock), and a unix socket's path has at
    # most 107 bytes (pytest-xdist's tmp_path adds a worker folder)
    with tempfile.TemporaryDirectory(prefix="modd-compose-") as d:
        r = Run(compose, Path(d))
        try:
            yield r
        finally:
            r.stop()


def archive_grows(directory: Path, timeout_s: float) -> None:
    def size() -> int:
        return sum(f.stat().st_size for f in directory.glob("*.mcap"))

    deadline = time.monotonic() + timeout_s
    first = 0
    while time.monotonic() < deadline:
        now = size()
        if first and now > first:
            return
        first = first or now
        time.sleep(0.3)
    raise AssertionError(f"the drone's archive in {directory} does not grow (size {size()})")


@pytest.mark.timeout(180)
def test_the_services_start_on_loopback_and_become_ready(compose: dict[str, Any], run: Run) -> None:
    order = [n for n in start_order(compose) if n not in (ROUTER, "credentials")]
    made = run.start("credentials")
    assert made.p.wait(60) == 0, made.log()
    config = run.router_config()
    assert config["access_control"]["default_permission"] == "deny"
    assert not run.procs["credentials"].log().count(":") > 2  # names files, no password
    with zenoh_router(run.router_port(), config) as router:
        watch = StatusWatch(router)
        try:
            for name in order:
                run.start(name)
            # the drone archives what its simulated sensors publish
            archive_grows(run.lb.tmp / "volumes" / "drone-archive", 60)  # slow start under load
            # the SubBroker linked to the drone and speaks on the router
            status = watch.wait("usv", lambda s: s["link"] == "up" and s["config_id"], 30)
            assert status["delivered"] >= 0
            # the backend is healthy, signs in, sees the drone's archive and relays its values
            run.healthcheck("backend", 30)
            backend = Backend(run.procs["backend"], run.lb.port(8080))
            backend.sign_in(run.env["MODD_ADMIN_PASSWORD"])
            files = backend.request("GET", "/drones/usv/archives")
            assert files.status_code == 200 and files.json(), files.text
            # a deploy goes backend -> router -> SubBroker -> drone and is kept in its volume
            demo = load_model(REPO / "metamodel" / "examples" / "demo.modd")
            project = backend.request(
                "POST", "/projects", json={"name": "demo", "model": {"model": demo}}
            )
            assert project.status_code == 201, project.text
            record = backend.request(
                "POST", f"/projects/{project.json()['id']}/deployments", json={}
            ).json()
            assert record["status"] == "acked", record
            assert (run.lb.tmp / "volumes" / "subbroker-state" / "deployed.json").is_file()
            with backend.stream("usv") as ws:
                ws.send('{"op": "subscribe", "subscriber": "sub_5"}')
                msgs = receive_until(ws, lambda m: m["type"] == "value", 20)
                assert msgs[-1]["data"]["topic"] == "usv.accelerometer.accel_z"
            for name in order:
                assert run.procs[name].alive(), f"{name} died:\n{run.procs[name].log()}"
        finally:
            watch.close()
            codes = run.stop()
    # stopped by the SIGTERM sent, not killed after the bound (uvicorn re-raises SIGTERM)
    assert all(code in (0, -signal.SIGTERM) for code in codes.values()), codes
