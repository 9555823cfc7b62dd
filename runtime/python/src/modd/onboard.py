"""The on-board model file: how a deploy reaches ``modd-sensors`` and
``modd-mavlink`` without restarting anything (docs/sensors.md, "Deploying to a
running drone").

Whoever learns of an acked deploy on the drone's machine writes the model to
the file (:func:`hand_over`, atomically); each on-board process started with
``--watch`` follows it (:class:`ModelWatch`, polled every ``POLL_S``), applies
what changed and writes what it did to ``<dir>/applied/<process>.json``
(:func:`write_result`), tagged with the digest of the file it applied. The
hand-over waits for those results (:func:`wait_results`) and puts them in the
deploy's acknowledgement.

Example::

    digest = hand_over(path, model)                  # the SubBroker, after CONFIG_ACK
    results = wait_results(path, digest, 2.0)        # {"sensors": {...}, "mavlink": {...}}
"""

from __future__ import annotations

import hashlib
import json
import os
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

POLL_S = 0.1  # how often a process looks at the model file
RESULT_WAIT_S = 2.0  # how long the hand-over waits for the processes' results
MAX_MODEL_BYTES = 4 << 20  # a larger file is refused, not read


def digest(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()[:16]


def results_dir(model_path: Path) -> Path:
    return model_path.parent / "applied"


def _replace(path: Path, data: bytes) -> None:
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_bytes(data)
    os.replace(tmp, path)


def _valid_file(model_path: Path) -> Path:
    return model_path.with_name(model_path.name + ".valid")


def model_bytes(model: dict[str, Any]) -> bytes:
    """The on-board model file's bytes for ``model`` (what :func:`hand_over` writes,
    and what ONBOARD carries compressed: the PubBroker writes them as they are)."""
    return (json.dumps(model, indent=1, sort_keys=True) + "\n").encode()


def pack(model: dict[str, Any]) -> bytes:
    """ONBOARD's payload: :func:`model_bytes` as one zstd frame (its size in the header,
    so that the PubBroker bounds it before decompressing)."""
    import zstandard

    return zstandard.ZstdCompressor(level=19, write_content_size=True).compress(model_bytes(model))


def unpack_answers(data: bytes, limit: int) -> dict[str, Any]:
    """ONBOARD_ACK's answers (a zstd frame of a JSON object, at most ``limit`` bytes
    once decompressed); ValueError naming what is wrong."""
    import zstandard

    try:
        size = zstandard.get_frame_parameters(data).content_size
        if size > limit:  # declared above the bound, or not declared (2^64 - 1): refused
            raise ValueError(f"{size} B once decompressed, above {limit} B")
        raw = zstandard.ZstdDecompressor().decompress(data, max_output_size=limit)
        doc = json.loads(raw)
    except (zstandard.ZstdError, ValueError) as exc:
        raise ValueError(f"unreadable on-board answers: {exc}") from exc
    if not isinstance(doc, dict):
        raise ValueError("on-board answers are not a JSON object")
    return doc


def hand_over(model_path: Path, model: dict[str, Any]) -> str:
    """Writes ``model`` (the deployed JSON document, validated by the caller) to the
    on-board model file; its digest. The digest goes first to ``<file>.valid``: a
    process finding it there need not check the model again (:func:`validated`)."""
    data = model_bytes(model)
    _replace(_valid_file(model_path), (digest(data) + "\n").encode())
    _replace(model_path, data)
    return digest(data)


def validated(model_path: Path, applied: str) -> dict[str, Any] | None:
    """The model file's document when it is the one of digest ``applied`` and the
    hand-over said it valid; None otherwise (a file edited by hand: check it)."""
    try:
        if _valid_file(model_path).read_text().strip() != applied:
            return None
        data = model_path.read_bytes()
    except OSError:
        return None
    if digest(data) != applied:
        return None
    try:
        doc = json.loads(data)
    except ValueError:
        return None
    return doc if isinstance(doc, dict) else None


def write_result(model_path: Path, process: str, applied: str, result: dict[str, Any]) -> None:
    """What ``process`` did with the model file of digest ``applied``."""
    out = results_dir(model_path)
    out.mkdir(parents=True, exist_ok=True)
    doc = {"process": process, "pid": os.getpid(), "digest": applied, "at_ns": time.time_ns()}
    _replace(out / f"{process}.json", (json.dumps({**doc, **result}) + "\n").encode())


def read_results(model_path: Path) -> dict[str, dict[str, Any]]:
    """Every process's last result, by process name (unreadable files left out)."""
    out: dict[str, dict[str, Any]] = {}
    folder = results_dir(model_path)
    for f in sorted(folder.glob("*.json")) if folder.is_dir() else []:
        try:
            doc = json.loads(f.read_text())
        except (OSError, ValueError):
            continue
        if isinstance(doc, dict):
            out[f.stem] = doc
    return out


def wait_results(
    model_path: Path, applied: str, timeout_s: float = RESULT_WAIT_S
) -> dict[str, dict[str, Any]]:
    """The processes' results for the model of digest ``applied``; a process that
    has not answered within ``timeout_s`` is there with ``ok`` false and why."""
    deadline = time.monotonic() + timeout_s
    while True:
        results = read_results(model_path)
        if all(r.get("digest") == applied for r in results.values()):
            return results
        if time.monotonic() >= deadline:
            break
        time.sleep(0.05)
    return {
        name: r
        if r.get("digest") == applied
        else {"process": name, "ok": False, "problem": f"no answer within {timeout_s:g} s"}
        for name, r in results.items()
    }


class ModelWatch:
    """Tells when the model file's content changed (``poll`` gives the new bytes)."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self._seen: tuple[int, int] | None = None
        self.digest = ""
        self.poll()

    def poll(self) -> bytes | None:
        try:
            st = self.path.stat()
        except OSError:
            return None
        key = (st.st_mtime_ns, st.st_size)
        if key == self._seen or st.st_size > MAX_MODEL_BYTES:
            return None
        self._seen = key
        try:
            data = self.path.read_bytes()
        except OSError:
            return None
        if digest(data) == self.digest:
            return None
        self.digest = digest(data)
        return data


def follow(
    watch: ModelWatch, apply: Callable[[str], None], stop: Any, period_s: float = POLL_S
) -> None:
    """Calls ``apply(digest)`` each time the model file changes, until ``stop`` is set."""
    while not stop.wait(period_s):
        if watch.poll() is not None:
            apply(watch.digest)
