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
from .zbridge import ZenohBridge

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


def create_app(settings: Settings, *, out: TextIO = sys.stdout) -> FastAPI:
    """The service for ``settings``; ``out`` receives the first admin's password."""

    @asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        settings.data_dir.mkdir(parents=True, exist_ok=True)
        store = Store.open(settings.effective_database_url)
        with store.session() as db:
            ensure_first_admin(db, settings.initial_admin_password, out)
        bridge = None
        if settings.zenoh_enabled:
            bridge = ZenohBridge.open(settings.zenoh_connect, settings.zenoh_listen,
                                      settings.zenoh_credentials)
        if settings.preload_milp:
            preload_milp()
        app.state.modd = AppState(settings, store, bridge)
        scene_sub = None
        if bridge is not None and settings.scene_port is not None:
            app.state.modd.scene = start_scene(settings, store)
            scene_sub = bridge.subscribe("modd/*/sub/*", app.state.modd.scene.on_value)
        try:
            yield
        finally:
            if scene_sub is not None:
                scene_sub.undeclare()
            if app.state.modd.scene is not None:
                app.state.modd.scene.server.stop()
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
