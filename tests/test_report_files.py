"""The report's Files section links every file the build lists, by a relative link that resolves in the folder."""

from __future__ import annotations

import json
import tomllib
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlparse

import pytest

from conftest import small_design


class _Links(HTMLParser):
    """The ``href`` of every ``<a>`` after the ``<h2>Files</h2>`` heading."""

    def __init__(self) -> None:
        super().__init__()
        self.in_files = False
        self.heading = False
        self.hrefs: list[str] = []

    def handle_starttag(self, tag, attrs):
        if tag == "h2":
            self.heading = True
        elif tag == "a" and self.in_files:
            self.hrefs.append(dict(attrs).get("href", ""))

    def handle_endtag(self, tag):
        if tag == "h2":
            self.heading = False

    def handle_data(self, data):
        if self.heading:
            self.in_files = data.strip() == "Files"


@pytest.fixture(scope="module")
def out(tmp_path_factory):
    from fabrication import build, parse_design

    folder = tmp_path_factory.mktemp("report") / "out"
    build(parse_design(tomllib.loads(small_design(faces_u=3, faces_v=3)))).write(folder)
    return folder


def _listed(manifest: dict) -> set[str]:
    out = set()
    for key, value in manifest["files"].items():
        for path in value if isinstance(value, list) else [value]:
            if key != "report_html":
                out.add(path)
    return out


def test_files_section_links_every_listed_file(out: Path):
    manifest = json.loads((out / "manifest.json").read_text(encoding="utf-8"))
    parser = _Links()
    parser.feed((out / "report.html").read_text(encoding="utf-8"))
    hrefs = parser.hrefs
    assert hrefs, "no links in the Files section"
    for h in hrefs:
        u = urlparse(h)
        assert not u.scheme and not u.netloc and not h.startswith("/"), h          # relative
        assert (out / unquote(u.path)).is_file(), h                                   # resolves in the folder
    linked = {unquote(h) for h in hrefs}
    assert _listed(manifest) <= linked, sorted(_listed(manifest) - linked)[:5]
    assert "manifest.json" in linked and len(_listed(manifest)) > 10
