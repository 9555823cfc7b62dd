"""What the SubBroker keeps in its state directory (docs/subbroker.md, "State"):
the last deployment the PubBroker acknowledged (``deployed.json``: the model
and who deployed which revision, when) and the dynamic subscriptions
(``dynamic.json``). Every file is replaced atomically (temporary file, fsync,
rename), so a crash leaves the old state or the new one, never half of one.

>>> Deployment.configured().as_json()["source"]
'configured'
"""

from __future__ import annotations

import json
import logging
import time
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any, Literal

from modd_model.io import write_atomic
from modd_model.jsondepth import MAX_DEPTH, loads_bounded

from .request import MAX_DEPLOY_BYTES

log = logging.getLogger("modd.subbroker")

Source = Literal["configured", "deploy", "kept"]

#: Largest state file read, by name ("*": the others); a larger one is set aside.
#: The window record is bounded when written (record_file: epochs, intervals),
#: a kept deployment by the deploy request's bound.
MAX_STATE_BYTES = {"windows.json": 8 * 1024 * 1024, "*": MAX_DEPLOY_BYTES + 64 * 1024}


@dataclass(frozen=True)
class Deployment:
    """Where the running model came from. ``source``: the configured model,
    a deploy acknowledged by the PubBroker in this run, or a deploy kept from
    an earlier run (``resumed_at_ns`` says when this run took it up again)."""

    source: Source
    project_id: int | None = None
    revision: int | None = None
    nonce: str | None = None
    deployed_by: str | None = None
    deployed_at_ns: int | None = None
    resumed_at_ns: int | None = None

    @classmethod
    def configured(cls) -> Deployment:
        return cls("configured")

    @classmethod
    def from_request(cls, request: dict[str, Any]) -> Deployment:
        """The metadata of a (verified) deploy request; stamped when acked."""

        def num(key: str) -> int | None:
            v = request.get(key)
            return v if isinstance(v, int) and not isinstance(v, bool) else None

        def text(key: str) -> str | None:
            v = request.get(key)
            return v[:128] if isinstance(v, str) else None

        return cls("deploy", num("project_id"), num("revision"), text("nonce"), text("deployed_by"))

    def acked(self) -> Deployment:
        return replace(self, deployed_at_ns=time.time_ns())

    def as_json(self) -> dict[str, Any]:
        return asdict(self)

    def describe(self) -> str:
        rev = f"revision {self.revision}" if self.revision is not None else "a revision"
        project = f" of project {self.project_id}" if self.project_id is not None else ""
        by = f" by {self.deployed_by}" if self.deployed_by else ""
        when = ""
        if self.deployed_at_ns:
            when = " at " + time.strftime(
                "%Y-%m-%d %H:%M:%S UTC", time.gmtime(self.deployed_at_ns / 1e9)
            )
        return f"{rev}{project}, deployed{when}{by}"


def model_content(model: dict[str, Any]) -> str:
    """A model's content for comparison: canonical JSON without the layout."""
    return json.dumps({k: v for k, v in model.items() if k != "layout"}, sort_keys=True)


def same_model(a: dict[str, Any], b: dict[str, Any]) -> bool:
    return model_content(a) == model_content(b)


class StateDir:
    """The SubBroker's state directory; ``None`` keeps nothing."""

    def __init__(self, path: Path | None) -> None:
        self.path = path
        self.set_aside_files: list[dict[str, str]] = []  # for the status (bounded: 3 files)

    def _file(self, name: str) -> Path | None:
        return self.path / name if self.path is not None else None

    def _write(self, name: str, doc: Any) -> None:
        f = self._file(name)
        if f is None:
            return
        f.parent.mkdir(parents=True, exist_ok=True)
        write_atomic(f, json.dumps(doc))

    def _read(self, name: str) -> Any:
        """The parsed file, or None when absent, unreadable or not JSON within the
        bounds (then set aside, :meth:`set_aside`): bounded time and memory."""
        f = self._file(name)
        if f is None:
            return None
        limit = MAX_STATE_BYTES.get(name, MAX_STATE_BYTES["*"])
        try:
            with f.open("rb") as fh:
                raw = fh.read(limit + 1)
        except FileNotFoundError:
            return None
        except OSError as exc:
            log.error("state file %s unreadable (%s): ignored", f, exc)
            return None
        try:
            if len(raw) > limit:
                raise ValueError(f"larger than {limit} bytes")
            return loads_bounded(raw, MAX_DEPTH)
        except (ValueError, RecursionError) as exc:
            self.set_aside(name, f"not JSON within the bounds: {exc}")
            return None

    def set_aside(self, name: str, reason: str) -> Path | None:
        """Rename a state file that cannot be used to ``<name>.bad-<UTC time>`` (kept for
        a look, never read again) and say so: the run goes on without it."""
        f = self._file(name)
        if f is None:
            return None
        stamp = time.strftime("%Y%m%dT%H%M%SZ", time.gmtime())
        aside = f.with_name(f"{name}.bad-{stamp}")
        n = 1
        while aside.exists():
            aside, n = f.with_name(f"{name}.bad-{stamp}-{n}"), n + 1
        try:
            f.rename(aside)
        except OSError as exc:
            log.error("state file %s cannot be used (%s) nor set aside (%s)", f, reason, exc)
            self.set_aside_files.append({"file": str(f), "reason": reason[:300]})
            return None
        log.error(
            "state file %s cannot be used (%s): set aside as %s; the SubBroker goes on without it",
            f,
            reason,
            aside.name,
        )
        self.set_aside_files.append({"file": str(f), "aside": str(aside), "reason": reason[:300]})
        del self.set_aside_files[:-8]
        return aside

    # -- the kept deployment ---------------------------------------------------

    def save_deployment(self, model: dict[str, Any], meta: Deployment) -> None:
        self._write("deployed.json", {"model": model, "deployment": meta.as_json()})

    def load_deployment(self) -> tuple[dict[str, Any], Deployment] | None:
        """The kept model and its metadata (source ``kept``), or None. A file of
        an older version (the bare model) is read as a deploy of no revision."""
        doc = self._read("deployed.json")
        if doc is None:
            return None
        if not isinstance(doc, dict):
            self.set_aside("deployed.json", "not a kept deployment (a JSON object expected)")
            return None
        if isinstance(doc.get("model"), dict):
            model: dict[str, Any] = doc["model"]
            found = doc.get("deployment")
            raw: dict[str, Any] = found if isinstance(found, dict) else {}
        else:
            model, raw = doc, {}
        fields = {
            k: raw.get(k)
            for k in ("project_id", "revision", "nonce", "deployed_by", "deployed_at_ns")
        }
        meta = Deployment(
            "kept",
            **{
                k: v
                for k, v in fields.items()  # type: ignore[arg-type]
                if isinstance(v, int | str) and not isinstance(v, bool)
            },
        )
        return model, replace(meta, resumed_at_ns=time.time_ns())

    def deployment_file(self) -> Path | None:
        return self._file("deployed.json")

    # -- dynamic subscriptions ----------------------------------------------------

    def save_dynamic(self, subs: list[dict[str, str]]) -> None:
        self._write("dynamic.json", {"subscriptions": subs})

    def load_dynamic(self) -> list[dict[str, str]]:
        doc = self._read("dynamic.json")
        subs = doc.get("subscriptions") if isinstance(doc, dict) else None
        if not isinstance(subs, list):
            if doc is not None:
                self.set_aside("dynamic.json", 'not {"subscriptions": [...]}')
            return []
        return [
            s
            for s in subs
            if isinstance(s, dict)
            and all(
                isinstance(s.get(k), str)
                for k in ("name", "topic", "period_s", "aggregation", "owner")
            )
        ]

    # -- the window record (backfill) ---------------------------------------------

    def save_windows(self, doc: dict[str, Any]) -> None:
        self._write("windows.json", doc)

    def journal_path(self) -> Path | None:
        """Where the windows delivered since the record was saved are written
        (window_journal.py); None without a state directory."""
        return self._file("windows.journal")

    def load_windows(self) -> Any:
        return self._read("windows.json")
