"""Parameter records from plain data (TOML tables, dicts), validated at the boundary.

Parameters of constructions and of the fabrication layer are frozen
dataclasses.  :func:`parse_params` turns a mapping into such a record,
checking every key against the fields (unknown keys get the nearest valid
name), every value against the field's type, and ranges declared in the
field metadata (``min``, ``max``, ``exclusive_min``, ``choices``, ``length``).
Every failure is a :class:`~ppfab.errors.DesignError` naming the dotted key path.

Examples
--------
>>> from dataclasses import dataclass, field
>>> @dataclass(frozen=True)
... class P:
...     depth: float = field(default=200.0, metadata={"exclusive_min": 0, "doc": "beam depth, mm"})
>>> parse_params(P, {"depth": 150}, "beams").depth
150.0
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import types
import typing
from typing import TYPE_CHECKING, Any, Mapping, TypeVar

from .errors import DesignError

if TYPE_CHECKING:  # pragma: no cover
    from _typeshed import DataclassInstance

T = TypeVar("T", bound="DataclassInstance")


def param(default: Any = dataclasses.MISSING, *, doc: str = "", **limits: Any) -> Any:
    """A dataclass field with a docstring and range limits (``min``, ``max``, ``exclusive_min``,
    ``exclusive_max``, ``choices``, ``length``, ``min_length``)."""
    meta = {"doc": doc, **limits}
    if isinstance(default, (list, dict)):
        value = default
        return dataclasses.field(default_factory=lambda: type(value)(value), metadata=meta)
    return dataclasses.field(default=default, metadata=meta)


def suggest(name: str, valid: list[str]) -> str:
    """`` (did you mean 'x'?)`` for the nearest valid name, or ``''``."""
    close = difflib.get_close_matches(name, valid, n=1, cutoff=0.6)
    return f" (did you mean '{close[0]}'?)" if close else ""


def _type_name(tp: Any) -> str:
    origin = typing.get_origin(tp)
    if origin in (list, tuple):
        args = typing.get_args(tp)
        return f"list of {_type_name(args[0])}" if args else "list"
    if origin in (typing.Union, types.UnionType):
        return " or ".join(_type_name(a) for a in typing.get_args(tp) if a is not type(None))
    if dataclasses.is_dataclass(tp):
        return "table"
    return {float: "number", int: "integer", str: "string", bool: "true/false", dict: "table"}.get(tp, str(tp))


def _convert(value: Any, tp: Any, path: str) -> Any:
    origin = typing.get_origin(tp)
    if origin in (typing.Union, types.UnionType):
        args = typing.get_args(tp)
        if value is None and type(None) in args:
            return None
        errors = []
        for a in args:
            if a is type(None):
                continue
            try:
                return _convert(value, a, path)
            except DesignError as exc:
                errors.append(exc)
        raise DesignError(path, f"expected {_type_name(tp)}, got {type(value).__name__} {value!r:.60}")
    if origin in (list, tuple):
        if not isinstance(value, (list, tuple)):
            raise DesignError(path, f"expected {_type_name(tp)}, got {type(value).__name__} {value!r:.60}")
        (inner,) = typing.get_args(tp)[:1] or (Any,)
        items = [_convert(v, inner, f"{path}[{k}]") for k, v in enumerate(value)]
        return tuple(items) if origin is tuple else items
    if tp is Any:
        return value
    if tp is bool:
        if not isinstance(value, bool):
            raise DesignError(path, f"expected true/false, got {value!r:.60}")
        return value
    if tp is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise DesignError(path, f"expected a number, got {type(value).__name__} {value!r:.60}")
        if not math.isfinite(value):
            raise DesignError(path, f"expected a finite number, got {value!r}")
        if abs(value) > MAX_MAGNITUDE:
            raise DesignError(path, f"{value:g} is out of range (numbers up to {MAX_MAGNITUDE:g} in size)")
        return float(value)
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            if isinstance(value, float) and value.is_integer() and abs(value) <= MAX_MAGNITUDE:
                return int(value)
            raise DesignError(path, f"expected an integer, got {type(value).__name__} {value!r:.60}")
        if abs(value) > MAX_MAGNITUDE:
            raise DesignError(path, f"{value} is out of range (numbers up to {MAX_MAGNITUDE:g} in size)")
        return value
    if tp is str:
        if not isinstance(value, str):
            raise DesignError(path, f"expected a string, got {type(value).__name__} {value!r:.60}")
        return value
    if tp is dict:
        if not isinstance(value, Mapping):
            raise DesignError(path, f"expected a table, got {type(value).__name__}")
        return dict(value)
    if isinstance(tp, type) and dataclasses.is_dataclass(tp):
        return parse_params(tp, value, path)
    return value


MAX_MAGNITUDE = 1e15
"""Largest magnitude of a number in a design file: beyond it squares and sums of lengths overflow or lose
every digit (a design value of 1e308 would otherwise surface as inf deep inside a construction)."""


def _check_limits(value: Any, meta: Mapping[str, Any], path: str) -> None:
    if value is None:
        return
    if "choices" in meta and value not in meta["choices"]:
        raise DesignError(path, f"must be one of {', '.join(map(repr, meta['choices']))}, got {value!r}"
                                + (suggest(value, list(meta["choices"])) if isinstance(value, str) else ""))
    if isinstance(value, (list, tuple)):
        if "length" in meta and len(value) != meta["length"]:
            raise DesignError(path, f"needs exactly {meta['length']} entries, got {len(value)}")
        if "min_length" in meta and len(value) < meta["min_length"]:
            raise DesignError(path, f"needs at least {meta['min_length']} entries, got {len(value)}")
        items = value
    else:
        items = [value]
    for k, v in enumerate(items):
        sub = path if not isinstance(value, (list, tuple)) else f"{path}[{k}]"
        if isinstance(v, (list, tuple)):
            for kk, vv in enumerate(v):
                _check_limits(vv, {k2: meta[k2] for k2 in meta if k2 in ("min", "max", "exclusive_min", "exclusive_max")}, f"{sub}[{kk}]")
            continue
        if not isinstance(v, (int, float)) or isinstance(v, bool):
            continue
        if "min" in meta and v < meta["min"]:
            raise DesignError(sub, f"must be >= {meta['min']}, got {v}")
        if "max" in meta and v > meta["max"]:
            raise DesignError(sub, f"must be <= {meta['max']}, got {v}")
        if "exclusive_min" in meta and v <= meta["exclusive_min"]:
            raise DesignError(sub, f"must be > {meta['exclusive_min']}, got {v}")
        if "exclusive_max" in meta and v >= meta["exclusive_max"]:
            raise DesignError(sub, f"must be < {meta['exclusive_max']}, got {v}")


def parse_params(cls: type[T], data: Mapping[str, Any] | None, path: str = "") -> T:
    """Build the dataclass ``cls`` from ``data``, validating keys, types and limits.

    A ``__post_init__`` of ``cls`` may raise :class:`DesignError` with a key
    relative to the record; it is re-raised with the full path.
    """
    data = {} if data is None else data
    if not isinstance(data, Mapping):
        raise DesignError(path, f"expected a table, got {type(data).__name__}")
    fields = {f.name: f for f in dataclasses.fields(cls) if f.init}
    hints = typing.get_type_hints(cls)
    kwargs: dict[str, Any] = {}
    for key, value in data.items():
        sub = f"{path}.{key}" if path else str(key)
        if key not in fields:
            raise DesignError(sub, "unknown key" + suggest(str(key), list(fields)) +
                              f"; valid keys: {', '.join(sorted(fields))}")
        converted = _convert(value, hints[key], sub)
        _check_limits(converted, fields[key].metadata, sub)
        kwargs[key] = converted
    for name, f in fields.items():
        if name not in kwargs and f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
            raise DesignError(f"{path}.{name}" if path else name, "missing required key")
    try:
        return cls(**kwargs)
    except DesignError as exc:
        if path and not exc.key.startswith(path):
            raise DesignError(f"{path}.{exc.key}" if exc.key else path, str(exc).split(": ", 1)[-1]) from None
        raise


def describe(cls: type) -> list[tuple[str, str, str, str]]:
    """``(key, type, default, doc)`` of every field, for the README and ``ppfab methods``."""
    hints = typing.get_type_hints(cls)
    out = []
    for f in dataclasses.fields(cls):
        if f.default is not dataclasses.MISSING:
            default = repr(f.default)
        elif f.default_factory is not dataclasses.MISSING:
            default = repr(f.default_factory())
        else:
            default = "(required)"
        out.append((f.name, _type_name(hints[f.name]), default, f.metadata.get("doc", "")))
    return out


def as_plain(record: Any) -> Any:
    """A dataclass record as plain JSON-able data (for the manifest)."""
    if dataclasses.is_dataclass(record):
        return {f.name: as_plain(getattr(record, f.name)) for f in dataclasses.fields(record)}
    if isinstance(record, (list, tuple)):
        return [as_plain(v) for v in record]
    return record
