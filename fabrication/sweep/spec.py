"""The sweep file (TOML): which design to vary, how, what to run and what to collect.

::

    [sweep]
    base = "default"            # design file, relative to this file, or "default" (the bundled example)
    stage = "nesting"           # "geometry", "nesting" or "files" (figures.STAGES)
    sample = "grid"             # "grid" (every combination), "zip" (i-th value of every key), "lhs"
    samples = 24                # "lhs": how many variants (a Latin hypercube of the [vary] keys)
    seed = 0                    # "lhs": seed of the sample
    pareto = ["glass_sheets", "steel_kg"]   # the two figures of the Pareto plot in index.html (default by stage)

    [set]                       # design keys set in every variant
    "nesting.time_budget" = 1.0

    [vary]                      # design keys (dotted paths) and their values
    "geometry.params.faces_u" = [16, 22]
    "panels.gap" = { from = 10.0, to = 20.0, step = 5.0 }     # or count = 3 instead of step
    "beams.depth" = { min = 150.0, max = 250.0 }              # "lhs" only: a continuous interval

    [cost]                      # unit prices (any currency); cost = Σ price × quantity
    glass_sheet = 900.0

Every problem is a :class:`~ppfab.errors.DesignError` naming the key of the sweep file, and the file.
"""

from __future__ import annotations

import math
import os
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ppfab.errors import DesignError

from .figures import COST_KEYS, FIGURES, STAGES

SAMPLES: tuple[str, ...] = ("grid", "zip", "lhs")
"""How the ``[vary]`` keys combine into variants."""

DEFAULT_PARETO: dict[str, tuple[str, str]] = {"geometry": ("panels", "panel_types"),
                                               "nesting": ("glass_sheets", "steel_kg"),
                                               "files": ("glass_sheets", "steel_kg")}
"""The figures of the Pareto plot when ``[sweep] pareto`` is not given."""

MAX_VARIANTS = 100_000
"""A sweep of more variants than this is refused before any is made (a grid grows fast)."""

RANGE_KEYS = frozenset({"from", "to", "step", "count", "min", "max", "integer"})


@dataclass(frozen=True)
class Axis:
    """One varied design key: its dotted ``key`` and either discrete ``values`` or, for ``lhs`` only, a
    continuous interval ``low``–``high`` (``integer``: whole numbers)."""

    key: str
    values: tuple[Any, ...] = ()
    low: float | None = None
    high: float | None = None
    integer: bool = False

    @property
    def continuous(self) -> bool:
        return self.low is not None


@dataclass(frozen=True)
class SweepSpec:
    """A parsed sweep file."""

    source: Path
    base: Path
    stage: str = "nesting"
    sample: str = "grid"
    samples: int = 0
    seed: int = 0
    pareto: tuple[str, str] = ("glass_sheets", "steel_kg")
    fixed: dict[str, Any] = field(default_factory=dict)
    axes: tuple[Axis, ...] = ()
    prices: dict[str, float] = field(default_factory=dict)
    currency: str = ""


def _error(key: str, message: str, where: Path | str) -> DesignError:
    return DesignError(key, f"{message} (in {where})")


def _flatten(table: dict, prefix: str = "") -> dict[str, Any]:
    """Dotted keys of ``[vary]``/``[set]``: ``panels.gap = …`` and ``"panels.gap" = …`` are the same key;
    a table of range keys (``from``/``to``/``min``/…) is a value, not a section."""
    out: dict[str, Any] = {}
    for k, v in table.items():
        key = f"{prefix}.{k}" if prefix else str(k)
        if isinstance(v, dict) and v and not set(v) <= RANGE_KEYS:
            out.update(_flatten(v, key))
        else:
            out[key] = v
    return out


def _number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _range(key: str, r: dict, sample: str, where: Path) -> Axis:
    """An axis from a range table: ``from``/``to`` with ``step`` or ``count``, or ``min``/``max`` (lhs)."""
    k = f"vary.{key}"
    if "min" in r or "max" in r:
        if sample != "lhs":
            raise _error(k, "a { min, max } interval is sampled only with sample = \"lhs\"; give a list or "
                            "{ from, to, step }", where)
        lo, hi = r.get("min"), r.get("max")
        if not (_number(lo) and _number(hi) and float(lo) < float(hi)):  # type: ignore[arg-type]
            raise _error(k, f"min and max must be numbers with min < max, got {lo!r} and {hi!r}", where)
        integer = bool(r.get("integer", isinstance(lo, int) and isinstance(hi, int)))
        return Axis(key, low=float(lo), high=float(hi), integer=integer)  # type: ignore[arg-type]
    ra, rb = r.get("from"), r.get("to")
    if not (_number(ra) and _number(rb)):
        raise _error(k, f"a range needs numbers 'from' and 'to', got {ra!r} and {rb!r}", where)
    a: float = ra   # type: ignore[assignment]
    b: float = rb   # type: ignore[assignment]
    ints = isinstance(a, int) and isinstance(b, int)
    if "count" in r:
        n = r["count"]
        if not isinstance(n, int) or isinstance(n, bool) or n < 1:
            raise _error(k, f"count must be a whole number ≥ 1, got {n!r}", where)
        vals = [a + (b - a) * i / (n - 1) for i in range(n)] if n > 1 else [a]
        ints = ints and all(float(v).is_integer() for v in vals)
    elif "step" in r:
        s = r["step"]
        if not _number(s) or s == 0 or (b - a) / s < 0:
            raise _error(k, f"step must be a number leading from {a!r} to {b!r}, got {s!r}", where)
        n = int(math.floor((b - a) / s + 1e-9)) + 1
        if n > MAX_VARIANTS:
            raise _error(k, f"{n} values; at most {MAX_VARIANTS}", where)
        vals = [a + i * s for i in range(n)]
        ints = ints and isinstance(s, int)
    else:
        raise _error(k, "a range needs 'step' or 'count' besides 'from' and 'to'", where)
    out = [int(round(v)) if ints else round(float(v), 9) for v in vals]
    return Axis(key, tuple(out))


def _axis(key: str, value: Any, sample: str, where: Path) -> Axis:
    if isinstance(value, list):
        if not value:
            raise _error(f"vary.{key}", "an empty list of values; give at least one", where)
        return Axis(key, tuple(value))
    if isinstance(value, dict):
        unknown = set(value) - RANGE_KEYS
        if unknown:
            raise _error(f"vary.{key}", f"unknown range key(s) {sorted(unknown)}; use from/to/step/count or "
                                        "min/max", where)
        return _range(key, value, sample, where)
    raise _error(f"vary.{key}", f"give a list of values or a range table, got {value!r}", where)


def _choice(doc: dict, key: str, allowed: tuple[str, ...], default: str, where: Path) -> str:
    v = doc.get(key, default)
    if v not in allowed:
        raise _error(f"sweep.{key}", f"must be one of {', '.join(repr(a) for a in allowed)}, got {v!r}", where)
    return str(v)


def parse_sweep(doc: dict, source: str | os.PathLike = "<dict>", base_dir: Path | None = None) -> SweepSpec:
    """Validate a sweep document (parsed TOML) into a :class:`SweepSpec`; ``base_dir`` is where a relative
    ``base`` path starts (the sweep file's folder)."""
    from ..design import DEFAULT_DESIGN

    where = Path(source)
    known = {"sweep", "set", "vary", "cost"}
    for name, value in doc.items():
        if name not in known:
            raise _error(name, f"unknown section; a sweep file has {', '.join(sorted(known))}", where)
        if not isinstance(value, dict):
            raise _error(name, f"must be a table ([{name}])", where)
    head = doc.get("sweep", {})
    unknown = set(head) - {"base", "stage", "sample", "samples", "seed", "pareto"}
    if unknown:
        raise _error(f"sweep.{sorted(unknown)[0]}", "unknown key; [sweep] has base, stage, sample, samples, "
                                                    "seed, pareto", where)
    base_name = head.get("base", "default")
    if not isinstance(base_name, str) or not base_name:
        raise _error("sweep.base", "give the design file to vary (a path) or \"default\"", where)
    base = DEFAULT_DESIGN if base_name == "default" else (base_dir or Path.cwd()) / base_name
    stage = _choice(head, "stage", STAGES, "nesting", where)
    sample = _choice(head, "sample", SAMPLES, "grid", where)
    samples, seed = head.get("samples", 0), head.get("seed", 0)
    for name, v in (("samples", samples), ("seed", seed)):
        if not isinstance(v, int) or isinstance(v, bool) or v < 0:
            raise _error(f"sweep.{name}", f"must be a whole number ≥ 0, got {v!r}", where)
    if sample == "lhs" and not 1 <= samples <= MAX_VARIANTS:
        raise _error("sweep.samples", f"sample = \"lhs\" needs samples = N (1 to {MAX_VARIANTS})", where)
    pareto = head.get("pareto", list(DEFAULT_PARETO[stage]))
    if not (isinstance(pareto, list) and len(pareto) == 2 and all(p in FIGURES for p in pareto)):
        raise _error("sweep.pareto", f"give two figures of {', '.join(FIGURES)}; got {pareto!r}", where)
    for p in pareto:
        if STAGES.index(FIGURES[p].stage) > STAGES.index(stage):
            raise _error("sweep.pareto", f"{p} is measured from stage {FIGURES[p].stage!r} on, and this sweep "
                                         f"runs stage {stage!r}; choose another figure or a later stage", where)
    vary = _flatten(doc.get("vary", {}))
    if not vary:
        raise _error("vary", "nothing to vary: give at least one design key with its values in [vary]", where)
    axes = tuple(_axis(k, v, sample, where) for k, v in vary.items())
    fixed = _flatten(doc.get("set", {}))
    for k in fixed:
        if k in vary:
            raise _error(f"set.{k}", "is also in [vary]; give it in one of the two", where)
    if sample == "zip":
        lengths = {len(a.values) for a in axes}
        if len(lengths) > 1:
            raise _error("vary", f"sample = \"zip\" takes the i-th value of every key: the lists must be "
                                 f"equally long, got lengths {sorted(lengths)}", where)
    prices = dict(doc.get("cost", {}))
    currency = prices.pop("currency", "")
    for k, v in prices.items():
        if k not in COST_KEYS:
            raise _error(f"cost.{k}", f"unknown price; [cost] has {', '.join(COST_KEYS)} (and currency)", where)
        if not _number(v):
            raise _error(f"cost.{k}", f"must be a number (price per unit), got {v!r}", where)
    if not isinstance(currency, str):
        raise _error("cost.currency", f"must be a text such as \"EUR\", got {currency!r}", where)
    return SweepSpec(source=where, base=base, stage=stage, sample=sample, samples=samples, seed=seed,
                     pareto=(str(pareto[0]), str(pareto[1])), fixed=fixed, axes=axes,
                     prices={k: float(v) for k, v in prices.items()}, currency=currency)


def load_sweep(path: str | os.PathLike) -> SweepSpec:
    """Read and validate a sweep file."""
    p = Path(path)
    if not p.is_file():
        raise DesignError("", f"{p}: no such sweep file; give the path of a sweep file (.toml)")
    if p.stat().st_size > 1 << 20:
        raise DesignError("", f"{p}: larger than 1 MiB, not a sweep file")
    try:
        doc = tomllib.loads(p.read_bytes().decode("utf-8-sig"))
    except UnicodeDecodeError:
        raise DesignError("", f"{p}: sweep file is not UTF-8 text") from None
    except tomllib.TOMLDecodeError as exc:
        raise DesignError("", f"{p}: malformed TOML: {exc}") from None
    return parse_sweep(doc, p, p.resolve().parent)
