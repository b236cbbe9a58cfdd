"""mesh.obj: readable, with the counts and grid shape the manifest gives."""

from __future__ import annotations

from . import Verification, check


@check("mesh")
def check_mesh(v: Verification) -> None:
    from ppfab.io import read_mesh

    m = v.manifest
    rel = m.get("mesh", {}).get("path", "mesh.obj")
    try:
        mesh = read_mesh(v.folder / rel)
    except Exception as exc:  # noqa: BLE001 - reported as a finding
        v.error(rel, "", f"cannot be read: {exc}")
        return
    v.read.mesh = mesh
    me = m.get("mesh", {})
    if me.get("vertices") not in (None, len(mesh.vertices)):
        v.error(rel, "vertices", f"{len(mesh.vertices)} in the file, {me.get('vertices')} in the manifest")
    if me.get("faces") not in (None, len(mesh.faces)):
        v.error(rel, "faces", f"{len(mesh.faces)} in the file, {me.get('faces')} in the manifest")
    if "rows" in me and "cols" in me:
        cols = me["cols"] if not me.get("closed") else me["cols"] + 1
        if (me["rows"] - 1) * (cols - 1) != len(mesh.faces):
            v.error(rel, "grid", f"rows {me['rows']} x cols {me['cols']} do not match {len(mesh.faces)} faces")
    v.checked.append("mesh")
