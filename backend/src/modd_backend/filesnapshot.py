"""A download of a file that may still grow (the archive the drone is
writing, the base station's record): exactly the bytes it held when the
download began, with that ``Content-Length``. (Starlette's FileResponse
declares the size it saw, then reads on to the end of the file: a file that
grew meanwhile sent more than declared and the server cut the connection.)

>>> file_snapshot(Path("run-0001.mcap"))   # doctest: +SKIP
"""

from __future__ import annotations

import os
from collections.abc import AsyncIterator
from pathlib import Path
from typing import BinaryIO

from starlette.concurrency import run_in_threadpool
from starlette.responses import StreamingResponse

from .downloads import content_disposition

CHUNK = 64 * 1024


async def _read(f: BinaryIO, size: int) -> AsyncIterator[bytes]:
    try:
        left = size
        while left > 0:
            chunk = await run_in_threadpool(f.read, min(CHUNK, left))
            if not chunk:  # shortened meanwhile: an append-only file never is
                return
            left -= len(chunk)
            yield chunk
    finally:
        f.close()


def file_snapshot(path: Path, media_type: str = "application/octet-stream") -> StreamingResponse:
    """The first ``size`` bytes of ``path``, ``size`` taken from the open file."""
    f = path.open("rb")
    size = os.fstat(f.fileno()).st_size
    return StreamingResponse(
        _read(f, size),
        media_type=media_type,
        headers={
            "Content-Length": str(size),
            "Content-Disposition": content_disposition(path.name),
        },
    )
