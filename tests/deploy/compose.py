"""Reading docker-compose.yml and the project's Dockerfiles without Docker, and
translating a service into a process on this machine.

A container's view is mapped onto loopback: service host names and 0.0.0.0
become 127.0.0.1, every port a command names gets a free loopback port (the
same one wherever that port appears: a listener and the services connecting to
it), the image's WORKDIR is the repository, other absolute paths move under a
temporary root, named volumes are directories there with a symlink at each
mount point, and a model file argument becomes a copy whose fixed loopback
ports are mapped the same way.
"""

from __future__ import annotations

import json
import re
import shlex
import shutil
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

REPO = Path(__file__).resolve().parents[2]
COMPOSE = REPO / "docker-compose.yml"
ENV_EXAMPLE = REPO / ".env.example"
MODEL_SUFFIXES = (".modd", ".json", ".toml", ".py")


def load_compose(path: Path = COMPOSE) -> dict[str, Any]:
    data: dict[str, Any] = yaml.safe_load(path.read_text())
    return data


def env_file(path: Path = ENV_EXAMPLE) -> dict[str, str]:
    """NAME=value lines (comments and blank lines skipped)."""
    out = {}
    for line in path.read_text().splitlines():
        line = line.strip()
        if line and not line.startswith("#"):
            name, _, value = line.partition("=")
            out[name.strip()] = value.strip()
    return out


_VAR = re.compile(r"\$\$|\$\{(\w+)(?:(:?[?-])([^}]*))?\}|\$(\w+)")


def interpolate(text: str, env: dict[str, str]) -> str:
    """Compose's variable substitution: $VAR, ${VAR}, ${VAR:-default},
    ${VAR:?error} (KeyError naming VAR when unset or empty), $$."""

    def sub(m: re.Match[str]) -> str:
        if m.group(0) == "$$":
            return "$"
        name = m.group(1) or m.group(4)
        value, op, arg = env.get(name), m.group(2), m.group(3)
        empty = value is None or (value == "" and op is not None and op.startswith(":"))
        if op and op.endswith("?") and empty:
            raise KeyError(f"{name}: {arg}")
        if op and op.endswith("-") and empty:
            return str(arg)
        return value or ""

    return _VAR.sub(sub, text)


# -- Dockerfiles -------------------------------------------------------------------------


def instructions(dockerfile: Path) -> list[tuple[str, str]]:
    """(INSTRUCTION, arguments) pairs, continuation lines joined, comments dropped."""
    out: list[tuple[str, str]] = []
    pending = ""
    for raw in dockerfile.read_text().splitlines():
        line = raw.strip()
        if not pending and (not line or line.startswith("#")):
            continue
        if line.startswith("#"):
            continue
        if line.endswith("\\"):
            pending += line[:-1] + " "
            continue
        full = (pending + line).strip()
        pending = ""
        word, _, rest = full.partition(" ")
        out.append((word.upper(), rest.strip()))
    return out


def _words(args: str) -> list[str]:
    if args.startswith("["):
        words: list[str] = json.loads(args)
        return words
    return shlex.split(args)


def copy_sources(dockerfile: Path) -> list[str]:
    """Sources of COPY/ADD from the build context (not those --from= a stage or image)."""
    out = []
    for instr, args in instructions(dockerfile):
        if instr not in ("COPY", "ADD"):
            continue
        words = _words(args)
        flags = [w for w in words if w.startswith("--")]
        if any(f.startswith("--from=") for f in flags):
            continue
        paths = [w for w in words if not w.startswith("--")]
        out.extend(paths[:-1])
    return out


@dataclass
class Image:
    """What a project image's final stage sets: WORKDIR, ENV, ENTRYPOINT, CMD."""

    workdir: str = "/"
    env: dict[str, str] = field(default_factory=dict)
    entrypoint: list[str] = field(default_factory=list)
    cmd: list[str] = field(default_factory=list)

    @classmethod
    def read(cls, dockerfile: Path) -> Image:
        image = cls()
        for instr, args in instructions(dockerfile):
            if instr == "FROM":
                image = cls()
            elif instr == "WORKDIR":
                image.workdir = args
            elif instr == "ENV":
                for word in shlex.split(args):
                    name, _, value = word.partition("=")
                    image.env[name] = value
            elif instr == "ENTRYPOINT":
                image.entrypoint = _words(args)
            elif instr == "CMD":
                image.cmd = _words(args)
        return image


# -- what the project provides -------------------------------------------------------------


def _pyprojects() -> list[dict[str, Any]]:
    root = tomllib.loads((REPO / "pyproject.toml").read_text())
    members = root["tool"]["uv"]["workspace"]["members"]
    return [tomllib.loads((REPO / m / "pyproject.toml").read_text()) for m in members]


def project_scripts() -> set[str]:
    """Console scripts of the uv workspace's members ([project.scripts])."""
    return {name for p in _pyprojects() for name in p["project"].get("scripts", {})}


def modd_commands() -> set[str]:
    """Subcommands of ``modd`` (the ``modd.commands`` entry points)."""
    return {
        name
        for p in _pyprojects()
        for name in p["project"].get("entry-points", {}).get("modd.commands", {})
    }


def toml_text(data: dict[str, Any], prefix: str = "") -> str:
    """TOML for a document of tables, strings, numbers, booleans and lists of them."""

    def value(v: Any) -> str:
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, list):
            return "[" + ", ".join(value(x) for x in v) + "]"
        return json.dumps(v)

    lines = [f"{k} = {value(v)}" for k, v in data.items() if not isinstance(v, dict)]
    for k, v in data.items():
        if isinstance(v, dict):
            lines += ["", f"[{prefix}{k}]", toml_text(v, f"{prefix}{k}.")]
    return "\n".join(lines)


# -- a service on loopback -------------------------------------------------------------------


@dataclass
class Loopback:
    """The container-to-loopback translation shared by every service of one run."""

    tmp: Path
    hosts: set[str]
    free_port: Any  # () -> int
    ports: dict[int, int] = field(default_factory=dict)
    models: dict[Path, Path] = field(default_factory=dict)

    def port(self, container_port: int) -> int:
        if container_port not in self.ports:
            self.ports[container_port] = self.free_port()
        return self.ports[container_port]

    def path(self, container_path: str, workdir: str) -> Path:
        """The image's WORKDIR is the repository; other absolute paths live under tmp
        (an image without a WORKDIR of its own, such as zenohd's "/", maps nothing
        into the repository: the test never writes into the work tree)."""
        p = Path(container_path)
        if not p.is_absolute():
            return REPO / p
        if Path(workdir) != Path("/") and (p == Path(workdir) or Path(workdir) in p.parents):
            return REPO / p.relative_to(workdir)
        return self.tmp / "root" / p.relative_to("/")

    def endpoints(self, text: str) -> str:
        """host:port for a service, 0.0.0.0 or 127.0.0.1 -> 127.0.0.1:mapped port."""
        names = "|".join(re.escape(h) for h in sorted(self.hosts | {"0.0.0.0", "127.0.0.1"}))
        return re.sub(
            rf"(?<![\w.-])({names}):(\d+)\b",
            lambda m: f"127.0.0.1:{self.port(int(m.group(2)))}",
            text,
        )

    def model(self, path: Path) -> Path:
        """A copy of a model file whose "127.0.0.1":PORT endpoints use mapped ports."""
        if path not in self.models:
            text = re.sub(
                r'"127\.0\.0\.1"\s*:\s*(\d+)',
                lambda m: f'"127.0.0.1":{self.port(int(m.group(1)))}',
                path.read_text(),
            )
            copy = self.tmp / "models" / path.name
            copy.parent.mkdir(parents=True, exist_ok=True)
            copy.write_text(text)
            self.models[path] = copy
        return self.models[path]

    def config(self, path: Path, image: Image) -> Path:
        """A copy of a SubBroker TOML file (docs/subbroker.md): its model becomes the
        model's loopback copy, paths and endpoints are translated."""
        data = tomllib.loads(path.read_text())
        model = data.get("model")
        if model is not None:
            data["model"] = str(self.model(path.parent / model))
        if "state_dir" in data:
            state = str(data["state_dir"])
            data["state_dir"] = str(
                self.path(state, image.workdir) if state.startswith("/") else path.parent / state
            )
        creds = data.get("zenoh", {}).get("credentials_dir")
        if isinstance(creds, str) and creds.startswith("/"):
            data["zenoh"]["credentials_dir"] = str(self.path(creds, image.workdir))
        copy = self.tmp / "configs" / path.name
        copy.parent.mkdir(parents=True, exist_ok=True)
        copy.write_text(self.endpoints(toml_text(data)))
        return copy

    def argv(self, words: list[str], image: Image) -> list[str]:
        out: list[str] = []
        for i, word in enumerate(words):
            before = words[i - 1] if i else ""
            if before in ("--port", "--scene-port") and word.isdigit() and int(word) > 0:
                out.append(str(self.port(int(word))))
            elif word == "0.0.0.0":
                out.append("127.0.0.1")
            elif word.startswith("/"):
                out.append(str(self.path(word, image.workdir)))
            elif word.endswith(".modd"):
                out.append(str(self.model(self.path(word, image.workdir))))
            elif word.endswith(".toml"):
                out.append(str(self.config(self.path(word, image.workdir), image)))
            elif "/" in word and ":" not in word and not word.startswith("-"):
                out.append(str(self.path(word, image.workdir)))  # relative to WORKDIR
            else:
                out.append(self.endpoints(word))
        return out

    def mount(self, volume: str, target: str, image: Image, read_only: bool = False) -> None:
        """A named volume: one directory, a symlink to it at each mount point. The
        first read-only mount holds the directory itself (the volume's store
        becomes a link to it): a reader that refuses folders reached through a
        link out of its tree (the backend's archive listing) sees, as under
        Docker, a plain directory there."""
        store = self.tmp / "volumes" / volume
        link = self.path(target, image.workdir)
        link.parent.mkdir(parents=True, exist_ok=True)
        if read_only and not store.is_symlink() and not link.exists() and not link.is_symlink():
            store.mkdir(parents=True, exist_ok=True)
            shutil.move(str(store), str(link))
            store.symlink_to(link, target_is_directory=True)
            return
        store.parent.mkdir(parents=True, exist_ok=True)
        if not store.exists():
            store.mkdir()
        if not link.is_symlink() and not link.exists():
            link.symlink_to(store, target_is_directory=True)
