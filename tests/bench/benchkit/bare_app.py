"""The floor of ``/api/health`` on a machine: a bare FastAPI app served by
uvicorn, answering what the workbench's health answers, from the event loop
and with nothing else to do (tests/bench/bench_health_load.py runs it pinned
to the backend's cores, beside it, under the same load).

    python -m uvicorn benchkit.bare_app:app --port 8123 --log-level warning
"""

from __future__ import annotations

from fastapi import FastAPI

app = FastAPI()


@app.get("/api/health")
async def health() -> dict[str, object]:
    return {
        "status": "ok",
        "database": "ok",
        "zenoh": "disabled",
        "scene": False,
        "ready": True,
        "saturated": False,
        "heavy_in_flight": 0,
        "heavy_limit": 8,
    }
