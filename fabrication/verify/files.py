"""Every file in the folder is listed in the manifest: a file ppfab did not write and list (``sha256``), such as
an extra cutting sheet copied in after the build, is a finding naming it; ``manifest.json`` itself lists none, and
the marker a build keeps in its folder while it writes (:data:`fabrication.contract.PARTIAL_MARKER`, removed before
the folder is delivered) is not a file of the build."""

from __future__ import annotations

from . import Verification, check


@check("files")
def check_files(v: Verification) -> None:
    from ..contract import PARTIAL_MARKER as MARKER

    m = v.manifest
    listed = set(m.get("sha256", {})) | {"manifest.json", MARKER}
    for path in sorted(p for p in v.folder.rglob("*") if p.is_file() or p.is_symlink()):
        rel = path.relative_to(v.folder).as_posix()
        if rel not in listed:
            v.error(rel, "", "is in the folder but not listed in manifest.json (sha256): not written by this build")
    v.checked.append("files")
