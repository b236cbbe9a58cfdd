"""What ``build(design)`` returns: :class:`Build`, the stages' records (:mod:`fabrication.records`) with the
output folder's writing and verifying.

The records themselves are data, one layer down, so that the writers, the parts list and the report type
against them without reaching up into the pipeline.
"""

from __future__ import annotations

import errno
import html
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..records import BuildRecord, NestingSet, NodeTable, PanelSet, Summary

if TYPE_CHECKING:  # pragma: no cover
    from ..progress import Progress

__all__ = ["Build", "BuildRecord", "NestingSet", "NodeTable", "PanelSet", "Summary"]


def _output_error(exc: OSError, tmp: Path, out: Path) -> Exception:
    """An operating-system error while writing into the temporary folder ``tmp``, as one line about ``out``."""
    from ppfab.errors import FabricationError

    name = str(exc.filename or "")
    where = str(out / Path(name).relative_to(tmp)) if name.startswith(str(tmp)) else (name or str(out))
    hint = "; free some space or write elsewhere" if exc.errno == errno.ENOSPC else ""
    return FabricationError(f"cannot write {where}: {exc.strerror or exc}{hint} (nothing was written)")


@dataclass(frozen=True, eq=False)
class Build(BuildRecord):
    """What ``build(design)`` returns: every stage's record (:class:`~fabrication.records.BuildRecord`, the data
    the writers read) and what is done with it — :meth:`write` turns it into the output folder, :meth:`verify`
    re-reads a folder it wrote, :meth:`_repr_html_` shows it in a notebook."""

    _written: list[Path] = field(default_factory=list, repr=False, compare=False)

    def write(self, out: str | Path, force: bool = False, progress: "Progress | None" = None) -> Path:
        """Write the output folder ``out`` atomically (see the README's output contract); returns its absolute
        path.

        Every file goes into a temporary folder beside ``out``; the checks of ``ppfab verify`` then re-read it,
        and it is renamed into place only when all writers succeeded and verify found nothing (otherwise
        :class:`~ppfab.errors.VerificationError` lists the findings and nothing is written).  With ``force``
        an existing folder is replaced, but only when it is a previous ppfab build
        (:func:`~fabrication.pipeline.folder.check_target`).
        """
        from ..writers import write_all
        from .folder import AtomicFolder
        from ..progress import Progress

        prog = progress or Progress(quiet=True)
        folder = AtomicFolder(out, force=force, protect=self.design.input_files())
        with folder as tmp:
            try:
                write_all(self, tmp, prog)
            except OSError as exc:              # disk full, permissions: name the file as the user knows it
                raise _output_error(exc, tmp, Path(out)) from None
            self._self_check(tmp, prog)
        path = folder.target                    # absolute: "a/../b" is b even when a does not exist
        self._written.append(path)
        return path

    def _self_check(self, folder: Path, progress: "Progress") -> None:
        """Run ``ppfab verify``'s checks on the folder just written; raise if any finds a problem."""
        from ppfab.errors import VerificationError

        from ..verify import verify

        progress.start("verify")
        result = verify(folder, progress=lambda done, total, what: progress.advance(
            done, total, f"{done} of {total} checks, {what}"))
        if not result.ok:
            progress.fail()
            shown = "; ".join(str(f) for f in result.findings[:3])
            more = f" (and {len(result.findings) - 3} more)" if len(result.findings) > 3 else ""
            raise VerificationError(f"the files of this build fail ppfab verify, so none were written: "
                                    f"{shown}{more}")
        progress.done(f"{len(result.checked)} checks")

    def verify(self, out: str | Path | None = None) -> Any:
        """Re-read a folder this build wrote (the last one by default) with ``ppfab verify``'s checks."""
        from ..verify import verify

        if out is None:
            if not self._written:
                raise ValueError("nothing written yet: call Build.write(out) first, or pass the folder")
            out = self._written[-1]
        return verify(out)

    def _repr_html_(self) -> str:
        """The summary as an HTML table (for notebooks), with the structure seen from above."""
        s = self.summary
        rows = [("design", self.design.info.name), ("panels / types", f"{s.panels} / {s.panel_types}"),
                ("beams / plates", f"{s.beams} / {s.beam_plates}"), ("nodes", s.nodes),
                ("glass area", f"{s.glass_area_m2:.1f} m²"), ("beam length", f"{s.beam_length_m:.1f} m"),
                ("glass sheets", f"{s.glass_sheets} ({100 * s.glass_utilisation:.1f} %)"),
                ("plate sheets", f"{s.plate_sheets} ({100 * s.plate_utilisation:.1f} %)"),
                ("torsion max", f"{s.torsion_max_deg:.3g}°")]
        body = "".join(f"<tr><th style='text-align:left'>{html.escape(str(k))}</th>"
                       f"<td>{html.escape(str(v))}</td></tr>" for k, v in rows)
        return f"<table>{body}</table>{self._plan_svg()}"

    def _plan_svg(self, width: int = 360) -> str:
        """Panels seen from above as a small inline SVG."""
        import numpy as np

        corners = np.array([p.corners_3d for p in self.panels.panels])
        if corners.size == 0:
            return ""
        xy = corners[..., :2]
        lo, hi = xy.reshape(-1, 2).min(axis=0), xy.reshape(-1, 2).max(axis=0)
        scale = width / max(float(hi[0] - lo[0]), 1e-9)
        height = float(hi[1] - lo[1]) * scale
        polys = "".join('<polygon points="' + " ".join(f"{(x - lo[0]) * scale:.1f},{height - (y - lo[1]) * scale:.1f}"
                                                        for x, y in quad) + '"/>' for quad in xy)
        return (f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height:.0f}" '
                f'style="fill:#cfe3f3;stroke:#1f4e79;stroke-width:0.5">{polys}</svg>')
