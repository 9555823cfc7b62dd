"""The application: ``create_app(settings)`` composes the routers; the store,
the first admin and the zenoh session are opened at start-up (lifespan).

>>> app = create_app(Settings(data_dir=Path("/tmp/modd")))   # doctest: +SKIP
>>> uvicorn.run(app, host="127.0.0.1", port=8000)            # doctest: +SKIP
"""

from __future__ import annotations

import sys
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from typing import Any, TextIO

from fastapi import APIRouter, FastAPI

from . import errors
from .accounts import ensure_first_admin
from .db import Store
from .deployments import last_acked
from .deps import AppState
from .foxglove import FoxgloveLive
from .planning import preload_milp
from .routers import (
    archives,
    auth,
    deploy,
    downloads,
    health,
    models,
    plan,
    projects,
    scene,
    streams,
    users,
)
from .scene import SceneServer, SceneService
from .settings import Settings
from .spa import mount_frontend
from .versions import get_version, model_of
from .zbridge import Undeclarable, ZenohBridge

ROUTERS: tuple[APIRouter, ...] = (
    health.router,
    auth.router,
    users.router,
    projects.router,
    models.router,
    plan.router,
    deploy.router,
    downloads.router,
    streams.router,
    archives.router,
    scene.router,
)


def start_scene(settings: Settings, store: Store) -> SceneService:
    """The viser server, fed with the model last deployed to each drone."""

    def deployed_model(drone: str) -> dict[str, Any] | None:
        with store.session() as db:
            running = last_acked(db, drone)
            if running is None:
                return None
            return model_of(get_version(db, running.project_id, running.revision))

    port = settings.scene_port or 0
    return SceneService(SceneServer(settings.host, port), deployed_model)


def start_foxglove(settings: Settings, out: TextIO) -> FoxgloveLive | None:
    """The Foxglove server, or None (said on ``out``) when its port is taken:
    the workbench runs without it rather than not at all."""
    try:
        server = FoxgloveLive(settings.host, settings.foxglove_port)
    except RuntimeError as exc:  # the SDK's FoxgloveError
        print(f"modd-backend: no Foxglove server on {settings.host}:{settings.foxglove_port}: "
              f"{exc}", file=out, flush=True)
        return None
    print(f"modd-backend: Foxglove server at {server.url}", file=out, flush=True)
    return server


def subscribe_values(bridge: ZenohBridge, state: AppState) -> list[Undeclarable]:
    """The one place delivered values and statuses of every drone arrive in
    the backend, handed to each consumer (3D scene, Foxglove server)."""
    on_value = [c.on_value for c in (state.scene, state.foxglove) if c is not None]
    subs: list[Undeclarable] = []
    if on_value:
        def values(key: str, payload: bytes) -> None:
            for consumer in on_value:
                consumer(key, payload)

        subs.append(bridge.subscribe("modd/*/sub/*", values))
    if state.foxglove is not None:
        subs.append(bridge.subscribe("modd/*/status", state.foxglove.on_status))
    return subs


def create_app(settings: Settings, *, out: TextIO = sys.stdout) -> FastAPI:
    """The service for ``settings``; ``out`` receives the first admin's password."""

    @asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        settings.data_dir.mkdir(parents=True, exist_ok=True)
        def first_start(store: Store) -> None:
            with store.session() as db:
                ensure_first_admin(db, settings.initial_admin_password, out)

        store = Store.open(settings.effective_database_url, init=first_start)
        bridge = None
        if settings.zenoh_enabled:
            bridge = ZenohBridge.open(settings.zenoh_connect, settings.zenoh_listen,
                                      settings.zenoh_credentials)
        if settings.preload_milp:
            preload_milp()
        app.state.modd = AppState(settings, store, bridge)
        subs = []
        if bridge is not None:
            if settings.scene_port is not None:
                app.state.modd.scene = start_scene(settings, store)
            if settings.foxglove_port:
                app.state.modd.foxglove = start_foxglove(settings, out)
            subs = subscribe_values(bridge, app.state.modd)
        try:
            yield
        finally:
            for sub in subs:
                sub.undeclare()
            if app.state.modd.scene is not None:
                app.state.modd.scene.server.stop()
            if app.state.modd.foxglove is not None:
                app.state.modd.foxglove.stop()
            if bridge is not None:
                bridge.close()
            store.close()

    app = FastAPI(
        title="MoDD workbench",
        version="0.1.0",
        description="Model store, live plan, deploy, live streams and archives of MoDD.",
        lifespan=lifespan,
    )
    errors.install(app)
    for router in ROUTERS:
        app.include_router(router)
    if settings.frontend_dist is not None:
        mount_frontend(app, settings.frontend_dist)
    return app
