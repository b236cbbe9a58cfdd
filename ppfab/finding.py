"""One record for "element X is off by V against the limit L": what every check and gate of ppfab reports.

A :class:`Finding` names the rule broken (``code``: a verify check such as ``torsion``, or a gate's kind such as
``short_segment``), the file it was found in (empty for a finding made before any file exists), the element
(a part, node, edge or panel id), the measured ``value`` and the ``limit`` it breaks where the rule has numbers
(units in the message), and the one-line ``message`` a user reads.  The verify checks
(:class:`fabrication.verify.Verification`), the beam defects (:class:`fabrication.beams.report.BeamReport`) and
the offenders of the build's gates (torsion, creases, panel planarity) are all lists of it.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any


@dataclass(frozen=True)
class Finding:
    """``code``: the rule; ``file``: where it was found (may be empty); ``element``: the id at fault (may be
    empty for a finding about a whole file); ``value`` / ``limit``: measured and allowed, where the rule has
    numbers; ``message``: one line for the user."""

    code: str
    file: str
    element: str
    value: float | None = None
    limit: float | None = None
    message: str = ""

    def __str__(self) -> str:
        head = ": ".join(x for x in (self.file, self.element) if x)
        return f"{head}: {self.message}" if head else self.message

    def as_dict(self) -> dict[str, Any]:
        """The fields as a JSON-ready dict."""
        return asdict(self)
