"""A generated file and how it is written to disk.

Generated files are rewritten on every run. User-owned files (the integrator's
driver code) are written once and never overwritten, so that regenerating after
a model change keeps the integrator's work."""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from enum import StrEnum
from pathlib import Path


class Ownership(StrEnum):
    GENERATED = "generated"  # rewritten on every run
    USER = "user"  # written once, then the user's


# A generated file's path: relative, parts of ASCII letters, digits, _ . and -
# (model names are identifiers; this holds even if a name were not one).
_PART = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.-]*")


def check_path(path: str) -> str:
    """``path`` when it is a safe relative path for a generated file: no control
    character, no separator other than /, no empty, ``.`` or ``..`` part, no
    absolute path. Raises ValueError naming the path otherwise."""
    parts = path.split("/")
    if not all(_PART.fullmatch(p) and p not in (".", "..") for p in parts):
        raise ValueError(f"unsafe generated file name {path!r}")
    return path


@dataclass(frozen=True)
class Artifact:
    path: str  # relative, with forward slashes
    content: str
    role: str  # integrator | operator | scientist
    ownership: Ownership = Ownership.GENERATED
    executable: bool = False

    def __post_init__(self) -> None:
        check_path(self.path)


@dataclass(frozen=True)
class Written:
    artifact: Artifact
    action: str  # "written" | "kept" (a user-owned file that already existed)


def write_artifacts(out_dir: str | Path, artifacts: list[Artifact]) -> list[Written]:
    """Write artifacts under out_dir; user-owned files that exist are kept."""
    root = Path(out_dir)
    done = []
    for a in artifacts:
        target = root / a.path
        if a.ownership is Ownership.USER and target.exists():
            done.append(Written(a, "kept"))
            continue
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_text(a.content, encoding="utf-8")
        if a.executable:
            os.chmod(target, 0o755)
        done.append(Written(a, "written"))
    return done
