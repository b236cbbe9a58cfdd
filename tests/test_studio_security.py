"""The studio as a security boundary: its server answers only requests for its own address (``Host``, and
``Origin`` when a browser sends one) that carry the session key in their path, checked with a real WebSocket
client (the ``websockets`` package viser uses) and raw HTTP; Save never overwrites the design read, nor a file the
studio did not write unless the page's replace box is ticked; a design that reads files outside its folder says
so in the page."""

from __future__ import annotations

import asyncio
import http.client
import inspect
import os
import shutil
import socket
from pathlib import Path

import pytest

from conftest import REPO

viser = pytest.importorskip("viser", reason="the studio extra is not installed (pip install '.[studio]')")
pytest.importorskip("tomli_w", reason="the studio extra is not installed")

from websockets.asyncio.client import connect  # noqa: E402
from websockets.exceptions import InvalidStatus  # noqa: E402

from fabrication.studio import guard  # noqa: E402
from fabrication.studio.app import Studio  # noqa: E402
from fabrication.studio.model import StudioModel  # noqa: E402
from ppfab.errors import DesignError  # noqa: E402

SMALL = REPO / "examples" / "smallest_roof.toml"
MESH_DESIGN = REPO / "examples" / "p_optimised_conical1.toml"


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@pytest.fixture(scope="module")
def studio():
    s = Studio(StudioModel.load(SMALL), port=_free_port(), design_path=str(SMALL))
    yield s
    s.stop()


def _ws(port: int, path: str, origin: str | None, host: str = "localhost") -> tuple[int, int | bytes]:
    """Open viser's WebSocket (its subprotocol ``viser-v<version>``) at ``path`` on the loopback port, sending
    ``Host: <host>:<port>``: ``(101, size of the first message)`` when it opened, else the HTTP status the
    handshake was refused with and the refusal's text."""
    async def go() -> tuple[int, int | bytes]:
        sock = socket.create_connection(("127.0.0.1", port), timeout=10)
        try:
            async with connect(f"ws://{host}:{port}{path}", sock=sock, origin=origin,  # type: ignore[arg-type]
                               subprotocols=[f"viser-v{viser.__version__}"],  # type: ignore[list-item]
                               open_timeout=10) as c:
                message = await asyncio.wait_for(c.recv(), 10)
                return 101, len(message)
        except InvalidStatus as exc:
            return exc.response.status_code, bytes(exc.response.body)
    return asyncio.run(go())


def _get(port: int, path: str, host: str, origin: str | None = None) -> tuple[int, bytes, str | None]:
    """``GET path`` on the loopback port with ``Host: host`` (and ``Origin``): ``(status, body, Location)``."""
    c = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
    c.putrequest("GET", path, skip_host=True)
    c.putheader("Host", host)
    if origin:
        c.putheader("Origin", origin)
    c.endheaders()
    r = c.getresponse()
    body = r.read()
    c.close()
    if r.status == 200:
        assert r.getheader("Referrer-Policy") == "no-referrer"          # the key never leaves in a Referer
    return r.status, body, r.getheader("Location")


def test_websocket_needs_the_studios_origin_and_the_session_key(studio):
    port, key = studio.server.get_port(), studio.gate.key
    mine = f"http://localhost:{port}"
    for origin in ("http://evil.example", f"http://evil.example:{port}", f"https://localhost:{port}",
                   f"http://localhost:{port + 1}", "null"):                     # other sites, a sandboxed frame
        status, text = _ws(port, f"/{key}", origin)
        assert status == 403 and b"Origin" in text, origin
    for path in ("/", "/" + "A" * len(key), f"/{key[:-1]}"):                   # the right origin, no key
        status, text = _ws(port, path, mine)
        assert status == 403 and b"session key" in text, path
    status, text = _ws(port, f"/{key}", mine, host="evil.example")            # DNS rebinding: a foreign name
    assert status == 403 and b"Host" in text
    status, first = _ws(port, f"/{key}", mine)                                  # both: the real client's request
    assert status == 101 and first > 100
    status, first = _ws(port, f"/{key}", f"http://127.0.0.1:{port}", host="127.0.0.1")
    assert status == 101 and first > 100


def test_http_needs_the_studios_host_and_the_session_key(studio):
    port, key = studio.server.get_port(), studio.gate.key
    status, body, _ = _get(port, f"/{key}/", f"localhost:{port}")
    assert status == 200 and body.lstrip().lower().startswith(b"<!doctype html>") and len(body) > 100_000
    status, body, _ = _get(port, f"/{key}/", f"evil.example:{port}")          # a foreign Host
    assert status == 403 and b"Host" in body and b"<html" not in body
    status, body, _ = _get(port, f"/{key}/", f"localhost:{port}", origin="http://evil.example")
    assert status == 403 and b"Origin" in body
    for path in ("/", "/index.html", f"/{key[:-1]}/", f"/x/{key}/"):
        status, body, _ = _get(port, path, f"localhost:{port}")
        assert status == 403 and b"session key" in body, path
    status, body, location = _get(port, f"/{key}", f"localhost:{port}")        # the page without its slash
    assert status == 302 and location == f"/{key}/" and body == b""
    assert studio.url == f"http://localhost:{port}/{key}/"


def test_gate_host_rules():
    g = guard.Gate("k", "127.0.0.1")
    assert all(g.host_allowed(h, 8080, 8080) for h in ("localhost", "127.0.0.1", "::1"))
    assert not g.host_allowed("localhost", 8081, 8080)
    assert not g.host_allowed("evil.example", 8080, 8080)
    assert not g.host_allowed("192.168.1.5", 8080, 8080)
    anywhere = guard.Gate("k", "0.0.0.0")                     # exposed: IP literals only, never a DNS name
    assert anywhere.host_allowed("192.168.1.5", 8080, 8080) and anywhere.host_allowed("localhost", 8080, 8080)
    assert not anywhere.host_allowed("evil.example", 8080, 8080)
    one = guard.Gate("k", "192.168.1.5")
    assert one.host_allowed("192.168.1.5", 8080, 8080) and not one.host_allowed("10.0.0.1", 8080, 8080)
    assert guard.new_key() != guard.new_key() and len(guard.new_key()) >= 40


def test_check_strips_the_key_and_logs_each_kind_of_refusal_once(caplog):
    import logging

    from websockets.datastructures import Headers
    from websockets.http11 import Request

    class Connection:
        local_address = ("127.0.0.1", 8080)

        def respond(self, status, text):
            return int(status), text

    exposed = guard.Gate("k3y", "0.0.0.0")                           # the Origin must be the Host's own page
    lan = {"Host": "192.168.1.5:8080", "Origin": "http://192.168.1.5:8080"}
    assert guard.check(exposed, Connection(), Request("/k3y/", Headers(lan)))[0] is None
    refused, _ = guard.check(exposed, Connection(), Request("/k3y/", Headers({**lan, "Origin": "http://10.0.0.9:8080"})))
    assert refused[0] == 403 and "Origin" in refused[1]
    g = guard.Gate("k3y", "127.0.0.1")
    mine = Headers({"Host": "localhost:8080"})
    refused, passed = guard.check(g, Connection(), Request("/k3y/index.html?x=1", mine))
    assert refused is None and passed.path == "/index.html?x=1"
    refused, passed = guard.check(g, Connection(), Request("/k3y/", mine))
    assert refused is None and passed.path == "/"
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="ppfab"):
        for _ in range(5):
            refused, passed = guard.check(g, Connection(), Request(
                "/k3y", Headers({"Host": "localhost:8080", "Origin": "http://evil.example"})))
            assert passed is None and refused[0] == 403 and "Origin 'http://evil.example'" in refused[1]
        guard.check(g, Connection(), Request("/", mine))
    said = [r.getMessage() for r in caplog.records if r.name == "ppfab"]
    assert len(said) == 2 and "Origin" in said[0] and "session key" in said[1]


def test_the_hook_point_in_viser_is_where_the_guard_expects_it(studio):
    """Fails when a viser release changes how it starts its server: the guard must then be rewritten."""
    from viser.infra import _infra

    source = inspect.getsource(_infra.WebsockServer._background_worker)
    assert "websockets.asyncio.server.serve(" in source and "process_request=" in source
    assert isinstance(_infra.websockets, guard._View)
    import websockets.asyncio.server

    assert websockets.asyncio.server.serve is not _infra.websockets.asyncio.server.serve   # the package unchanged
    assert websockets.asyncio.server.ServerConnection is _infra.websockets.asyncio.server.ServerConnection


def test_the_studio_refuses_to_run_when_the_guard_cannot_be_applied(monkeypatch):
    import websockets
    from viser.infra import _infra

    monkeypatch.setattr(_infra, "websockets", websockets)          # as if viser reached serve another way
    monkeypatch.setattr(guard, "_install", lambda: _infra)
    port = _free_port()
    with pytest.raises(guard.GuardUnavailable, match="refuses to run unguarded"):
        Studio(StudioModel.load(SMALL), port=port)
    with pytest.raises(OSError):                                  # and the unguarded server was stopped
        socket.create_connection(("127.0.0.1", port), timeout=2).close()


def test_no_share_link(studio):
    assert studio.server.request_share_url() is None


# -- saving ----------------------------------------------------------------------------------------------
def _design_copy(tmp_path: Path) -> Path:
    p = tmp_path / "roof.toml"
    shutil.copyfile(SMALL, p)
    return p


def test_save_never_overwrites_a_file_it_did_not_write_without_consent(tmp_path):
    m = StudioModel.load(_design_copy(tmp_path))
    other = tmp_path / "notes.toml"
    other.write_bytes(b"# someone else's file\n")
    before = other.read_bytes(), other.stat().st_mtime_ns
    with pytest.raises(DesignError, match="not written by this studio"):
        m.save(other)
    assert (other.read_bytes(), other.stat().st_mtime_ns) == before
    assert m.save(other, replace=True) == other                     # consent given
    assert other.read_bytes() != before[0] and b"[geometry]" in other.read_bytes()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["notes.toml", "roof.toml"]     # no temporary left


def test_save_never_overwrites_the_design_it_read(tmp_path):
    design = _design_copy(tmp_path)
    m = StudioModel.load(design)
    assert m.set_param("geometry.scale", 1100.0), m.error
    before = design.read_bytes()
    link = tmp_path / "link.toml"
    link.symlink_to(design)
    for target in (design, link, tmp_path / "." / "roof.toml"):
        for replace in (False, True):
            with pytest.raises(DesignError, match="never overwritten"):
                m.save(target, replace=replace)
    assert design.read_bytes() == before
    default = StudioModel.load(None)
    assert default.save_rules.target(default.source).kind == "input"    # the bundled default too


def test_save_over_its_own_earlier_save_and_only_while_unchanged(tmp_path):
    m = StudioModel.load(_design_copy(tmp_path))
    out = tmp_path / "edited.toml"
    m.save(out)
    first = out.read_bytes()
    assert m.set_param("geometry.scale", 1100.0), m.error
    m.save(out)                                                      # its own file: no consent needed
    assert out.read_bytes() != first and StudioModel.load(out).geometry["scale"] == 1100.0
    out.write_bytes(out.read_bytes() + b"# edited by hand\n")        # changed since: no longer the studio's
    changed = out.read_bytes()
    with pytest.raises(DesignError, match="not written by this studio"):
        m.save(out)
    assert out.read_bytes() == changed


def test_page_asks_before_replacing_and_consent_is_for_one_file(tmp_path):
    design = _design_copy(tmp_path)
    studio = Studio(StudioModel.load(design), port=_free_port(), design_path=str(design))
    try:
        other = tmp_path / "theirs.toml"
        other.write_bytes(b"# theirs\n")
        studio.save_path.value = str(other)                          # as if typed in the page
        assert studio.replace_box.visible and not studio.replace_box.value
        assert "not written by this studio" in studio.save_note.content
        studio._guard(studio._save)                                  # Save without ticking: refused
        assert other.read_bytes() == b"# theirs\n" and "not written by this studio" in studio.model.error
        studio.replace_box.value = True                              # ticked for theirs.toml …
        third = tmp_path / "third.toml"
        third.write_bytes(b"# third\n")
        studio.save_path.value = str(third)                          # … then another name: consent withdrawn
        assert not studio.replace_box.value
        studio._guard(studio._save)
        assert third.read_bytes() == b"# third\n"
        studio.save_path.value = str(other)
        studio.replace_box.value = True
        studio._guard(studio._save)
        assert b"[geometry]" in other.read_bytes() and not studio.replace_box.visible
        assert "saved by this studio" in studio.save_note.content        # its own file now: no box
        studio.save_path.value = str(design)                         # the design read: no box at all
        assert not studio.replace_box.visible and "never overwritten" in studio.save_note.content
        before = design.read_bytes()
        studio._guard(studio._save)
        assert design.read_bytes() == before
    finally:
        studio.stop()


def test_a_design_reading_files_outside_its_folder_says_so(tmp_path):
    import tomllib

    import tomli_w

    doc = tomllib.loads(MESH_DESIGN.read_text(encoding="utf-8"))
    mesh = (MESH_DESIGN.parent / doc["geometry"]["mesh"]).resolve()
    doc["geometry"]["mesh"] = str(mesh)                              # absolute: outside tmp_path
    design = tmp_path / "elsewhere.toml"
    design.write_text(tomli_w.dumps(doc), encoding="utf-8")
    m = StudioModel.load(design)
    assert m.outside_files() == [mesh]
    assert m.save_rules.target(tmp_path / "x.toml").kind == "new"
    assert any(p.resolve() == mesh for p in m.save_rules.inputs)    # the mesh is an input: never overwritten
    studio = Studio(m, port=_free_port(), design_path=str(design))
    try:
        assert studio.outside_note is not None and str(mesh) in studio.outside_note.content
    finally:
        studio.stop()
    inside = StudioModel.load(MESH_DESIGN)                           # the mesh beside its design: nothing said
    assert inside.outside_files() == [] and os.path.isfile(inside.mesh_file() or "")


def test_ppfab_studio_prints_the_keyed_address_and_answers_only_it(tmp_path):
    """``ppfab studio`` in its own process: the one address it prints carries the key and serves the page;
    the same address without the key, or with another Host, is refused; viser's banner (no key) is not shown."""
    import re
    import subprocess
    import sys

    port = _free_port()
    proc = subprocess.Popen([sys.executable, "-m", "fabrication.cli", "studio", str(SMALL), "--port", str(port),
                             "--no-browser"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path)
    try:
        assert proc.stdout is not None
        line = proc.stdout.readline()
        found = re.fullmatch(r"ppfab: studio at http://localhost:(\d+)/([A-Za-z0-9_-]{43})/ \(Ctrl-C to stop\)\n",
                             line)
        assert found, line
        served, key = int(found.group(1)), found.group(2)
        assert served == port
        status, body, _ = _get(port, f"/{key}/", f"localhost:{port}")
        assert status == 200 and b"<html" in body[:200].lower()
        assert _get(port, "/", f"localhost:{port}")[0] == 403
        assert _get(port, f"/{key}/", f"attacker.example:{port}")[0] == 403
        assert _ws(port, f"/{key}", "http://attacker.example")[0] == 403
        assert _ws(port, f"/{key}", f"http://localhost:{port}")[0] == 101
    finally:
        proc.terminate()
        try:
            proc.wait(20)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(20)
