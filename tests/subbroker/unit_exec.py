"""A systemd unit's own command lines, as systemd would run them, for the install
tests (test_install_units.py): the installed unit file read from a root, its
``EnvironmentFile=`` (``-`` prefix: optional) and ``Environment=`` loaded, then
``ExecStartPre=`` and ``ExecStart=`` split into words and expanded by systemd's rules
for the simple cases the packaged units use (systemd.service(5), "Command lines";
systemd.unit(5), "Specifiers"):

- ``${NAME}``: the value as it is, inside its word;
- ``$NAME`` as a whole word: the value split at whitespace into words (none if empty);
- ``%%``, ``%t`` (/run), ``%S`` (/var/lib), ``%n`` (the unit's name), ``%i`` (the
  instance of a template unit: ``name@usv1.service`` is read from ``name@.service``).

Anything else (another specifier, a prefix such as ``+`` or ``!``, a line continued
with a backslash) is refused with the unit's name and line, rather than guessed.

Example::

    unit = read_unit(root, "modd-sensors.service")
    unit.exec_start        # ['/usr/bin/modd-sensors', '--model', ...]
    unit.env["MODD_SENSORS_ARGS"]
"""

from __future__ import annotations

import re
import shlex
from dataclasses import dataclass, field
from pathlib import Path

UNIT_DIR = "lib/systemd/system"
SPECIFIERS = {"%": "%", "t": "/run", "S": "/var/lib"}
_VAR = re.compile(r"\$\{([A-Za-z_][A-Za-z0-9_]*)\}")
_WORD_VAR = re.compile(r"\$([A-Za-z_][A-Za-z0-9_]*)")


class UnitError(ValueError):
    """A unit line this reader does not expand, located."""


@dataclass
class Unit:
    name: str
    service: dict[str, list[str]] = field(default_factory=dict)
    env: dict[str, str] = field(default_factory=dict)
    exec_start_pre: list[list[str]] = field(default_factory=list)
    exec_start: list[str] = field(default_factory=list)

    def one(self, key: str, default: str = "") -> str:
        values = self.service.get(key, [])
        return values[-1] if values else default


def sections(text: str, where: str) -> dict[str, dict[str, list[str]]]:
    """Section -> key -> values (in order) of a unit file."""
    out: dict[str, dict[str, list[str]]] = {}
    current: dict[str, list[str]] | None = None
    for n, raw in enumerate(text.splitlines(), 1):
        line = raw.strip()
        if not line or line[0] in "#;":
            continue
        if line.endswith("\\"):
            raise UnitError(f"{where}:{n}: a continued line is not read here")
        if line.startswith("[") and line.endswith("]"):
            current = out.setdefault(line[1:-1], {})
            continue
        if current is None or "=" not in line:
            raise UnitError(f"{where}:{n}: not a key=value line in a section: {line!r}")
        key, value = line.split("=", 1)
        current.setdefault(key.strip(), []).append(value.strip())
    return out


def environment_file(path: Path) -> dict[str, str]:
    """KEY=VALUE lines (comments, blank lines skipped; one pair of quotes removed)."""
    env: dict[str, str] = {}
    for raw in path.read_text().splitlines():
        line = raw.strip()
        if not line or line[0] in "#;" or "=" not in line:
            continue
        key, value = line.split("=", 1)
        value = value.strip()
        if len(value) >= 2 and value[0] == value[-1] and value[0] in "\"'":
            value = value[1:-1]
        env[key.strip()] = value
    return env


def specifiers(word: str, unit: str, where: str) -> str:
    def one(m: re.Match[str]) -> str:
        c = m.group(1)
        if c == "n":
            return unit
        if c == "i" and "@" in unit:
            return unit.partition("@")[2].rpartition(".")[0]
        if c not in SPECIFIERS:
            raise UnitError(f"{where}: specifier %{c} is not expanded here")
        return SPECIFIERS[c]

    return re.sub(r"%(.)", one, word)


def command(line: str, env: dict[str, str], unit: str, where: str) -> list[str]:
    """One Exec line's argv, expanded as systemd does (see the module's docstring)."""
    if line[:1] in "@-:+!":
        raise UnitError(f"{where}: the prefix {line[0]!r} is not read here")
    argv: list[str] = []
    for word in shlex.split(line):
        whole = _WORD_VAR.fullmatch(word)
        if whole:
            argv += env.get(whole.group(1), "").split()
            continue
        word = _VAR.sub(lambda m: env.get(m.group(1), ""), word)
        if _WORD_VAR.search(word):
            raise UnitError(f"{where}: $NAME inside a word is not expanded by systemd: {word!r}")
        argv.append(specifiers(word, unit, where))
    return argv


def read_unit(root: Path, name: str) -> Unit:
    """The installed unit ``name`` of the root, its commands expanded."""
    prefix, at, rest = name.partition("@")
    path = root / UNIT_DIR / (f"{prefix}@{rest[rest.rfind('.') :]}" if at else name)
    service = sections(path.read_text(), str(path)).get("Service", {})
    unit = Unit(name, service)
    for value in service.get("EnvironmentFile", []):
        optional = value.startswith("-")
        file = root / value.lstrip("-").lstrip("/")
        if file.exists():
            unit.env.update(environment_file(file))
        elif not optional:
            raise UnitError(f"{path}: EnvironmentFile {value} is missing")
    for value in service.get("Environment", []):
        for pair in shlex.split(value):
            key, _, val = pair.partition("=")
            unit.env[key] = val
    pre = service.get("ExecStartPre", [])
    unit.exec_start_pre = [command(v, unit.env, name, f"{path} ExecStartPre") for v in pre]
    starts = service.get("ExecStart", [])
    if len(starts) != 1:
        raise UnitError(f"{path}: {len(starts)} ExecStart lines, a simple service has one")
    unit.exec_start = command(starts[0], unit.env, name, f"{path} ExecStart")
    return unit
