"""The application: ``create_app(settings)`` composes the routers; the store,
the first admin and the zenoh session are opened at start-up (lifespan).

>>> app = create_app(Settings(data_dir=Path("/tmp/modd")))   # doctest: +SKIP
>>> uvicorn.run(app, host="127.0.0.1", port=8000)            # doctest: +SKIP
"""

from __future__ import annotations

import asyncio
import gc
import logging
import os
import sys
from collections.abc import AsyncIterator
from concurrent.futures import ThreadPoolExecutor
from contextlib import asynccontextmanager
from typing import Any, TextIO

from anyio import CapacityLimiter
from fastapi import APIRouter, FastAPI
from sqlalchemy import text
from starlette.concurrency import run_in_threadpool

from . import archive_work, errors, planning, storeproc
from .accounts import ensure_first_admin
from .apidocs import install_docs
from .archive_pool import ArchivePool
from .bodies import install_schemas
from .db import Store
from .deployments import last_acked
from .deps import STORE_THREADS, AppState
from .foxglove import FoxgloveLive
from .guards import Guard, HeavyLimiter
from .hub import SubscriptionHub
from .loopback_tls import LOOPBACK, LoopbackTls
from .planning import preload_milp
from .reconcile import DroneStatuses, reconcile
from .routers import (
    archives,
    auth,
    backfill,
    datasetmeta,
    deploy,
    downloads,
    fleet,
    foxglove,
    health,
    live,
    models,
    pairing,
    plan,
    projects,
    records,
    rehearsal,
    scene,
    tiles,
    users,
)
from .scene import SceneServer, SceneService
from .settings import Settings
from .socketcaps import SocketCaps
from .spa import mount_frontend
from .throttle import KnownPairs, Throttle
from .versions import get_version, model_of
from .zenoh_session import ZenohSession

log = logging.getLogger("modd_backend")

ROUTERS: tuple[APIRouter, ...] = (
    health.router,
    auth.router,
    users.router,
    projects.router,
    models.router,
    datasetmeta.router,
    plan.router,
    deploy.router,
    fleet.router,
    downloads.router,
    downloads.credentials_router,
    pairing.router,
    live.router,
    archives.router,
    archives.replay_router,
    scene.router,
    scene.proxy,
    foxglove.router,
    backfill.router,
    records.router,
    records.track_router,
    tiles.router,
    rehearsal.router,
)


def start_scene(settings: Settings, store: Store) -> SceneService:
    """The viser server (on loopback: browsers reach it only through the
    backend's ``/scene/`` proxy), fed with the model last deployed to each drone."""

    def deployed_model(drone: str) -> dict[str, Any] | None:
        with store.session() as db:
            running = last_acked(db, drone)
            if running is None:
                return None
            return model_of(get_version(db, running.project_id, running.revision))

    port = settings.scene_port or 0
    return SceneService(SceneServer("127.0.0.1", port), deployed_model)


def start_foxglove(settings: Settings, tls: LoopbackTls, out: TextIO) -> FoxgloveLive | None:
    """The Foxglove server on loopback behind TLS (viewers come in through
    ``/foxglove/live``), or None (said on ``out``) when its port is taken:
    the workbench runs without it rather than not at all."""
    try:
        server = FoxgloveLive(LOOPBACK, settings.foxglove_port, tls=tls)
    except RuntimeError as exc:  # the SDK's FoxgloveError
        print(
            f"modd-backend: no Foxglove server on {LOOPBACK}:{settings.foxglove_port}: {exc}",
            file=out,
            flush=True,
        )
        return None
    print(
        f"modd-backend: Foxglove live at ws://{settings.host}:{settings.port}/foxglove/live "
        "(with a ticket: the workbench's Foxglove links, docs/ecosystem.md)",
        file=out,
        flush=True,
    )
    return server


def _ping(state: AppState) -> None:
    with state.store.session() as db:
        db.execute(text("SELECT 1"))


def _reconcile(state: AppState) -> None:
    assert state.statuses is not None
    with state.store.session() as db:
        reconcile(db, state.statuses, state.settings.deploy_timeout_s)


async def _reconcile_deployments(
    state: AppState, stop: asyncio.Event, every_s: float = 1.0
) -> None:
    """Settle deploy records with what the drones report (reconcile.py)."""
    while not stop.is_set():
        await asyncio.sleep(every_s)
        try:
            await run_in_threadpool(_reconcile, state)
        except Exception:  # reported; the next round tries again
            log.exception("reconciling deploy records failed")


async def _ping_database(state: AppState, stop: asyncio.Event, every_s: float = 2.0) -> None:
    """Keep ``state.database`` current for /api/health (which never waits on it)."""
    while not stop.is_set():
        try:
            # asyncio.timeout, not wait_for: Python 3.11's wait_for swallows a
            # cancellation that arrives as the ping completes, and the loop
            # then outlived the app's shutdown (a CI run hung 600 s on it).
            async with asyncio.timeout(every_s * 2):
                await run_in_threadpool(_ping, state)
            state.database = "ok"
        except Exception:  # any failure of the store is reported, never raised
            state.database = "error"
        await asyncio.sleep(every_s)


def create_app(settings: Settings, *, out: TextIO = sys.stdout) -> FastAPI:
    """The service for ``settings``; ``out`` receives the first admin's password."""

    @asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        os.umask(0o077)  # the store, logs and state this process writes: owner only
        settings.data_dir.mkdir(parents=True, exist_ok=True)

        def first_start(store: Store) -> None:
            with store.session() as db:
                ensure_first_admin(db, settings.initial_admin_password, out)

        store = Store.open(settings.effective_database_url, init=first_start)
        zenoh_session = None
        if settings.zenoh_enabled:
            zenoh_session = ZenohSession.open(
                settings.zenoh_connect, settings.zenoh_listen, settings.zenoh_credentials
            )
        if settings.preload_milp:
            preload_milp()
        state = AppState(
            settings,
            store,
            zenoh_session,
            heavy=HeavyLimiter(settings.heavy_per_user, settings.heavy_total),
            archive_pool=ArchivePool(archive_work.ARCHIVE_WORKERS),
            login_accounts=Throttle(settings.login_limit_account, settings.login_window_s),
            login_addresses=Throttle(settings.login_limit_address, settings.login_window_s),
            login_known=KnownPairs(settings.login_known_s),
            socket_caps=SocketCaps(settings.ws_sockets_per_user, settings.ws_sockets_per_address),
        )
        app.state.modd = state
        state.database = "ok"  # just opened and migrated
        state.login_threads = CapacityLimiter(settings.login_threads)
        state.closing_threads = CapacityLimiter(4)
        state.store_threads = ThreadPoolExecutor(STORE_THREADS, thread_name_prefix="modd-store")
        url = settings.effective_database_url
        if storeproc.usable(url, settings.store_processes):
            state.store_procs = storeproc.StoreProcesses(url, settings.store_processes)
        if settings.foxglove_port or settings.foxglove_replay_port:
            state.loopback_tls = LoopbackTls.generate()
        if zenoh_session is not None:
            state.hub = SubscriptionHub()
            state.statuses = DroneStatuses()
            state.hub.listen_all_status(state.statuses.on_status)
            state.hub.start(zenoh_session)
            if settings.scene_port is not None:
                state.scene = start_scene(settings, store)
                state.hub.listen_all(state.scene.on_value)
            if settings.foxglove_port and state.loopback_tls is not None:
                state.foxglove = start_foxglove(settings, state.loopback_tls, out)
                if state.foxglove is not None:
                    state.hub.listen_all(state.foxglove.on_value)
                    state.hub.listen_all_status(state.foxglove.on_status)
        if settings.foxglove_replay_port:
            from .replay import ReplaySlot

            state.replay = ReplaySlot(
                LOOPBACK, settings.foxglove_replay_port, tls=state.loopback_tls
            )
        stop = asyncio.Event()
        tasks = [asyncio.create_task(_ping_database(state, stop))]
        if state.statuses is not None:
            tasks.append(asyncio.create_task(_reconcile_deployments(state, stop)))
        # Everything loaded so far (FastAPI, cvxpy, viser, zenoh: ~150,000
        # objects) lives as long as the process: out of the collector's
        # sight, a full collection no longer stalls the event loop (it took
        # ~300 ms on a loaded machine, /api/health's p99 under a WebSocket flood).
        gc.collect()
        gc.freeze()
        try:
            yield
        finally:
            # The flag ends each loop even if a cancellation is lost; the
            # bounded wait keeps a stuck store call from holding the shutdown.
            stop.set()
            for task in tasks:
                task.cancel()
            await asyncio.wait(tasks, timeout=10)
            if state.hub is not None:
                state.hub.stop()
            if state.scene is not None:
                state.scene.server.stop()
            if state.foxglove is not None:
                state.foxglove.stop()
            if state.replay is not None:
                state.replay.stop()
            if zenoh_session is not None:
                zenoh_session.close()
            if state.archive_pool is not None:
                await state.archive_pool.close()
            await run_in_threadpool(planning.shutdown_pool)
            state.store_threads.shutdown(wait=False, cancel_futures=True)
            if state.store_procs is not None:
                state.store_procs.close()
            store.close()

    app = FastAPI(
        title="MoDD workbench",
        version="0.1.0",
        description="Model store, live plan, deploy, live streams and archives of MoDD.",
        lifespan=lifespan,
        docs_url=None,  # apidocs.py: Swagger UI from the backend's own files
    )
    errors.install(app)
    app.add_middleware(Guard, settings=settings)
    for router in ROUTERS:
        app.include_router(router)
    install_schemas(app)  # the bodies routes read themselves (bodies.py)
    install_docs(app)
    if settings.frontend_dist is not None:
        mount_frontend(app, settings.frontend_dist)
    return app
