"""A deployed model applied to a running ``modd-sensors``: only the readers whose
instrument changed stop or start; the others read on, and no sample of theirs is
lost (docs/sensors.md, "Deploying to a running drone").

Example::

    result = apply_plans(runner, plan_sensors(model), lambda name: Publisher(name, ingress))
    result["sensors"]   # [{"sensor": "gnss", "action": "started", "ok": True, "state": "open"}]
"""

from __future__ import annotations

import dataclasses
import os
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from .plan import SensorPlan
from .run import Runner, SensorThread, Sink

JOIN_S = 1.0  # a stopped reader closes its device within its read timeout (0.1 s)
OPEN_WAIT_S = 1.0  # how long a new reader is given to open its device before the answer


def linked_device(plan: SensorPlan, devices: Path | None) -> SensorPlan:
    """``plan`` reading ``devices/<name>`` when that link is there (a simulated run's
    pseudo-terminal, as ``modd up --simulate`` started it), else as the model says."""
    if devices is None or not os.path.lexists(devices / plan.name):
        return plan
    return dataclasses.replace(
        plan, device=dataclasses.replace(plan.device, path=str(devices / plan.name))
    )


def _outcome(action: str, t: SensorThread | None) -> dict[str, Any]:
    """What one reader did, and whether it reads (``ok``) or why not (``problem``)."""
    if t is None:
        return {"action": action, "ok": True, "state": "closed"}
    if t.health.busy:
        return {"action": action, "ok": False, "state": "busy", "problem": t.health.busy}
    if t.health.connected:
        return {"action": action, "ok": True, "state": "open"}
    path = t.plan.device.path
    why = "missing" if t.absent else "not opened yet"
    return {"action": action, "ok": False, "state": "closed", "problem": f"device {path} {why}"}


def _settled(t: SensorThread) -> bool:
    return t.health.connected or bool(t.health.busy) or t.absent


def _declare(runner: Runner, plan: SensorPlan, make_sink: Callable[[str], Sink]) -> None:
    for m in plan.mappings:
        if m.publisher not in runner.sinks:
            runner.sinks[m.publisher] = make_sink(m.publisher)
        runner.sinks[m.publisher].declare(m.topic, m.type)


def apply_plans(
    runner: Runner, plans: list[SensorPlan], make_sink: Callable[[str], Sink]
) -> dict[str, Any]:
    """Stops the readers of removed or changed instruments, starts the new ones;
    what each did (``unchanged``, ``started``, ``restarted``, ``stopped``)."""
    old = {s.plan.name: s for s in runner.sensors}
    actions: dict[str, str] = {}
    readers: list[SensorThread] = []
    for plan in plans:
        cur = old.get(plan.name)
        if cur is not None and cur.plan == plan:
            actions[plan.name] = "unchanged"
            readers.append(cur)
            continue
        _declare(runner, plan, make_sink)
        actions[plan.name] = "started" if cur is None else "restarted"
        readers.append(SensorThread(plan, runner.sinks, runner.log))
    gone = [s for name, s in old.items() if actions.get(name, "stopped") != "unchanged"]
    for s in gone:
        s.stop()
    for s in gone:
        s.join(JOIN_S)  # its device closed before a new reader opens it
    for name in old.keys() - actions.keys():
        actions[name] = "stopped"
    new = [s for s in readers if actions[s.plan.name] != "unchanged"]
    for s in new:
        s.start()
    runner.sensors = readers
    deadline = time.monotonic() + OPEN_WAIT_S  # a kept reader may still be opening too
    while not all(_settled(s) for s in readers) and time.monotonic() < deadline:
        time.sleep(0.02)
    by_name = {s.plan.name: s for s in readers}
    out = [{"sensor": n, **_outcome(a, by_name.get(n))} for n, a in sorted(actions.items())]
    for r in out:
        if r["action"] != "unchanged":
            runner.log(f"deploy: {r['sensor']} {r['action']}" + _said(r))
    return {"ok": all(r["ok"] for r in out), "sensors": out}


def _said(r: dict[str, Any]) -> str:
    return f" ({r['problem']})" if r.get("problem") else f" ({r['state']})"
