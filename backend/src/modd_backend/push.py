"""``modd push MODEL --server URL [--project NAME] [--deploy]``: put a model file
into a running workbench, as a new project or a new revision of an existing
one, and optionally deploy it. It speaks only the public REST API
(docs/backend.md), so it works against any workbench, local or remote.

The password comes from ``$MODD_PASSWORD`` or ``--password-file``, never from
the command line (which other users of the machine can read in ``ps``).
Redirects are not followed (the bearer token would travel to wherever they
point): the error names the address to give instead. A plain ``http://``
server that is not loopback gets a warning: the password and token cross the
network in clear.

Deploying needs the drone's SubBroker to answer; ``--wait S`` retries a
failed deploy until then (e.g. right after ``modd up`` started it).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
import urllib.error
import urllib.parse
import urllib.request
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .zenoh_session import read_secret


class PushError(Exception):
    """The workbench refused or could not be reached; the message says which step."""


class _NoRedirect(urllib.request.HTTPRedirectHandler):
    """A redirect ends the push (urllib would send the token along)."""

    def redirect_request(
        self, req: urllib.request.Request, fp: Any, code: int, msg: str, headers: Any, newurl: str
    ) -> urllib.request.Request | None:
        raise PushError(
            f"{req.get_method()} {req.full_url}: the server redirects to "
            f"{newurl[:200]!r}; not followed (the token would go along): give "
            "the workbench's own address with --server"
        )


_OPENER = urllib.request.build_opener(_NoRedirect)


def plain_http_warning(server: str) -> str | None:
    """A warning when ``server`` is plain http:// to a host not on loopback.

    >>> plain_http_warning("http://127.0.0.1:8080") is None
    True
    >>> plain_http_warning("http://base.example:8080")[:40]
    'warning: http://base.example:8080 is pla'
    """
    import ipaddress

    url = urllib.parse.urlsplit(server)
    host = url.hostname or ""
    if url.scheme != "http" or host == "localhost" or host.endswith(".localhost"):
        return None
    try:
        if ipaddress.ip_address(host).is_loopback:
            return None
    except ValueError:
        pass
    return (
        f"warning: {server} is plain http to another machine: the password and the "
        "session token cross the network in clear (use https://)"
    )


@dataclass
class Client:
    """The few REST calls a push needs, on the standard library only."""

    server: str
    token: str | None = None
    timeout_s: float = 30.0

    def call(
        self,
        method: str,
        path: str,
        body: Any = None,
        *,
        raw: bytes | None = None,
        content_type: str = "application/json",
    ) -> Any:
        data = raw if raw is not None else (None if body is None else json.dumps(body).encode())
        req = urllib.request.Request(self.server.rstrip("/") + path, data=data, method=method)
        if data is not None:
            req.add_header("Content-Type", content_type)
        if self.token:
            req.add_header("Authorization", f"Bearer {self.token}")
        try:
            with _OPENER.open(req, timeout=self.timeout_s) as resp:
                text = resp.read().decode(errors="replace")
        except urllib.error.HTTPError as exc:
            raise PushError(f"{method} {path}: HTTP {exc.code}: {_detail(exc.read())}") from None
        except (urllib.error.URLError, OSError) as exc:
            raise PushError(f"{method} {path}: cannot reach {self.server}: {exc}") from None
        try:
            return json.loads(text) if text else None
        except ValueError:
            raise PushError(
                f"{method} {path}: {self.server} answered something that is not "
                f"the workbench's JSON: {text[:120]!r}"
            ) from None

    def login(self, user: str, password: str) -> None:
        out = self.call("POST", "/api/auth/login", {"username": user, "password": password})
        self.token = out["token"]


def _detail(body: bytes) -> str:
    try:
        parsed = json.loads(body)
    except ValueError:
        return body.decode(errors="replace")[:500]
    if isinstance(parsed, dict):
        detail = str(parsed.get("detail", parsed))
        diags = parsed.get("diagnostics") or []
        lines = [
            f"  {d.get('file') or ''}:{d.get('line') or ''}: {d.get('message')}"
            for d in diags[:10]
            if isinstance(d, dict)
        ]
        return "\n".join([detail, *lines])
    return str(parsed)


def find_project(client: Client, name: str) -> dict[str, Any] | None:
    projects: list[dict[str, Any]] = client.call("GET", "/api/projects")
    return next((p for p in projects if p["name"] == name), None)


def push_model(client: Client, text: str, fmt: str, name: str, message: str) -> tuple[int, int]:
    """(project id, revision) holding the model; a new revision only when the
    model differs from the head, so pushing the same file twice is a no-op."""
    project = find_project(client, name)
    if project is None:
        query = urllib.parse.urlencode({"name": name, "format": fmt})
        created = client.call(
            "POST", f"/api/projects/import?{query}", raw=text.encode(), content_type="text/plain"
        )
        return int(created["id"]), int(created["head_revision"])
    pid = int(project["id"])
    head = client.call("GET", f"/api/projects/{pid}/model") if project["head_revision"] else None
    checked = client.call("POST", "/api/validate", {"text": text, "format": fmt})
    if head is not None and _content(checked.get("model")) == _content(head["model"]):
        return pid, int(head["revision"])
    saved = client.call(
        "PUT",
        f"/api/projects/{pid}/model",
        {
            "base_revision": project["head_revision"],
            "text": text,
            "format": fmt,
            "message": message,
        },
    )
    return pid, int(saved["revision"])


def keep_project(client: Client, name: str) -> tuple[int, int] | None:
    """``--if-new``: (project id, revision to run) when the project exists: the
    revision last deployed with an ack, else the head. None: no such project."""
    project = find_project(client, name)
    if project is None or not project["head_revision"]:
        return None
    pid = int(project["id"])
    records: list[dict[str, Any]] = client.call("GET", f"/api/projects/{pid}/deployments")
    acked = [r for r in records if r.get("status") == "acked"]
    if acked:
        return pid, int(max(acked, key=lambda r: int(r["id"]))["revision"])
    return pid, int(project["head_revision"])


def _content(model: Any) -> Any:
    """The model without its diagram layout, which a .modd file does not carry."""
    if isinstance(model, dict):
        return {k: v for k, v in model.items() if k != "layout"}
    return model


def deploy(client: Client, project_id: int, revision: int, wait_s: float) -> dict[str, Any]:
    """Deploy, retrying failures (a SubBroker not up yet) until wait_s has passed."""
    deadline = time.monotonic() + wait_s
    while True:
        record: dict[str, Any] = client.call(
            "POST", f"/api/projects/{project_id}/deployments", {"revision": revision}
        )
        if record["status"] == "acked" or time.monotonic() >= deadline:
            return record
        time.sleep(1.0)


def _password(args: argparse.Namespace) -> str:
    if args.password_file:
        try:  # a small regular file, not a link (docs/security.md)
            return read_secret(Path(args.password_file), "password file").strip()
        except (OSError, ValueError) as exc:
            raise PushError(f"--password-file {args.password_file}: {exc}") from None
    if pw := os.environ.get("MODD_PASSWORD"):
        return pw
    raise PushError("no password: set MODD_PASSWORD or give --password-file")


def run(args: argparse.Namespace) -> int:
    path = Path(args.model)
    fmt = "json" if path.suffix == ".json" else "modd"
    name = args.project or path.stem
    warning = plain_http_warning(args.server)
    if warning is not None:
        print(f"modd push: {warning}", file=sys.stderr)
    try:
        text = path.read_text()
        client = Client(args.server)
        client.login(args.user, _password(args))
        kept = keep_project(client, name) if args.if_new else None
        if kept is not None:
            pid, revision = kept
            print(
                f"modd push: project {name!r} (id {pid}) exists: kept as it is, "
                f"running revision {revision}"
            )
        else:
            pid, revision = push_model(
                client, text, fmt, name, args.message or f"pushed {path.name}"
            )
            print(f"modd push: project {name!r} (id {pid}) at revision {revision}")
        if not args.deploy:
            return 0
        record = deploy(client, pid, revision, args.wait)
    except (OSError, PushError) as exc:
        print(f"modd push: {exc}", file=sys.stderr)
        return 1
    except (KeyError, TypeError, ValueError, AttributeError) as exc:  # not the API's shape
        print(
            f"modd push: unexpected answer from {args.server} (is it a MoDD workbench?): "
            f"{type(exc).__name__}: {str(exc)[:120]}",
            file=sys.stderr,
        )
        return 1
    if record.get("status") != "acked":
        print(
            f"modd push: deploy to drone {record.get('drone')!r} {record.get('status')}: "
            f"{record.get('error')}",
            file=sys.stderr,
        )
        return 1
    print(f"modd push: deployed revision {revision} to drone {record.get('drone')!r} (acked)")
    return 0


def register(sub: Any) -> None:
    p = sub.add_parser("push", help="put a model into a running workbench (and deploy it)")
    p.add_argument("model", metavar="MODEL", help=".modd or .json model")
    p.add_argument("--server", default="http://127.0.0.1:8080", help="workbench URL")
    p.add_argument("--user", default="admin")
    p.add_argument("--password-file", metavar="FILE", help="default: $MODD_PASSWORD")
    p.add_argument("--project", metavar="NAME", help="project name (default: the file's stem)")
    p.add_argument("--message", help="revision message")
    p.add_argument(
        "--if-new",
        action="store_true",
        help="load the model only into a new project; an existing one is kept "
        "(--deploy then deploys its last deployed revision, else its head)",
    )
    p.add_argument("--deploy", action="store_true", help="deploy the pushed revision")
    p.add_argument(
        "--wait",
        type=float,
        default=0.0,
        metavar="S",
        help="retry a failed deploy for up to S seconds",
    )
    p.set_defaults(func=run)
