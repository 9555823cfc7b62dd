"""The live plan: the planning engine's own output for a model, or the
diagnostics saying why there is none. Same code as the brokers run.

>>> live_plan(load_text(text, "x.modd")).plan["buffer_sizes"]   # doctest: +SKIP
{'usv.accelerometer.accel_x': 28, ...}

The HTTP routes never plan (nor parse, nor validate) on the event loop or in
the shared thread pool: :func:`guarded_call` sends the request to a small
pool of worker processes (:data:`PLAN_WORKERS`), each under an address-space
limit (:data:`PLAN_MEMORY_BYTES`); a request may plan :data:`PLAN_TIMEOUT_S`
(a timer in the worker stops it and the answer says so); a worker that does
not answer even then is killed and replaced. At
most :data:`PLAN_QUEUE` requests wait for a worker; beyond, 503 with
Retry-After. So one worst-case model cannot stall ``/api/health`` or the
other routes (docs/planning.md, "Bounds").
"""

from __future__ import annotations

import asyncio
import multiprocessing
import os
import threading
import time
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, replace
from typing import Any, Literal, TypeVar

from fastapi import HTTPException
from modd_contracts.types_gen import PlanDocument
from modd_model import LoadResult, validate
from modd_model.diagnostics import Diagnostic, ModelError
from modd_model.query import topics
from modd_plan import make_plan
from modd_plan.calibration import CalibrationError
from modd_plan.campaign import channel_diagnostics
from modd_plan.cli import load_calibration

from .modelio import diagnostics_json, read_text

Method = Literal["exact", "cvxpy"]
T = TypeVar("T")


@dataclass(frozen=True)
class LivePlan:
    plan: PlanDocument | None
    diagnostics: list[dict[str, object]]
    elapsed_ms: float

    def to_json(self) -> dict[str, Any]:
        return {
            "ok": self.plan is not None,
            "plan": self.plan,
            "diagnostics": self.diagnostics,
            "elapsed_ms": round(self.elapsed_ms, 3),
        }


def live_plan(
    result: LoadResult, method: Method = "exact", calibrate: str | None = None
) -> LivePlan:
    """Plan a loaded model when it has no errors; never raises for bad models.
    ``calibrate``: the path of an archive whose samples size the quantised
    values (``modd plan --calibrate``); one it cannot read is a diagnostic."""
    start = time.perf_counter()
    diags = list(result.diagnostics)
    plan = None
    if result.model is not None and not result.errors:
        try:
            calibration = None
            if calibrate is not None:
                calibration = load_calibration(calibrate, list(topics(result.model)))
            plan = make_plan(result.model, method=method, calibration=calibration).to_json()
            # a campaign's shared channels, summed over its vehicles' own plans: pinned
            # as the radio's refusal is (a warning; `modd plan` exits 6)
            diags += [
                replace(d, severity="warning")
                for d in channel_diagnostics(result.model, method=method, calibration=calibration)
            ]
            # a refusal by the radio, pinned in the editor (the plan is still shown)
            diags += [
                Diagnostic(d["message"], d["pointer"], "warning")
                for d in plan.get("radio", {}).get("diagnostics", [])
            ]
        except ModelError as exc:  # the planner's bounds, located at the subscriptions
            diags.extend(exc.diagnostics)
        except CalibrationError as exc:
            diags.append(Diagnostic(f"cannot calibrate the plan: {exc}", "/link/radio"))
        except (ValueError, KeyError, ArithmeticError) as exc:
            diags.append(Diagnostic(f"the planner cannot plan this model: {exc}", ""))
    return LivePlan(plan, diagnostics_json(diags), (time.perf_counter() - start) * 1000)


def preload_milp() -> None:
    """Import cvxpy once (about 0.6 s) so that no request pays for it."""
    from modd_plan import milp  # noqa: F401


#: Worker processes planning at once, seconds a request may plan, bytes of
#: address space a worker may use, requests waiting for a worker at most.
#: One core is left to the event loop and the other routes.
PLAN_WORKERS = max(1, min(4, (os.cpu_count() or 2) - 1))
PLAN_TIMEOUT_S = 30.0
PLAN_MEMORY_BYTES = 2 << 30
PLAN_QUEUE = 8
#: Extra seconds a worker may take to start (spawn, imports) before the
#: request is given up and the workers killed.
PLAN_START_S = 60.0

_lock = threading.Lock()
_pool: ProcessPoolExecutor | None = None
_waiting = 0


def _limit_worker(memory_bytes: int) -> None:
    import resource

    resource.setrlimit(resource.RLIMIT_AS, (memory_bytes, memory_bytes))
    import modd_plan.plan  # noqa: F401  (warm: the first request pays no import)


def _get_pool() -> ProcessPoolExecutor:
    global _pool
    with _lock:
        if _pool is None:
            os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # a small address space
            _pool = ProcessPoolExecutor(
                PLAN_WORKERS,
                mp_context=multiprocessing.get_context("spawn"),
                initializer=_limit_worker,
                initargs=(PLAN_MEMORY_BYTES,),
            )
        return _pool


def _discard_pool(pool: ProcessPoolExecutor) -> None:
    """Kill the workers of ``pool`` (one of them is over its time) and let
    the next request start a fresh pool."""
    global _pool
    with _lock:
        if _pool is pool:
            _pool = None
    for proc in list(getattr(pool, "_processes", {}).values()):
        proc.kill()
    pool.shutdown(wait=False, cancel_futures=True)


def shutdown_pool() -> None:
    """Stop the workers (the service's shutdown, tests); one still planning is
    killed, its answer having no one left to read it."""
    global _pool
    with _lock:
        pool, _pool = _pool, None
    if pool is not None:
        for proc in list(getattr(pool, "_processes", {}).values()):
            proc.kill()
        pool.shutdown(wait=True, cancel_futures=True)


class _OverTime(Exception):
    pass


def _over_time(_signum: int, _frame: object) -> None:
    raise _OverTime


def plan_request(
    model: dict[str, Any] | None,
    text: str | None,
    fmt: str,
    method: Method,
    timeout_s: float = PLAN_TIMEOUT_S,
    calibrate: str | None = None,
) -> dict[str, Any]:
    """In a worker: read (parse, validate) and plan within ``timeout_s``
    (a timer signal), calibrated by the archive at ``calibrate`` if given;
    the LivePlan's JSON."""
    import signal

    if method == "cvxpy":
        preload_milp()  # imports are not the model's time
    start = time.perf_counter()
    previous = signal.signal(signal.SIGALRM, _over_time)
    signal.setitimer(signal.ITIMER_REAL, timeout_s)
    try:
        if model is not None:
            result = LoadResult(model, validate(model), {})
        else:
            assert text is not None
            result = read_text(text, "modd" if fmt == "modd" else "json")
        return live_plan(result, method, calibrate).to_json()
    except _OverTime:
        return _failed(
            f"planning this model takes longer than the budget of {timeout_s:g} s",
            (time.perf_counter() - start) * 1000,
        )
    except MemoryError:
        return _failed(
            f"the planner ran out of its memory budget ({PLAN_MEMORY_BYTES >> 20} MiB)",
            (time.perf_counter() - start) * 1000,
        )
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def _failed(message: str, elapsed_ms: float) -> dict[str, Any]:
    return LivePlan(None, diagnostics_json([Diagnostic(message, "")]), elapsed_ms).to_json()


async def guarded_call(fn: Callable[..., T], *args: Any) -> T | dict[str, Any]:
    """``fn(*args, timeout_s)`` (:func:`plan_request` or a function around it
    that also reads the request body and serialises its answer, so that the
    event loop neither parses a model of 4 MiB nor walks a plan of 10 MB) in
    a worker process, within the time and memory budget; the failure's
    LivePlan JSON when the worker is over it; 503 (Retry-After) when too
    many requests already wait."""
    global _waiting
    if _waiting >= PLAN_QUEUE:
        raise HTTPException(503, "the planner is busy; retry shortly", headers={"Retry-After": "1"})
    _waiting += 1
    start = time.perf_counter()
    pool = _get_pool()
    try:
        future = pool.submit(fn, *args, PLAN_TIMEOUT_S)
        return await asyncio.wait_for(asyncio.wrap_future(future), PLAN_TIMEOUT_S + PLAN_START_S)
    except TimeoutError:  # the worker's own timer did not stop it: kill it
        _discard_pool(pool)
        return _failed(
            f"planning this model takes longer than the budget of {PLAN_TIMEOUT_S:g} s",
            (time.perf_counter() - start) * 1000,
        )
    except BrokenProcessPool:
        _discard_pool(pool)
        return _failed(
            "the planner's worker stopped (over its memory budget of "
            f"{PLAN_MEMORY_BYTES >> 20} MiB?)",
            (time.perf_counter() - start) * 1000,
        )
    finally:
        _waiting -= 1
