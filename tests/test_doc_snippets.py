"""Every TOML snippet of the README and docs/*.md is a design that builds, or a marked part of one.

Before each fenced ``toml`` block an HTML comment says what it is:

- ``<!-- example: examples/NAME.toml -->`` — the whole design file: the block is that file, word for word,
  and the test builds it (with small nesting budgets; ``slow`` after the path marks a big one);
- ``<!-- part of: examples/NAME.toml -->`` — an excerpt: every key it sets has the same value in that file
  (which the example tests build).

A block without such a comment fails the test, so no snippet is left unbuilt.
"""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

import pytest

from conftest import REPO
from test_examples import small_form

DOCS = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]
BLOCK = re.compile(r"(?:<!--\s*(example|part of):\s*(\S+)(\s+slow)?\s*-->\s*\n)?```toml\n(.*?)```", re.S)


def snippets() -> list[tuple[str, str | None, str | None, bool, str]]:
    """``(where, kind, path, slow, text)`` of every ``toml`` block in the docs, in order."""
    out = []
    for doc in DOCS:
        text = doc.read_text(encoding="utf-8")
        for m in BLOCK.finditer(text):
            line = text[:m.start(4)].count("\n")
            out.append((f"{doc.relative_to(REPO)}:{line}", m.group(1), m.group(2), bool(m.group(3)), m.group(4)))
    return out


SNIPPETS = snippets()
FULL = [pytest.param(s, id=s[0], marks=[pytest.mark.slow] if s[3] else []) for s in SNIPPETS if s[1] == "example"]


def _leaves(doc: dict, prefix: str = "") -> dict[str, object]:
    out: dict[str, object] = {}
    for k, v in doc.items():
        if isinstance(v, dict):
            out.update(_leaves(v, f"{prefix}{k}."))
        else:
            out[f"{prefix}{k}"] = v
    return out


def test_the_docs_have_snippets_and_every_one_is_marked():
    assert any(s[0].startswith("README.md") for s in SNIPPETS)
    unmarked = [s[0] for s in SNIPPETS if s[1] is None]
    assert not unmarked, f"toml blocks without an <!-- example: … --> or <!-- part of: … --> comment: {unmarked}"
    for where, kind, path, _, text in SNIPPETS:
        assert (REPO / str(path)).is_file(), f"{where}: {path} does not exist"
        tomllib.loads(text)                                    # every snippet is valid TOML


@pytest.mark.parametrize("snippet", [s for s in SNIPPETS if s[1] == "part of"], ids=lambda s: s[0])
def test_partial_snippet_is_part_of_its_example(snippet):
    where, _, path, _, text = snippet
    whole = _leaves(tomllib.loads((REPO / str(path)).read_text(encoding="utf-8")))
    for key, value in _leaves(tomllib.loads(text)).items():
        assert key in whole and whole[key] == value, f"{where}: {key} = {value!r} is not in {path}"


@pytest.mark.parametrize("snippet", FULL)
def test_full_snippet_is_its_example_and_builds(snippet, tmp_path):
    from fabrication.cli import main

    where, _, path, _, text = snippet
    example = REPO / str(path)
    assert text == example.read_text(encoding="utf-8"), f"{where} differs from {path}"
    design = tmp_path / Path(str(path)).name
    design.write_text(small_form(text, example.parent), encoding="utf-8")
    out = tmp_path / "out"
    assert main(["build", str(design), "-o", str(out), "--quiet"]) == 0
    assert (out / "report.html").is_file() and (out / "beams.step").is_file()
