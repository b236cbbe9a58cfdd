"""manifest.json: the keys of the contract, units, the sha256 of every file listed, and values of the right
type.  A malformed value (``files.glass_sheets = 5``, a string where a number belongs) is a finding naming its
key, and is left out of ``data["manifest"]``, so the later checks read only well-formed values.  The
``fabrication`` parameters are parsed with the design's own parameter records and written back as the build
writes them: what does not come out the same (an alias such as ``beam_depth`` that differs from
``beams.depth``) is named."""

from __future__ import annotations

import hashlib
import json
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


def recompute_fabrication(v: Verification, fab: Any) -> dict[str, Any]:
    """The ``fabrication`` table as the build writes it from its parameter records, the records parsed from
    ``fab`` itself; every section that does not parse is a finding (and left out of what is returned)."""
    from ppfab.errors import DesignError
    from ppfab.schema import as_plain, parse_params

    from ..design import Design, DesignInfo, _section_types
    from ..writers.manifest import fabrication_params

    if not isinstance(fab, dict):
        v.error("manifest.json", "fabrication", f"must be an object, got {type(fab).__name__}")
        return {}
    types = _section_types()
    records: dict[str, Any] = {}
    good = True
    for name in FABRICATION_SECTIONS:
        try:
            records[name] = parse_params(types[name](), fab.get(name, {}), f"fabrication.{name}")
        except DesignError as exc:
            v.error("manifest.json", exc.key or f"fabrication.{name}", str(exc).split(": ", 1)[-1])
            good = False
    if not good:
        return {}
    design = Design(source="", sha256="", base_dir=Path("."), info=DesignInfo(), geometry=None,  # type: ignore[arg-type]
                    sections=records)
    want = fabrication_params(design)
    for name in FABRICATION_SECTIONS:
        want[name] = as_plain(records[name])
    return want


def _compare(v: Verification, got: Any, want: Any, path: str) -> None:
    """Name every key of ``got`` that differs from ``want`` (numbers within 1e-9 relative)."""
    if isinstance(want, dict):
        if not isinstance(got, dict):
            v.error("manifest.json", path, f"must be an object, got {got!r}"[:200])
            return
        for key in want:
            if key in got:                  # a key the build did not write reads as its default
                _compare(v, got[key], want[key], f"{path}.{key}")
        return
    if is_number(want) and is_number(got):
        if abs(float(got) - float(want)) <= 1e-9 * max(1.0, abs(float(want))):
            return
    elif isinstance(want, list) and isinstance(got, list) and len(want) == len(got):
        for k, (a, b) in enumerate(zip(got, want)):
            _compare(v, a, b, f"{path}[{k}]")
        return
    elif got == want:
        return
    v.error("manifest.json", path, f"{got!r} differs from the value its parameter section gives, {want!r}"[:240])


@check("manifest", 10)
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
    fab = m.get("fabrication", {})
    want = recompute_fabrication(v, fab)
    if want:
        _compare(v, fab, want, "fabrication")
        clean["fabrication"] = want
    else:
        clean["fabrication"] = {}
    for key in ("summary", "glazing", "quality", "design"):
        if key in clean and not isinstance(clean[key], dict):
            v.error("manifest.json", key, f"must be an object, got {type(clean[key]).__name__}")
            clean[key] = {}
    v.data["manifest"] = clean
    v.checked.append("manifest")
