"""The workbench's local server: the page, its files, and one JSON route per computation.

A Starlette application (:func:`create_app`) served by uvicorn on 127.0.0.1 only
(:func:`serve`). Every request passes :class:`Guard` first:

- the path starts with the random token of the URL (else 404, the same for every path);
- ``Host`` is the served address and ``Origin``, when sent, the served origin (else 403:
  another site's page, or a DNS name rebound to 127.0.0.1, is refused);
- only GET and POST; a POST carries ``Content-Type: application/json`` and at most
  :data:`MAX_BODY` bytes (else 415, 413);
- a body that is not JSON, or not the shape a route expects, gets a 400 with a message;
  no traceback ever reaches the page.

The server reads and writes the one graph file it was started on (and, for the full run,
the result folder ``<stem>-result`` beside it); the page's JSON is turned into TOML and
read by the graph's own parser, and nothing it sends is evaluated.
"""

from __future__ import annotations

import asyncio
import hashlib
import hmac
import secrets
import signal
import socket
import sys
import threading
import webbrowser
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from types import FrameType
from typing import Any

from starlette.applications import Starlette
from starlette.concurrency import run_in_threadpool
from starlette.requests import Request
from starlette.responses import HTMLResponse, JSONResponse, Response
from starlette.routing import Mount, Route
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from mtmc.errors import InputError, MtmcError
from mtmc.io import decode_utf8, loads_json, to_jsonable, write_text_atomic
from mtmc.workbench import compute
from mtmc.workbench.view import GraphDocument, check_payload, graph_json

__all__ = ["MAX_BODY", "Guard", "Session", "create_app", "serve"]

#: The largest request body, bytes (a graph of Stryczek's size is some tens of kB).
MAX_BODY = 2 * 1024 * 1024
#: Suffixes of the static files and their content types.
CONTENT_TYPES = {
    ".html": "text/html; charset=utf-8",
    ".js": "text/javascript; charset=utf-8",
    ".mjs": "text/javascript; charset=utf-8",
    ".css": "text/css; charset=utf-8",
    ".json": "application/json",
    ".png": "image/png",
    ".svg": "image/svg+xml",
    ".txt": "text/plain; charset=utf-8",
    ".md": "text/plain; charset=utf-8",
}
_PAGE_POLICY = (
    "default-src 'self'; script-src 'self'; style-src 'self' 'unsafe-inline'; "
    "img-src 'self' data: blob:; connect-src 'self'; object-src 'none'; base-uri 'none'; "
    "frame-ancestors 'none'; form-action 'none'"
)
_REPORT_POLICY = (
    "default-src 'none'; style-src 'unsafe-inline'; img-src data:; script-src 'unsafe-inline'; "
    "frame-ancestors 'none'"
)


@dataclass
class Session:
    """The one graph file the server edits, and what the page last said of it.

    Parameters
    ----------
    path : Path
        The graph file (it need not exist yet: the first save creates it).
    """

    path: Path
    doc: GraphDocument = field(init=False)
    unsaved: bool = False
    latest: dict[str, int] = field(default_factory=dict)
    result_dir: Path | None = None
    loaded_sha: str | None = field(init=False, default=None)
    compute_lock: threading.Lock = field(default_factory=threading.Lock)
    file_lock: threading.Lock = field(default_factory=threading.Lock)

    def __post_init__(self) -> None:
        if not self.path.exists() and not self.path.parent.is_dir():
            raise InputError(
                f"no folder {self.path.parent} to create the graph file in", file=str(self.path)
            )
        self.load()

    def on_disk(self) -> bytes | None:
        """The graph file's bytes as they are now (None where there is no file)."""
        if not self.path.exists():
            return None
        try:
            return self.path.read_bytes()
        except OSError as exc:
            raise InputError(
                f"cannot read the graph file: {exc.strerror or exc}", file=str(self.path)
            ) from None

    def load(self) -> None:
        """Read the graph file (again), and remember its SHA-256 to see a later change on disk."""
        data = self.on_disk()
        text = "" if data is None else decode_utf8(data, self.path.name)
        self.doc = GraphDocument(text, self.path.name)
        self.loaded_sha = _sha(data)
        self.unsaved = False

    def changed_on_disk(self) -> bool:
        """Whether the file on disk is no longer the one the page was given (or last saved)."""
        return _sha(self.on_disk()) != self.loaded_sha

    @property
    def name(self) -> str:
        """The file's name, as messages give it."""
        return self.path.name


def _sha(data: bytes | None) -> str | None:
    return None if data is None else hashlib.sha256(data).hexdigest()


class _Refused(Exception):
    def __init__(self, status: int, message: str) -> None:
        super().__init__(message)
        self.status = status
        self.message = message


def _headers(scope: Scope) -> dict[str, str]:
    return {k.decode("latin-1").lower(): v.decode("latin-1") for k, v in scope["headers"]}


class Guard:
    """The checks every request passes before the application sees it (module docstring).

    Parameters
    ----------
    app : ASGI application
        The application behind the guard.
    token : str
        The random token: the first segment of every path.
    host : str
        The served ``host:port`` (``127.0.0.1:8765``); the origin is ``http://`` it.
    max_body : int
        The largest body, bytes.
    """

    def __init__(self, app: ASGIApp, token: str, host: str, max_body: int = MAX_BODY) -> None:
        self.app = app
        self.token = token.encode()
        self.host = host
        self.origin = f"http://{host}"
        self.max_body = max_body

    def _check(self, scope: Scope) -> None:
        h = _headers(scope)
        if h.get("host") != self.host:
            raise _Refused(403, f"refused: Host {h.get('host')!r} is not {self.host}")
        origin = h.get("origin")
        if origin is not None and origin != self.origin:
            raise _Refused(403, f"refused: Origin {origin!r} is not {self.origin}")
        if h.get("sec-fetch-site", "same-origin") not in ("same-origin", "none"):
            raise _Refused(403, "refused: a request from another site")
        segment = scope["path"].lstrip("/").split("/", 1)[0].encode()
        if not hmac.compare_digest(segment, self.token):
            raise _Refused(404, "not found")
        method = scope["method"]
        if method not in ("GET", "HEAD", "POST"):
            raise _Refused(405, f"method {method} not allowed")
        if method == "POST":
            if h.get("content-type", "").split(";")[0].strip() != "application/json":
                raise _Refused(415, "expected Content-Type: application/json")
            length = h.get("content-length")
            if length is not None and (not length.isdigit() or int(length) > self.max_body):
                raise _Refused(413, f"the body is larger than {self.max_body} bytes")

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        """Refuse the request, or pass it on with a bounded body and the security headers."""
        if scope["type"] == "lifespan":
            await self.app(scope, receive, send)
            return
        if scope["type"] != "http":  # no websockets
            return
        try:
            self._check(scope)
        except _Refused as exc:
            await _plain(exc.status, exc.message)(scope, receive, send)
            return
        received = 0

        async def limited() -> Message:
            nonlocal received
            message = await receive()
            received += len(message.get("body", b""))
            if received > self.max_body:
                raise _Refused(413, f"the body is larger than {self.max_body} bytes")
            return message

        async def secured(message: Message) -> None:
            if message["type"] == "http.response.start":
                headers = list(message.get("headers", []))
                names = {k.lower() for k, _ in headers}
                for k, v in (
                    (b"referrer-policy", b"no-referrer"),
                    (b"x-content-type-options", b"nosniff"),
                    (b"cache-control", b"no-store"),
                    (b"x-frame-options", b"DENY"),
                    (b"content-security-policy", _PAGE_POLICY.encode()),
                ):
                    if k not in names:
                        headers.append((k, v))
                message = {**message, "headers": headers}
            await send(message)

        await self.app(scope, limited, secured)


def _plain(status: int, message: str) -> Response:
    return JSONResponse({"error": message}, status_code=status)


def _json(obj: Any, status: int = 200) -> Response:
    return JSONResponse(to_jsonable(obj, nonfinite_as_null=True), status_code=status)


async def _body(request: Request) -> dict[str, Any]:
    chunks = []
    async for chunk in request.stream():
        chunks.append(chunk)
    raw = b"".join(chunks)
    try:
        data = loads_json(raw.decode("utf-8"), "the body")
    except UnicodeDecodeError as exc:
        raise _Refused(400, f"the body is not JSON: {exc}") from None
    if not isinstance(data, dict):
        raise _Refused(400, "the body must be a JSON object")
    return data


Endpoint = Callable[[Request], Awaitable[Response]]


def _route(func: Callable[[Request, Session], Awaitable[Any]], session: Session) -> Endpoint:
    """An endpoint: errors as one line of JSON (400 for the input, 500 for a bug)."""

    async def endpoint(request: Request) -> Response:
        try:
            out = await func(request, session)
        except _Refused as exc:
            return _plain(exc.status, exc.message)
        except MtmcError as exc:
            return _plain(400, str(exc))
        except Exception as exc:  # a bug: one line, no traceback
            return _plain(500, f"internal error: {type(exc).__name__}: {exc}")
        return out if isinstance(out, Response) else _json(out)

    return endpoint


def _graph_of(data: dict[str, Any], session: Session) -> dict[str, Any]:
    if "graph" not in data:
        raise _Refused(400, "missing graph")
    return check_payload(data["graph"], session.doc.view)


def _static_files() -> dict[str, tuple[bytes, str]]:
    """The page's files by path under ``static/`` (the only files the server sends)."""
    out: dict[str, tuple[bytes, str]] = {}
    root = resources.files("mtmc.workbench") / "static"

    def walk(node: Any, prefix: str) -> None:
        for child in node.iterdir():
            name = prefix + child.name
            if child.is_dir():
                walk(child, name + "/")
            else:
                suffix = "." + child.name.rsplit(".", 1)[-1] if "." in child.name else ""
                if suffix in CONTENT_TYPES:
                    out[name] = (child.read_bytes(), CONTENT_TYPES[suffix])

    walk(root, "")
    return out


# --------------------------------------------------------------------------- routes


async def _get_graph(_: Request, s: Session) -> Any:
    with s.file_lock:
        if s.changed_on_disk():  # edited on disk: a page (re)loading shows the file as it is
            s.load()
    text = s.doc.text
    plan, report = await run_in_threadpool(compute.check_text, text, s.name)
    return {
        "file": s.name,
        "exists": s.path.exists(),
        "view": s.doc.view,
        "palette": compute.palette(),
        "check": report,
        "positions": compute.positions(plan),
        "live": {"trials": compute.LIVE_TRIALS, "seed": compute.LIVE_SEED},
        "unsaved": s.unsaved,
    }


async def _check(request: Request, s: Session) -> Any:
    view = _graph_of(await _body(request), s)
    text = s.doc.render(view)
    plan, report = await run_in_threadpool(compute.check_text, text, s.name)
    report["positions"] = compute.positions(plan)
    return report


async def _run(request: Request, s: Session) -> Any:
    data = await _body(request)
    seq, client = data.get("seq", 0), data.get("client", "")
    if isinstance(seq, bool) or not isinstance(seq, int):
        raise _Refused(400, "seq must be an integer")
    if not isinstance(client, str) or len(client) > 64:
        raise _Refused(400, "client must be a short string")
    selected = data.get("selected")
    if selected is not None and not isinstance(selected, str):
        raise _Refused(400, "selected must be a place name")
    view = _graph_of(data, s)
    text = s.doc.render(view)
    # requests are numbered by each page (a reload starts again): the latest of each wins
    if client not in s.latest and len(s.latest) >= 16:
        s.latest.pop(next(iter(s.latest)))
    s.latest[client] = max(s.latest.get(client, 0), seq)

    def work() -> dict[str, Any]:
        with s.compute_lock:  # one run at a time; a newer request makes this one stale
            if seq < s.latest[client]:
                return {"seq": seq, "stale": True}
            out = compute.live_run(text, s.name, selected=selected)
        out["seq"] = seq
        return out

    return await run_in_threadpool(work)


async def _arc(request: Request, s: Session) -> Any:
    data = await _body(request)
    view = _graph_of(data, s)
    source, target, types = data.get("source"), data.get("target"), data.get("types", {})
    if not isinstance(source, str) or not isinstance(target, str):
        raise _Refused(400, "source and target must be node names")
    if not isinstance(types, dict) or not all(isinstance(v, str) for v in types.values()):
        raise _Refused(400, "types must map place names to types")
    why = compute.arc_refusal(view, source, target, types)
    return {"ok": why is None, "message": why}


async def _save(request: Request, s: Session) -> Any:
    view = _graph_of(await _body(request), s)
    text = s.doc.render(view)
    plan, report = await run_in_threadpool(compute.check_text, text, s.name)

    def write() -> None:
        with s.file_lock:
            if s.changed_on_disk():
                raise _Refused(
                    409,
                    f"{s.name} was changed on disk after this page loaded it; not saved, so "
                    "that change is kept. Reload the page to edit the file as it is now "
                    "(the edits made here since are lost).",
                )
            write_text_atomic(s.path, text)
            s.doc.rebase(text)
            s.loaded_sha = _sha(text.encode("utf-8"))
            s.unsaved = False

    try:
        await run_in_threadpool(write)
    except OSError as exc:
        raise _Refused(500, f"{s.path}: cannot write: {exc.strerror or exc}") from None
    return {
        "saved": s.name,
        "bytes": len(text.encode("utf-8")),
        "view": s.doc.view,
        "check": report,
        "positions": compute.positions(plan),
    }


async def _dirty(request: Request, s: Session) -> Any:
    data = await _body(request)
    dirty = data.get("dirty")
    if not isinstance(dirty, bool):
        raise _Refused(400, "dirty must be true or false")
    s.unsaved = dirty
    return {"unsaved": s.unsaved}


def _int_field(data: dict[str, Any], key: str, low: int, default: int | None) -> int | None:
    v = data.get(key, default)
    if v is None:
        return None
    if isinstance(v, bool) or not isinstance(v, int) or v < low:
        raise _Refused(400, f"{key} must be an integer >= {low}")
    return v


async def _full_run(request: Request, s: Session) -> Any:
    data = await _body(request)
    trials = _int_field(data, "trials", 2, 200_000)
    seed = _int_field(data, "seed", 0, None)
    outputs = data.get("outputs")
    if not isinstance(outputs, list) or not outputs or not all(isinstance(o, str) for o in outputs):
        raise _Refused(400, "outputs must be a non-empty list of place names")
    if s.unsaved or not s.path.exists():
        raise _Refused(409, "save the graph first: the full run reads the saved file")
    assert trials is not None
    title = s.doc.view.get("title", "")

    def work() -> Path:
        with s.compute_lock:
            return compute.full_run(s.path, title, outputs, trials, seed)

    s.result_dir = await run_in_threadpool(work)
    return {"folder": str(s.result_dir), "report": "report"}


async def _report(_: Request, s: Session) -> Any:
    if s.result_dir is None or not (s.result_dir / "report.html").is_file():
        raise _Refused(404, "no full run yet")
    html = (s.result_dir / "report.html").read_text(encoding="utf-8")
    return HTMLResponse(html, headers={"content-security-policy": _REPORT_POLICY})


async def _export(request: Request, s: Session) -> Any:
    from mtmc.graph import dumps_assertions, graph_to_dot, loads_graph

    data = await _body(request)
    view = _graph_of(data, s)
    to = data.get("to")
    text = s.doc.render(view)
    stem = s.path.stem
    if to == "toml":
        return {"text": text, "filename": f"{stem}.toml"}
    if to not in ("assertions", "dot"):
        raise _Refused(400, "to must be toml, assertions or dot")
    graph = await run_in_threadpool(lambda: loads_graph(text, file=s.name))
    if to == "assertions":
        return {"text": dumps_assertions(graph), "filename": f"{stem}.pl"}
    return {"text": graph_to_dot(graph), "filename": f"{stem}.dot"}


async def _import(request: Request, _: Session) -> Any:
    from mtmc.graph import dumps_graph, loads_assertions

    data = await _body(request)
    text, fmt = data.get("text"), data.get("format")
    if not isinstance(text, str):
        raise _Refused(400, "text must be a string")
    if fmt == "assertions":
        graph = await run_in_threadpool(lambda: loads_assertions(text, validate=False))
        toml_text = dumps_graph(graph)
    elif fmt == "toml":
        toml_text = text
    else:
        raise _Refused(400, "format must be assertions or toml")
    view = graph_json(toml_text, "imported")
    for entry in (*view["places"], *view["transitions"]):
        entry["src"] = None
    return {"view": view}


def create_app(session: Session, token: str, host: str, max_body: int = MAX_BODY) -> ASGIApp:
    """The workbench application for one file, behind its :class:`Guard`.

    Parameters
    ----------
    session : Session
        The file being edited.
    token : str
        The random token of the URL (the first path segment of every request).
    host : str
        The served ``host:port``.
    max_body : int
        The largest request body, bytes.

    Returns
    -------
    ASGI application
        The guarded application.
    """
    files = _static_files()

    async def page(_: Request) -> Response:
        body, kind = files["index.html"]
        return Response(body, media_type=kind)

    async def static(request: Request) -> Response:
        name = request.path_params["name"]
        if name not in files:
            return _plain(404, "not found")
        body, kind = files[name]
        return Response(body, headers={"content-type": kind})

    posts = {
        "check": _check,
        "run": _run,
        "arc": _arc,
        "save": _save,
        "dirty": _dirty,
        "full-run": _full_run,
        "export": _export,
        "import": _import,
    }
    routes = [
        Route("/", page, methods=["GET"]),
        Route("/static/{name:path}", static, methods=["GET"]),
        Route("/api/graph", _route(_get_graph, session), methods=["GET"]),
        Route("/report", _route(_report, session), methods=["GET"]),
        *(
            Route(f"/api/{name}", _route(func, session), methods=["POST"])
            for name, func in posts.items()
        ),
    ]
    app = Starlette(routes=[Mount(f"/{token}", routes=routes)])
    return Guard(app, token, host, max_body)


def _listen(port: int) -> socket.socket:
    sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    try:
        sock.bind(("127.0.0.1", port))
    except OSError as exc:
        sock.close()
        raise InputError(
            f"cannot listen on 127.0.0.1:{port}: {exc.strerror or exc}", field="--port"
        ) from None
    sock.listen(64)
    return sock


def serve(
    path: str | Path,
    *,
    port: int = 0,
    open_browser: bool = True,
    echo: Callable[[str], None] = print,
) -> None:
    """Serve the workbench for ``path`` on 127.0.0.1 until Ctrl-C.

    The first line printed is the URL (with its token). Ctrl-C stops the server; while
    the page holds an unsaved edit, the first Ctrl-C only says so and a second one stops.

    Parameters
    ----------
    path : str or Path
        The TOML graph file (created on the first save if it does not exist).
    port : int
        The port (0: a free one).
    open_browser : bool
        Open the URL in the default browser.
    echo : callable
        Where the lines go (default: stdout).

    Raises
    ------
    InputError
        If the file is not a TOML graph file, cannot be read, or the port is taken.
    ParseError
        If the file is not TOML.
    """
    import uvicorn

    from mtmc.graph.files import ASSERTION_SUFFIXES

    p = Path(path)
    if p.suffix.lower() in ASSERTION_SUFFIXES:
        raise InputError(
            "the workbench edits TOML graph files; import the assertion database in the page, "
            f"or convert it with: mtmc graph export {p} --to toml -o {p.stem}.toml",
            file=str(p),
        )
    session = Session(p)
    sock = _listen(port)
    host = f"127.0.0.1:{sock.getsockname()[1]}"
    token = secrets.token_urlsafe(24)
    url = f"http://{host}/{token}/"
    echo(url)
    sys.stdout.flush()
    config = uvicorn.Config(
        create_app(session, token, host),
        log_level="warning",
        lifespan="off",
        timeout_graceful_shutdown=2,
    )
    server = _Server(config, session, echo)
    if open_browser:
        threading.Timer(0.3, webbrowser.open, (url,)).start()
    try:
        server.run(sockets=[sock])
    except KeyboardInterrupt:
        pass
    finally:
        sock.close()
    echo("mtmc: workbench stopped" + (" (unsaved edits discarded)" if session.unsaved else ""))


class _Server:
    """uvicorn's server, whose first Ctrl-C over an unsaved edit only warns."""

    def __init__(self, config: Any, session: Session, echo: Callable[[str], None]) -> None:
        import uvicorn

        session_ = session
        warned = {"done": False}

        class Server(uvicorn.Server):
            def handle_exit(self, sig: int, frame: FrameType | None) -> None:
                if sig == signal.SIGINT and session_.unsaved and not warned["done"]:
                    warned["done"] = True
                    echo(
                        "mtmc: the page holds unsaved edits: save them there, "
                        "or press Ctrl-C again to stop without saving"
                    )
                    sys.stdout.flush()
                    return
                super().handle_exit(sig, frame)

        self._server = Server(config)

    def run(self, sockets: list[socket.socket]) -> None:
        asyncio.run(self._server.serve(sockets=sockets))
