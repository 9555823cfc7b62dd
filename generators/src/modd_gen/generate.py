"""Which targets each role gets, and the index of what was generated."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from .artifact import Artifact
from .context import Context, Station, build_context
from .targets import cpp_driver, pubbroker_config, ros2_msgs, subbroker_config, subscribers

Target = Callable[[Context], list[Artifact]]

#: role -> its targets, in the order they are written
ROLES: dict[str, list[Target]] = {
    "integrator": [cpp_driver.artifacts, ros2_msgs.artifacts],
    "operator": [pubbroker_config.artifacts, subbroker_config.artifacts],
    "scientist": [subscribers.artifacts],
}


def register_target(role: str, target: Target) -> None:
    """Add a target to a role (targets that need optional packages register late)."""
    if target not in ROLES[role]:
        ROLES[role].append(target)


def generate(
    model: dict[str, Any], role: str | None = None, station: Station | None = None
) -> list[Artifact]:
    """Every artifact of a validated model, or only those of one role; sorted by path.
    ``station``: the base station of the deployment the artifacts are for (the
    scientist's subscribers connect there), when it is known."""
    if role is not None and role not in ROLES:
        raise ValueError(f"unknown role {role!r}; expected one of {', '.join(ROLES)}")
    ctx = build_context(model)
    ctx.station = station
    roles = [role] if role else list(ROLES)
    out = [a for r in roles for target in ROLES[r] for a in target(ctx)]
    return sorted(out, key=lambda a: a.path)
