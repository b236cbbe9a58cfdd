"""Variants of a sweep: the base design with the ``[set]`` keys and one combination of the ``[vary]`` values.

A variant's key is the first 16 hex digits of the sha256 of its design (canonical JSON, the mesh file, if
any, by its sha256 instead of its path) and of the stage the sweep runs: the same design run to the same
stage has the same key in any sweep, so a rerun recognises what is already done.
"""

from __future__ import annotations

import copy
import hashlib
import itertools
import json
import math
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ppfab.errors import DesignError

from .spec import MAX_VARIANTS, Axis, SweepSpec


@dataclass(frozen=True)
class Variant:
    """One design of a sweep: ``index`` (0, 1, … in sweep order), ``key`` (hash, see the module docstring),
    the varied ``values`` (dotted key → value) and the whole design document ``doc``."""

    index: int
    key: str
    values: dict[str, Any]
    doc: dict = field(repr=False)


def set_key(doc: dict, dotted: str, value: Any) -> None:
    """Set ``doc[a][b][c] = value`` for ``dotted = "a.b.c"``, creating tables on the way; a path through a
    value that is not a table is refused naming the key."""
    parts = dotted.split(".")
    node = doc
    for i, p in enumerate(parts[:-1]):
        nxt = node.setdefault(p, {})
        if not isinstance(nxt, dict):
            raise DesignError(dotted, f"{'.'.join(parts[:i + 1])} is a value, not a table, in the base design")
        node = nxt
    node[parts[-1]] = value


def load_base(spec: SweepSpec) -> dict:
    """The base design as a TOML document (checked by :func:`fabrication.design.load_design` first), its
    mesh path, if any, made absolute so the variants read it from anywhere."""
    from ..design import load_design

    design = load_design(spec.base)
    doc = copy.deepcopy(design.raw)
    mesh = design.mesh_path()
    if mesh is not None:
        doc["geometry"]["mesh"] = str(mesh.resolve())
    return doc


def _combinations(spec: SweepSpec) -> list[tuple[Any, ...]]:
    axes = spec.axes
    if spec.sample == "zip":
        return list(zip(*(a.values for a in axes)))
    if spec.sample == "grid":
        n = math.prod(len(a.values) for a in axes)
        if n > MAX_VARIANTS:
            raise DesignError("vary", f"the grid has {n} variants, more than {MAX_VARIANTS}; use sample = \"lhs\" "
                                      f"with samples = N (in {spec.source})")
        return list(itertools.product(*(a.values for a in axes)))
    u = latin_hypercube(spec.samples, len(axes), spec.seed)
    return [tuple(_pick(a, float(x)) for a, x in zip(axes, row)) for row in u]


def latin_hypercube(n: int, d: int, seed: int) -> Any:
    """``(n, d)`` points in [0, 1): in every dimension, each of the ``n`` strata ``[k/n, (k+1)/n)`` holds
    exactly one point (a random permutation of the strata, a uniform position inside each); seeded.

    >>> u = latin_hypercube(5, 2, seed=0)
    >>> sorted((u[:, 0] * 5).astype(int).tolist()), sorted((u[:, 1] * 5).astype(int).tolist())
    ([0, 1, 2, 3, 4], [0, 1, 2, 3, 4])
    """
    import numpy as np

    rng = np.random.default_rng(seed)
    strata = np.stack([rng.permutation(n) for _ in range(d)], axis=1)
    return (strata + rng.random((n, d))) / n


def _pick(axis: Axis, u: float) -> Any:
    """The value of ``axis`` at ``u`` in [0, 1) of a Latin-hypercube sample."""
    if axis.low is not None and axis.high is not None:
        if axis.integer:
            lo, hi = math.ceil(axis.low), math.floor(axis.high)
            return int(min(hi, lo + math.floor(u * (hi - lo + 1))))
        return float(f"{axis.low + u * (axis.high - axis.low):.6g}")
    return axis.values[min(int(u * len(axis.values)), len(axis.values) - 1)]


def _file_sha(path: str) -> str:
    try:
        return hashlib.sha256(Path(path).read_bytes()).hexdigest()
    except OSError:
        return f"unreadable:{path}"


def variant_key(doc: dict, stage: str) -> str:
    """The key of a design document run to ``stage`` (see the module docstring).

    >>> variant_key({"geometry": {"method": "x"}}, "geometry") == variant_key({"geometry": {"method": "x"}}, "geometry")
    True
    >>> variant_key({"geometry": {"method": "x"}}, "geometry") == variant_key({"geometry": {"method": "x"}}, "nesting")
    False
    """
    ident = copy.deepcopy(doc)
    mesh = ident.get("geometry", {}).get("mesh") if isinstance(ident.get("geometry"), dict) else None
    if isinstance(mesh, str):
        ident["geometry"]["mesh"] = _file_sha(mesh)
    text = json.dumps({"design": ident, "stage": stage}, sort_keys=True, ensure_ascii=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def make_variants(spec: SweepSpec, base: dict | None = None) -> list[Variant]:
    """Every variant of the sweep, in sweep order, each design once (a repeated combination is dropped)."""
    base = load_base(spec) if base is None else base
    fixed = copy.deepcopy(base)
    for k, v in spec.fixed.items():
        set_key(fixed, k, v)
    out: list[Variant] = []
    seen: set[str] = set()
    for combo in _combinations(spec):
        doc = copy.deepcopy(fixed)
        values = {a.key: v for a, v in zip(spec.axes, combo)}
        for k, v in values.items():
            set_key(doc, k, v)
        key = variant_key(doc, spec.stage)
        if key in seen:
            continue
        seen.add(key)
        out.append(Variant(len(out), key, values, doc))
    return out


def _key(k: str) -> str:
    """A TOML key: bare when it can be, else quoted."""
    return k if re.fullmatch(r"[A-Za-z0-9_-]+", k) else json.dumps(k)


def design_text(doc: dict, comment: str = "") -> str:
    """A design document as TOML text (one table per section, nested tables inline), readable by
    :func:`fabrication.design.load_design`."""
    from ..starter import toml_value

    lines = [f"# {ln}" for ln in comment.splitlines()]
    top = {k: v for k, v in doc.items() if not isinstance(v, dict)}
    lines += [f"{_key(k)} = {toml_value(v)}" for k, v in top.items()]
    for section, table in doc.items():
        if not isinstance(table, dict):
            continue
        lines += ["", f"[{_key(section)}]"]
        lines += [f"{_key(k)} = {toml_value(v)}" for k, v in table.items()]
    text = "\n".join(lines) + "\n"
    tomllib.loads(text)                 # what is written is read back the same
    return text
