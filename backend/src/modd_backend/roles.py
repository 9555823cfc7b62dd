"""Roles, and which role owns which part of a model.

A model edit is allowed when the user holds, for every part the edit changes,
the role owning that part (admin holds all):

>>> owners_of_changes({"subscribers": []}, {"subscribers": [{"name": "s"}]})
{'/subscribers': 'scientist'}
"""

from __future__ import annotations

from enum import StrEnum
from typing import Any

from modd_contracts.owners_gen import MODEL_PART_OWNERS


class Role(StrEnum):
    designer = "designer"
    integrator = "integrator"
    scientist = "scientist"
    operator = "operator"
    admin = "admin"


ALL_ROLES: tuple[Role, ...] = tuple(Role)
#: Roles that may edit some part of a model (layout belongs to any of them).
EDITORS: frozenset[Role] = frozenset({Role.designer, Role.integrator, Role.scientist})

#: Top-level model parts and their owners (the schema's ``x-owner``, generated);
#: "/drone" without its sensors is the platform (designer); "/drone/sensors" is
#: the integrator's; None: any editor.
PART_OWNERS: dict[str, Role | None] = {
    part: None if role is None else Role(role) for part, role in MODEL_PART_OWNERS.items()
}

_MISSING = object()


def _parts(model: dict[str, Any]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in model.items():
        if key == "drone" and isinstance(value, dict):
            out["/drone"] = {k: v for k, v in value.items() if k != "sensors"}
            out["/drone/sensors"] = value.get("sensors", _MISSING)
        else:
            out["/" + key] = value
    return out


def owners_of_changes(before: dict[str, Any], after: dict[str, Any]) -> dict[str, str | None]:
    """Changed parts (JSON pointers) and the role owning each (None: any editor).

    A part unknown to the schema is the designer's."""
    a, b = _parts(before), _parts(after)
    changed: dict[str, str | None] = {}
    for part in sorted(set(a) | set(b)):
        if a.get(part, _MISSING) != b.get(part, _MISSING):
            owner = PART_OWNERS.get(part, Role.designer)
            changed[part] = owner.value if owner is not None else None
    return changed


def may_edit(roles: set[str], changes: dict[str, str | None]) -> list[str]:
    """The changed parts the holder of ``roles`` may not edit (empty: allowed)."""
    if Role.admin in roles:
        return []
    denied = []
    for part, owner in changes.items():
        if owner is None:
            if not roles & {r.value for r in EDITORS}:
                denied.append(part)
        elif owner not in roles:
            denied.append(part)
    return denied


def parse_roles(text: str) -> set[str]:
    return {r for r in text.split(",") if r}


def format_roles(roles: set[str] | list[str]) -> str:
    return ",".join(sorted(set(roles)))
