"""manifest.json: the keys of the contract, units, and the sha256 of every file listed."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

from . import Verification, check


def _sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


@check("manifest", 10)
def check_manifest(v: Verification) -> None:
    path = v.folder / "manifest.json"
    if not path.exists():
        v.error("manifest.json", "", "missing")
        return
    try:
        m = json.loads(path.read_text(encoding="utf-8"))
    except ValueError as exc:
        v.error("manifest.json", "", f"not valid JSON ({exc})")
        return
    v.data["manifest"] = m
    for key in ("generator", "units", "design", "mesh", "fabrication", "files", "quality", "sha256"):
        if key not in m:
            v.error("manifest.json", key, "missing key")
    if m.get("units") != "mm":
        v.error("manifest.json", "units", f"must be 'mm', got {m.get('units')!r}")
    for name, digest in sorted(m.get("sha256", {}).items()):
        f = v.folder / name
        if not f.exists():
            v.error(name, "", "listed in the manifest but missing")
        elif _sha(f) != digest:
            v.error(name, "", "sha256 differs from the manifest (file changed after the build)")
    listed = set()
    for value in m.get("files", {}).values():
        listed.update([value] if isinstance(value, str) else [x for x in value if isinstance(x, str)])
    for name in sorted(listed - set(m.get("sha256", {}))):
        v.error("manifest.json", name, "file listed without a sha256")
    v.checked.append("manifest")
