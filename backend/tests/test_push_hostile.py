"""``modd push`` against a server that is not (only) a MoDD workbench: a
redirect to another host is not followed and the bearer token never reaches
it; an answer that is not the API's gives a one-line error, no traceback;
plain http:// to another machine is warned about."""

from __future__ import annotations

import http.server
import json
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest
from modd_model.cli import main as modd

DEMO = Path(__file__).resolve().parents[2] / "metamodel" / "examples" / "demo.modd"
Answer = Callable[[http.server.BaseHTTPRequestHandler], None]


@contextmanager
def answering(host: str, answer: Answer, seen: list[dict[str, str]]) -> Iterator[str]:
    class Handler(http.server.BaseHTTPRequestHandler):
        def _any(self) -> None:
            seen.append({"path": self.path, **{k.lower(): v for k, v in self.headers.items()}})
            self.rfile.read(int(self.headers.get("Content-Length") or 0))
            answer(self)

        do_GET = do_POST = do_PUT = _any

        def log_message(self, *args: object) -> None:
            pass

    server = http.server.ThreadingHTTPServer((host, 0), Handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://{host}:{server.server_address[1]}"
    finally:
        server.shutdown()
        thread.join(10)
        server.server_close()


def _send(
    h: http.server.BaseHTTPRequestHandler,
    status: int,
    body: bytes,
    headers: dict[str, str] | None = None,
) -> None:
    h.send_response(status)
    for k, v in (headers or {}).items():
        h.send_header(k, v)
    h.send_header("Content-Length", str(len(body)))
    h.end_headers()
    h.wfile.write(body)


def test_a_redirect_elsewhere_gets_no_token(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setenv("MODD_PASSWORD", "pw")
    elsewhere: list[dict[str, str]] = []
    with answering("127.0.0.2", lambda h: _send(h, 200, b"[]"), elsewhere) as other:

        def workbench(h: http.server.BaseHTTPRequestHandler) -> None:
            if h.path == "/api/auth/login":
                _send(h, 200, json.dumps({"token": "secret-token"}).encode())
            else:
                _send(h, 302, b"", {"Location": other + h.path})

        with answering("127.0.0.1", workbench, []) as base:
            assert modd(["push", str(DEMO), "--server", base]) == 1
    err = capsys.readouterr().err
    assert "redirects to" in err and "not followed" in err, err
    assert not any("secret-token" in str(r) for r in elsewhere), elsewhere


@pytest.mark.parametrize("body", [b"<html>a login page</html>", b'{"ok": true}', b"[1, 2]"])
def test_an_unexpected_answer_is_one_line(
    body: bytes, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setenv("MODD_PASSWORD", "pw")
    with answering("127.0.0.1", lambda h: _send(h, 200, body), []) as base:
        assert modd(["push", str(DEMO), "--server", base]) == 1
    err = capsys.readouterr().err
    assert err.startswith("modd push: ") and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1, err


def test_plain_http_to_another_machine_is_warned() -> None:
    from modd_backend.push import plain_http_warning

    assert plain_http_warning("http://10.1.2.3:8080") is not None
    assert plain_http_warning("http://base-station.lan") is not None
    for fine in (
        "https://base-station.lan",
        "http://127.0.0.1:8080",
        "http://localhost:8080",
        "http://[::1]:8080",
        "http://127.5.5.5",
    ):
        assert plain_http_warning(fine) is None, fine
