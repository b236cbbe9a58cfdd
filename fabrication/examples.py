"""The bundled example designs (``ppfab examples``, ``ppfab build --example NAME``) and the meshes they use.

They are package data (``fabrication/data/examples``: in a source checkout a link to ``examples/``), so an
example builds from an installed package; a mesh an example reads is bundled beside it in ``meshes/``, with
its repository, path and commit in the README there.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass
from pathlib import Path

from ppfab.errors import DesignError
from ppfab.schema import suggest

EXAMPLES_DIR = Path(__file__).resolve().parent / "data" / "examples"
"""The folder of the bundled example designs."""


@dataclass(frozen=True)
class Example:
    """One bundled example: its ``name`` (file stem), ``path``, the construction ``method``, ``mesh`` file or
    ``[surface]`` file it builds, and its ``[design]`` name and description."""

    name: str
    path: Path
    method: str
    mesh: str
    title: str
    description: str
    surface: str = ""

    @property
    def source(self) -> str:
        """What it builds from: ``method 'bisector'`` or ``mesh meshes/DOS__conical1.obj``."""
        if self.method:
            return f"method '{self.method}'"
        return f"surface {self.surface}" if self.surface else f"mesh {self.mesh}"


def _example(path: Path) -> Example:
    doc = tomllib.loads(path.read_text(encoding="utf-8"))
    geo, info = doc.get("geometry", {}), doc.get("design", {})
    return Example(path.stem, path, str(geo.get("method", "")), str(geo.get("mesh", "")),
                   str(info.get("name", path.stem)), str(info.get("description", "")),
                   str(doc.get("surface", {}).get("path", "")))


def examples() -> list[Example]:
    """Every bundled example, sorted by name."""
    return [_example(p) for p in sorted(EXAMPLES_DIR.glob("*.toml"))]


def example_path(name: str) -> Path:
    """The design file of the bundled example ``name`` (a :class:`~ppfab.errors.DesignError` naming the valid
    ones when there is none)."""
    names = [e.name for e in examples()]
    stem = name[:-5] if name.endswith(".toml") else name
    if stem not in names:
        raise DesignError("--example", f"no bundled example {name!r}" + suggest(stem, names)
                                       + f"; `ppfab examples` lists them ({', '.join(names)})")
    return EXAMPLES_DIR / f"{stem}.toml"


def example_for_method(method: str) -> Example | None:
    """The first bundled example (by name) built with construction ``method``, or ``None``."""
    return next((e for e in examples() if e.method == method), None)
