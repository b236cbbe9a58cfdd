"""manifest.json: the keys of the contract, units, the sha256 of every file listed, and values of the right
type.  A malformed value (``files.glass_sheets = 5``, a string where a number belongs) is a finding naming its
key, and is left out of :attr:`FolderData.manifest`, so the other checks read only well-formed values.  The
``fabrication`` parameters are parsed with the design's own parameter records and written back as the build
writes them: what does not come out the same (an alias such as ``beam_depth`` that differs from
``beams.depth``) is named."""

from __future__ import annotations

import hashlib
import json
import types
from pathlib import Path
from typing import Any

from . import Verification, check
from ._cells import is_number

FABRICATION_SECTIONS = ("support", "beams", "panels", "glazing", "splices", "nesting", "beam_nesting", "output")
MESH_INTEGERS = ("vertices", "faces", "rows", "cols")


def _sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _clean_files(v: Verification, files: Any) -> dict[str, Any]:
    """The ``files`` table with every entry that is neither a file name nor a list of them left out (a finding)."""
    if not isinstance(files, dict):
        v.error("manifest.json", "files", f"must be an object of file names, got {type(files).__name__}")
        return {}
    out: dict[str, Any] = {}
    for key, value in files.items():
        if isinstance(value, str) or (isinstance(value, list) and all(isinstance(x, str) for x in value)):
            out[key] = value
        else:
            v.error("manifest.json", f"files.{key}", f"must be a file name or a list of file names, got {value!r}"[:200])
    return out


def _clean_mesh(v: Verification, mesh: Any) -> dict[str, Any]:
    if not isinstance(mesh, dict):
        v.error("manifest.json", "mesh", f"must be an object, got {type(mesh).__name__}")
        return {}
    out = dict(mesh)
    for key in MESH_INTEGERS:
        if key in out and not (isinstance(out[key], int) and not isinstance(out[key], bool) and out[key] >= 0):
            v.error("manifest.json", f"mesh.{key}", f"must be a count, got {out[key]!r}"[:200])
            del out[key]
    if not isinstance(out.get("path", "mesh.obj"), str):
        v.error("manifest.json", "mesh.path", f"must be a file name, got {out['path']!r}"[:200])
        del out["path"]
    return out


FLAT_ALIASES = {"panel_gap": "panels.gap", "planarity_tolerance": "panels.planarity_tolerance",
                "max_crease_deg": "panels.max_crease_deg", "glass_thickness": "panels.thickness",
                "glass_makeup": "panels.makeup", "sheet": "nesting.sheet", "sheet_margin": "nesting.margin",
                "part_spacing": "nesting.spacing"}
"""The flat keys of ``fabrication`` the writer copies from a section
(:func:`fabrication.writers.manifest.fabrication_params`); every ``beam_<key>`` is ``beams.<key>``."""


def _defaults() -> dict[str, Any]:
    """Section → its parameters at their defaults (plain values), and the flat keys as the writer derives them
    from those."""
    from ppfab.schema import as_plain, parse_params

    from ..design import SECTION_DEFAULTS, Design, DesignInfo, _section_types
    from ..writers.manifest import fabrication_params

    types = _section_types()
    records: dict[str, Any] = {name: parse_params(types[name](), dict(SECTION_DEFAULTS.get(name, {})), name)
                               for name in FABRICATION_SECTIONS}
    design = Design(source="", sha256="", base_dir=Path("."), info=DesignInfo(), geometry=None,  # type: ignore[arg-type]
                    sections=records)
    out = fabrication_params(design)
    out.update({name: as_plain(records[name]) for name in FABRICATION_SECTIONS})
    return out


def _hints() -> dict[str, dict[str, Any]]:
    """Section → key → the type hint of its parameter (the dataclass fields of the section's record)."""
    import typing

    from ..design import _section_types

    types = _section_types()
    return {name: typing.get_type_hints(types[name]()) for name in FABRICATION_SECTIONS}


def _accepts(value: Any, hint: Any) -> bool:
    """Whether a JSON value has the type ``hint`` names (unions, ``None``, numbers, flags, text, literals, lists
    and tuples of them; anything else is taken)."""
    import typing

    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if hint is type(None):
        return value is None
    if origin in (typing.Union, types.UnionType):
        return any(_accepts(value, a) for a in args)
    if origin is typing.Literal:
        return value in args
    if hint is bool:
        return isinstance(value, bool)
    if hint in (int, float):
        return is_number(value) and (hint is float or float(value).is_integer())
    if hint is str:
        return isinstance(value, str)
    if origin in (list, tuple) or hint in (list, tuple):
        if not isinstance(value, list):
            return False
        inner = [a for a in args if a is not Ellipsis]
        if origin is tuple and inner and Ellipsis not in args and len(inner) != len(value):
            return False
        return all(any(_accepts(x, a) for a in inner) for x in value) if inner else True
    return True


def _name(hint: Any) -> str:
    """A type hint as a reader says it: ``a number``, ``a number or text``."""
    import typing

    words = {bool: "true or false", int: "a whole number", float: "a number", str: "text", type(None): "null"}
    if typing.get_origin(hint) in (typing.Union, types.UnionType):
        return " or ".join(_name(a) for a in typing.get_args(hint))
    if typing.get_origin(hint) in (list, tuple):
        return "a list"
    return words.get(hint, str(hint))


def _kind(value: Any) -> str:
    """``number``, ``bool``, ``None`` or the JSON type's name, to compare like with like."""
    return "number" if is_number(value) else type(value).__name__


def _equal(a: Any, b: Any) -> bool:
    if is_number(a) and is_number(b):
        return abs(float(a) - float(b)) <= 1e-9 * max(1.0, abs(float(b)))
    return bool(a == b)


def clean_fabrication(v: Verification, fab: Any) -> dict[str, Any]:
    """``fab`` with every value of the wrong type (a finding naming its key) replaced by the parameter's
    default, for the other checks; every flat alias (``panel_gap``, ``beam_depth``, …) that differs from its section's key is named.
    Types are judged by the parameter records' type hints, not by parsing: a build of an older version keeps
    verifying when a newer one tightens a parameter's limits."""
    if not isinstance(fab, dict):
        v.error("manifest.json", "fabrication", f"must be an object, got {type(fab).__name__}")
        return {}
    hints, defaults = _hints(), _defaults()
    aliases = dict(FLAT_ALIASES)
    aliases.update({k: f"beams.{k[5:]}" for k in fab if k.startswith("beam_") and k[5:] in hints["beams"]})
    out: dict[str, Any] = {}
    for key, value in fab.items():
        if key in hints:
            if not isinstance(value, dict):
                v.error("manifest.json", f"fabrication.{key}", f"must be an object, got {value!r}"[:200])
                out[key] = dict(defaults[key])
                continue
            section = {}
            for k, x in value.items():
                if k in hints[key] and not _accepts(x, hints[key][k]):
                    v.error("manifest.json", f"fabrication.{key}.{k}",
                            f"{x!r} is not {_name(hints[key][k])}"[:200])
                    x = defaults[key].get(k)                 # the other checks read the default
                if x is not None:
                    section[k] = x
            out[key] = section
            continue
        name, _, sub = aliases.get(key, "").partition(".")
        if name and sub in hints[name] and not _accepts(value, hints[name][sub]):
            v.error("manifest.json", f"fabrication.{key}", f"{value!r} is not {_name(hints[name][sub])}"[:200])
            value = defaults.get(key)
        if value is not None:
            out[key] = value
    for flat, path in aliases.items():
        name, key = path.split(".")
        part = out.get(name)
        if flat not in out or not isinstance(part, dict) or key not in part:
            continue
        if _kind(part[key]) != _kind(out[flat]):
            continue                            # a value resolved from a word or a default (clearance 'auto' ->
            #                                     1.7 mm, glass thickness None -> the make-up's)
        if not _equal(out[flat], part[key]):
            v.error("manifest.json", f"fabrication.{flat}", f"{out[flat]!r} differs from fabrication.{path} "
                                                            f"{part[key]!r} (the build writes one value twice)")
            out[flat] = part[key]
    return out


@check("manifest")
def check_manifest(v: Verification) -> None:
    path = v.folder / "manifest.json"
    if not path.exists():
        v.error("manifest.json", "", "missing")
        return
    try:
        m = json.loads(path.read_text(encoding="utf-8"))
    except (ValueError, RecursionError) as exc:
        v.error("manifest.json", "", f"not valid JSON ({exc})")
        return
    if not isinstance(m, dict):
        v.error("manifest.json", "", f"must be a JSON object, got {type(m).__name__}")
        return
    for key in ("generator", "units", "design", "mesh", "fabrication", "files", "quality", "sha256"):
        if key not in m:
            v.error("manifest.json", key, "missing key")
    if m.get("units") != "mm":
        v.error("manifest.json", "units", f"must be 'mm', got {m.get('units')!r}")
    clean = dict(m)
    clean["files"] = _clean_files(v, m.get("files", {}))
    clean["mesh"] = _clean_mesh(v, m.get("mesh", {}))
    sha = m.get("sha256", {})
    if not isinstance(sha, dict):
        v.error("manifest.json", "sha256", f"must be an object of file name → digest, got {type(sha).__name__}")
        sha = {}
    for name, digest in sorted(sha.items()):
        f = v.folder / name
        if not isinstance(digest, str):
            v.error("manifest.json", f"sha256.{name}", f"must be a hex digest, got {digest!r}"[:200])
        elif not f.is_file():
            v.error(name, "", "listed in the manifest but missing")
        elif _sha(f) != digest:
            v.error(name, "", "sha256 differs from the manifest (file changed after the build)")
    listed: set[str] = set()
    for value in clean["files"].values():
        listed.update([value] if isinstance(value, str) else value)
    for name in sorted(listed - set(sha)):
        v.error("manifest.json", name, "file listed without a sha256")
    clean["fabrication"] = clean_fabrication(v, m.get("fabrication", {}))
    for key in ("summary", "glazing", "quality", "design"):
        if key in clean and not isinstance(clean[key], dict):
            v.error("manifest.json", key, f"must be an object, got {type(clean[key]).__name__}")
            clean[key] = {}
    v.read.manifest = clean
    v.checked.append("manifest")
