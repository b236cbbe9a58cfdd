"""Every DXF of a folder read by ezdxf once per verification (and process), whichever check asks first.

The checks of the cutting sheets, the per-type DXFs, the stock named on every DXF, the cover plates' DXFs and
the bolt holes each need part of what one ``ezdxf.readfile`` and its auditor give
(:func:`fabrication.writers.dxf.read_sheet_dxf`: outlines with their XDATA, texts, circles, dimensions, header
custom properties); at about 15 ms a file (the bundled default has 296 DXFs) reading each file once for every
check that uses it was a sixth of the self-check.  The contract each check holds a file to stays with the
check (:func:`fabrication.writers.dxf.sheet_contract`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:  # pragma: no cover
    from ..writers.dxf import DXFContent
    from . import Verification


def dxf_content(v: "Verification", rel: str) -> "DXFContent":
    """The DXF ``rel`` (relative to the folder) as :func:`~fabrication.writers.dxf.read_sheet_dxf` reads it, read
    once: kept in :attr:`FolderData.dxf` (relative path → content, or the exception reading raised, raised again
    at every call)."""
    from ..writers.dxf import read_sheet_dxf

    memo = v.read.dxf
    if rel not in memo:
        try:
            memo[rel] = read_sheet_dxf(v.folder / rel)
        except Exception as exc:  # noqa: BLE001 - kept and raised again to each caller, who reports it
            memo[rel] = exc
    got = memo[rel]
    if isinstance(got, Exception):
        raise got
    return got
