"""Saves announced to everyone with the project open: the save route
publishes ``{"type": "saved", "project", "revision", "author", "message"}``
and every stream WebSocket that asked ``{"op": "watch", "project": ID}``
gets it (docs/backend.md, "Live relay").

Callbacks run on the saving thread and must not block (the stream sockets
put into their DropOldestQueue).

>>> events = ProjectEvents()
>>> got = []
>>> events.add(1, got.append)
>>> events.publish(1, {"type": "saved", "revision": 2}); events.publish(2, {"type": "saved"})
>>> got
[{'type': 'saved', 'revision': 2}]
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

Event = dict[str, Any]
EventCallback = Callable[[Event], None]
#: Projects one socket may watch at once (a page watches the one it shows).
WATCH_LIMIT = 8


class ProjectEvents:
    """Listeners per project id, fanned out in process."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._listeners: dict[int, set[EventCallback]] = {}

    def add(self, project_id: int, callback: EventCallback) -> None:
        with self._lock:
            self._listeners.setdefault(project_id, set()).add(callback)

    def remove(self, project_id: int, callback: EventCallback) -> None:
        with self._lock:
            cbs = self._listeners.get(project_id)
            if cbs is not None:
                cbs.discard(callback)
                if not cbs:
                    del self._listeners[project_id]

    def publish(self, project_id: int, event: Event) -> None:
        with self._lock:
            targets = list(self._listeners.get(project_id, ()))
        for cb in targets:
            cb(event)

    def watchers(self, project_id: int) -> int:
        with self._lock:
            return len(self._listeners.get(project_id, ()))


class ProjectWatches:
    """The projects one stream socket watches; ``send`` must not block."""

    def __init__(self, events: ProjectEvents, send: EventCallback) -> None:
        self._events = events
        self._send = send
        self._projects: set[int] = set()

    def handle(self, op: str, project: Any) -> Event:
        """``watch``/``unwatch`` a project id; ValueError names what is wrong."""
        if not isinstance(project, int) or isinstance(project, bool) or not 0 < project < 2**31:
            raise ValueError("'project' is a project id (a positive integer)")
        if op == "unwatch":
            if project in self._projects:
                self._projects.discard(project)
                self._events.remove(project, self._send)
            return {"type": "unwatched", "project": project}
        if project not in self._projects:
            if len(self._projects) >= WATCH_LIMIT:
                raise ValueError(f"a socket watches at most {WATCH_LIMIT} projects")
            self._projects.add(project)
            self._events.add(project, self._send)
        return {"type": "watching", "project": project}

    def close(self) -> None:
        for project in self._projects:
            self._events.remove(project, self._send)
        self._projects.clear()
