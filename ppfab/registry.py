"""Tables of named entries filled by the modules of one package: the one mechanism behind every registry.

Constructions, support methods, joint types, output writers, verify checks and nesting strategies are each a
:class:`Registry`: the modules of a package add their entries when imported, and :meth:`Registry.load`
imports every module of the package once, so adding an entry is adding one file.  Looking up an unknown
name raises :class:`~ppfab.errors.DesignError` naming the key, the valid names and the nearest one.

Examples
--------
>>> r: Registry[int] = Registry("colour", "ppfab.frame")     # any importable package or module
>>> r.add("red", 1)
1
>>> r.get("red"), r.names()
(1, ('red',))
>>> r.get("rde", "paint.colour")
Traceback (most recent call last):
ppfab.errors.DesignError: paint.colour: unknown colour 'rde' (did you mean 'red'?); valid colours: red
"""

from __future__ import annotations

import importlib
import pkgutil
from typing import Generic, Iterable, TypeVar

from .errors import DesignError
from .schema import suggest

T = TypeVar("T")


class Registry(Generic[T]):
    """Name → entry, filled by the modules of ``package`` (all of them but ``skip`` and ``_private`` ones)."""

    def __init__(self, kind: str, package: str, skip: Iterable[str] = ()):
        self.kind = kind
        self.package = package
        self.skip = frozenset(skip)
        self._entries: dict[str, T] = {}
        self._loaded = False

    def add(self, name: str, entry: T) -> T:
        """Register ``entry`` under ``name`` (twice is a programming error)."""
        if name in self._entries:
            raise RuntimeError(f"{self.kind} {name!r} registered twice")
        self._entries[name] = entry
        return entry

    def load(self) -> dict[str, T]:
        """Import every module of the package once; the table."""
        if not self._loaded:
            package = importlib.import_module(self.package)
            for info in pkgutil.iter_modules(getattr(package, "__path__", [])):
                if info.name not in self.skip and not info.name.startswith("_"):
                    importlib.import_module(f"{self.package}.{info.name}")
            self._loaded = True
        return self._entries

    @property
    def entries(self) -> dict[str, T]:
        """The table as filled so far (without importing anything)."""
        return self._entries

    def names(self) -> tuple[str, ...]:
        """The registered names, sorted."""
        return tuple(sorted(self.load()))

    def get(self, name: str, key: str = "") -> T:
        """The entry ``name``; an unknown name is a :class:`DesignError` under ``key`` listing the valid ones."""
        table = self.load()
        if name not in table:
            self.reject(name, key)
        return table[name]

    def check(self, name: str, key: str = "", also: Iterable[str] = ()) -> None:
        """Raise the :meth:`get` error unless ``name`` is registered or one of ``also`` (e.g. ``"auto"``)."""
        if name not in also and name not in self.load():
            self.reject(name, key, also)

    def reject(self, name: str, key: str, also: Iterable[str] = ()) -> None:
        valid = [*also, *sorted(self.load())]
        raise DesignError(key, f"unknown {self.kind} {name!r}{suggest(name, valid)}; "
                               f"valid {self.kind}s: {', '.join(valid)}")
