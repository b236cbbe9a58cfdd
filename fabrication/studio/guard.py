"""The studio's gate: every HTTP request and every WebSocket handshake the studio's server receives is checked
before viser sees it.

A request is let through only when

* its ``Host`` header names the address the studio serves (``localhost``, ``127.0.0.1`` or ``[::1]`` with the
  bound port when it binds the loopback address; the bound address itself, or any IP literal, otherwise): a page
  of another site that had its DNS name pointed at this machine (DNS rebinding) sends its own name;
* its ``Origin`` header, when there is one, is ``http://`` and that same address (browsers send it on every
  WebSocket handshake and on cross-site requests; they apply no same-origin rule to WebSockets, so this is what
  keeps a page of another site from driving the studio);
* its path starts with the session's key, ``/<key>/`` (:func:`new_key`, ``secrets.token_urlsafe``): the page
  is served at ``http://localhost:PORT/<key>/`` and viser's client opens its WebSocket at the page's own
  address, ``ws://localhost:PORT/<key>``, so a real browser carries the key without any change to the client,
  while a program on this machine that can forge both headers still cannot connect without it.

Anything else gets ``403 Forbidden`` with a one-line reason (a WebSocket is refused during its opening
handshake, before any message is exchanged).  The key is stripped from the path before viser serves the file.

viser (1.1) offers no hook for this: its server calls ``websockets.asyncio.server.serve(…, process_request=…)``
from inside a private function.  :func:`guarded_server` therefore gives viser's infrastructure module its own
view of the ``websockets`` package whose ``serve`` puts :meth:`Gate.check` in front of viser's
``process_request``; the ``websockets`` package itself is not changed.  When a viser release no longer reaches
``serve`` through that name, the gate is never applied and :func:`guarded_server` stops the server and raises
(the studio never runs unguarded); ``tests/test_studio_security.py`` checks the hook point too.
"""

from __future__ import annotations

import hmac
import http
import inspect
import ipaddress
import logging
import secrets
import threading
import urllib.parse
from dataclasses import dataclass, field, replace
from typing import Any, Callable, TypeVar

from ppfab.errors import PpfabError

LOOPBACK_NAMES = ("localhost", "127.0.0.1", "::1")
"""The names of the loopback address a browser on this machine may use."""

T = TypeVar("T")
log = logging.getLogger("ppfab")
_REINSTALL = "the studio is made for viser 1.1: pip install 'viser>=1.1.1,<1.2'"


class GuardUnavailable(PpfabError, RuntimeError):
    """The installed viser no longer starts its server the way :func:`guarded_server` hooks into."""


def new_key() -> str:
    """A fresh session key (32 random bytes, URL-safe)."""
    return secrets.token_urlsafe(32)


def is_loopback(host: str) -> bool:
    """Whether ``host`` (a bind address or a name) is this machine only."""
    h = host.strip("[]").lower()
    if h == "localhost":
        return True
    try:
        return ipaddress.ip_address(h).is_loopback
    except ValueError:
        return False


def _split_host(value: str) -> tuple[str, int | None] | None:
    """``(host, port)`` of a ``Host`` header or an origin's authority (``name``, ``name:port``, ``[v6]:port``);
    ``None`` when it cannot be read."""
    try:
        parts = urllib.parse.urlsplit("//" + value.strip())
        host, port = parts.hostname, parts.port
    except ValueError:
        return None
    if not host or parts.username is not None or parts.path or parts.query or parts.fragment:
        return None
    return host.lower(), port


@dataclass(frozen=True)
class Gate:
    """Who may talk to one studio: ``key`` the session key, ``bind`` the address the server binds (``told``:
    the kinds of refusal logged so far, each once)."""

    key: str
    bind: str
    told: set[str] = field(default_factory=set, compare=False, repr=False)   # refusals logged already

    def host_allowed(self, host: str, port: int | None, served_port: int) -> bool:
        """Whether ``host:port`` (from ``Host`` or ``Origin``) is an address the studio is served at."""
        if port is None:
            port = 80
        if port != served_port:
            return False
        if is_loopback(self.bind):
            return host in LOOPBACK_NAMES or host == self.bind.strip("[]").lower()
        if self.bind in ("0.0.0.0", "::", ""):
            if host == "localhost":
                return True
            try:
                ipaddress.ip_address(host)      # an IP literal: never a name a foreign site controls
            except ValueError:
                return False
            return True
        return host == self.bind.strip("[]").lower()

    def refusal(self, headers: Any, path: str, served_port: int) -> str | None:
        """Why a request with ``headers`` for ``path`` is refused, or ``None`` when it may pass."""
        hosts = headers.get_all("Host")
        if len(hosts) != 1:
            return "one Host header is required"
        parsed = _split_host(hosts[0])
        if parsed is None or not self.host_allowed(*parsed, served_port):
            return f"Host {hosts[0]!r} is not the studio's address"
        origins = headers.get_all("Origin")
        if len(origins) > 1:
            return "more than one Origin header"
        if origins:
            o = urllib.parse.urlsplit(origins[0].strip())
            authority = _split_host(o.netloc) if o.scheme == "http" and not o.path else None
            if authority is None or (authority[0], authority[1] or 80) != (parsed[0], parsed[1] or 80):
                return f"Origin {origins[0]!r} is not the studio's page"
        first = path.partition("?")[0].split("/")
        if len(first) < 2 or first[0] != "" or not hmac.compare_digest(first[1].encode(), self.key.encode()):
            return "this address lacks the studio's session key: open the address the studio printed"
        return None

    def strip(self, path: str) -> str:
        """``path`` without its leading ``/<key>`` (``/`` for the page itself)."""
        rest = path[len(self.key) + 1:]
        return rest if rest.startswith("/") else "/" + rest


def check(gate: Gate, connection: Any, request: Any) -> tuple[Any, Any]:
    """``(refusal, request)``: a ``403`` response for a refused request (``None`` otherwise) and the request
    with the session key stripped from its path (or a redirect from ``/<key>`` to ``/<key>/`` for a page)."""
    port = int(connection.local_address[1])
    reason = gate.refusal(request.headers, request.path, port)
    if reason is not None:
        kind = reason.split()[0]
        if kind not in gate.told:                # once per kind: a stale tab retries every second
            gate.told.add(kind)
            log.warning("studio: refused a request: %s", reason)
        return connection.respond(http.HTTPStatus.FORBIDDEN, f"ppfab studio: {reason}\n"), None
    path, sep, query = request.path.partition("?")
    websocket = request.headers.get("Upgrade", "").lower() == "websocket"
    if path == "/" + gate.key and not websocket:
        response = connection.respond(http.HTTPStatus.FOUND, "")
        response.headers["Location"] = f"/{gate.key}/{sep}{query}"
        return response, None
    return None, replace(request, path=gate.strip(path) + sep + query)


# -- the hook into viser -------------------------------------------------------------------------------------
class _View:
    """A read-only view of a module that replaces some of its attributes (``overrides``)."""

    def __init__(self, target: Any, overrides: dict[str, Any]):
        self._target = target
        self._overrides = overrides

    def __getattr__(self, name: str) -> Any:
        if name in self._overrides:
            return self._overrides[name]
        return getattr(self._target, name)


_lock = threading.Lock()
_pending: list[Gate] = []            # the gate of the server being started (at most one, under _lock)
_applied: list[Gate] = []            # gates the hook has put in front of a server


def _guarded_serve(real_serve: Callable[..., Any]) -> Callable[..., Any]:
    def serve(handler: Any, *args: Any, process_request: Any = None, **kwargs: Any) -> Any:
        if not _pending:                 # another viser server in this process: unchanged
            return real_serve(handler, *args, process_request=process_request, **kwargs)
        gate = _pending[0]

        async def guarded(connection: Any, request: Any) -> Any:
            refused, request = check(gate, connection, request)
            if refused is not None:
                return refused
            response = None if process_request is None else process_request(connection, request)
            if inspect.isawaitable(response):
                response = await response
            if response is not None:
                response.headers["Referrer-Policy"] = "no-referrer"     # the key never leaves in a Referer
            return response

        _applied.append(gate)
        return real_serve(handler, *args, process_request=guarded, **kwargs)
    return serve


def _install() -> Any:
    """Give viser's infrastructure module its view of ``websockets`` (once); returns that module."""
    import importlib

    infra = importlib.import_module("viser.infra._infra")
    current: Any = getattr(infra, "websockets", None)
    if isinstance(current, _View):
        return infra
    try:
        real_serve = current.asyncio.server.serve
    except AttributeError:
        raise GuardUnavailable("the installed viser does not start its server through websockets.asyncio."
                               f"server.serve; the studio cannot guard it ({_REINSTALL})") from None
    server_view = _View(current.asyncio.server, {"serve": _guarded_serve(real_serve)})
    setattr(infra, "websockets", _View(current, {"asyncio": _View(current.asyncio, {"server": server_view})}))
    return infra


def guarded_server(gate: Gate, start: Callable[[], T], stop: Callable[[T], None]) -> T:
    """Start a viser server with ``start()`` with ``gate`` in front of every request; raises
    :class:`GuardUnavailable` (after ``stop``-ping the server) when the gate was not applied."""
    with _lock:
        _install()
        _pending.append(gate)
        try:
            server = start()
        finally:
            _pending.clear()
        applied = any(g is gate for g in _applied)
        _applied[:] = [g for g in _applied if g is not gate]
    if not applied:
        stop(server)
        raise GuardUnavailable("the installed viser started its server without the studio's gate; the studio "
                               f"refuses to run unguarded ({_REINSTALL})")
    return server
