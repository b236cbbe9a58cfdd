"""Bolt sets of the bolted splices (``bolts.csv``): size, grade, length from the grip, washers, nut, category.

Each bolted splice is clamped by ``bolts`` identical sets through its two cover plates and the beam plate
between them.  The bolt length is

    grip = 2·t_cover + t_beam,   ℓ_min = grip + washers·h_washer + m_nut + projection,

rounded up to the next standard length (:data:`STANDARD_LENGTHS`, ISO 4014 / EN 14399: 5 mm steps up to
70 mm, 10 mm up to 160 mm, 20 mm beyond).  ``projection`` (``[splices] thread_projection``, 5 mm) is the thread
standing out of the nut: EN 1090-2 §8.2.2 asks for at least one full thread pitch (2.5 mm for M20) beyond the
nut; the rest takes up plate over-thickness (EN 10029 allows +1.2 mm on a 10 mm plate).

Category (EN 1993-1-8 §3.4.1): ``A`` bearing type, non-preloaded (the default: a splice of a glass roof's
beams designed for bearing); ``B``/``C`` slip-resistant, preloaded.  Non-preloaded sets are an ISO 4014 bolt,
an ISO 4032 nut and ISO 7089 washers; preloaded sets are EN 14399-3 (HR) with EN 14399-6 washers.  Nut heights
and washer thicknesses are the standards' nominal values below (mm); the project's bolt supplier confirms them.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from ppfab.errors import DesignError

NUT_HEIGHT = {"M12": 10.8, "M16": 14.8, "M20": 18.0, "M24": 21.5, "M27": 23.8, "M30": 25.6}
"""ISO 4032 (and EN 14399-3 HR) nut height ``m``, mm."""
WASHER_ISO7089 = {"M12": 2.5, "M16": 3.0, "M20": 3.0, "M24": 4.0, "M27": 4.0, "M30": 4.0}
"""ISO 7089 plain washer thickness ``h``, mm (non-preloaded sets)."""
WASHER_EN14399_6 = {"M12": 3.0, "M16": 4.0, "M20": 4.0, "M24": 4.0, "M27": 5.0, "M30": 5.0}
"""EN 14399-6 chamfered washer thickness ``h``, mm (preloaded sets)."""
GRADES = ("4.6", "5.6", "8.8", "10.9")
PRELOADED_GRADES = ("8.8", "10.9")
CATEGORIES = ("A", "B", "C")


def standard_length(minimum: float) -> int:
    """The shortest standard bolt length (mm) of at least ``minimum``.

    >>> standard_length(61.0), standard_length(70.0), standard_length(71.0), standard_length(161.0)
    (65, 70, 80, 180)
    """
    length = 20
    while length < minimum - 1e-9:
        length += 5 if length < 70 else (10 if length < 160 else 20)
    return length


@dataclass(frozen=True)
class BoltSpec:
    """A bolt as ``[splices] bolt`` names it: ``"M20 8.8"`` → size ``M20``, grade ``8.8``."""

    size: str
    grade: str

    @classmethod
    def parse(cls, text: str, key: str = "bolt") -> "BoltSpec":
        m = re.fullmatch(r"\s*(M\d+)\s+(\d+\.\d)\s*", text)
        if m is None or m.group(1) not in NUT_HEIGHT or m.group(2) not in GRADES:
            raise DesignError(key, f"{text!r} is not a bolt ppfab can list: write '<size> <grade>' with size one of "
                                   f"{', '.join(NUT_HEIGHT)} and grade one of {', '.join(GRADES)} (e.g. 'M20 8.8')")
        return cls(m.group(1), m.group(2))


@dataclass(frozen=True)
class BoltSet:
    """One row of ``bolts.csv``: the bolt sets of one splice (all alike)."""

    splice: str
    beam: str
    pieces: tuple[str, str]
    size: str
    grade: str
    category: str
    grip_mm: float
    washers: int
    washer_mm: float
    nut_mm: float
    projection_mm: float
    length_mm: int
    quantity: int

    @property
    def min_length_mm(self) -> float:
        """``grip + washers·h + m + projection`` before rounding to a standard length."""
        return self.grip_mm + self.washers * self.washer_mm + self.nut_mm + self.projection_mm

    @property
    def preloaded(self) -> bool:
        return self.category in ("B", "C")

    def row(self) -> dict[str, object]:
        """The ``bolts.csv`` row (columns :data:`fabrication.contract.BOLTS_COLUMNS`)."""
        std = "EN 14399-3 HR" if self.preloaded else "ISO 4014"
        nut = f"{'EN 14399-3' if self.preloaded else 'ISO 4032'} {self.size} m={self.nut_mm:g}"
        kind = "EN 14399-6" if self.preloaded else "ISO 7089"
        washer = f"{self.washers} x {kind} {self.size[1:]} h={self.washer_mm:g}"
        return {"splice": self.splice, "beam": self.beam, "pieces": f"{self.pieces[0]};{self.pieces[1]}",
                "bolt": f"{std} {self.size}x{self.length_mm} {self.grade}", "size": self.size, "grade": self.grade,
                "length_mm": self.length_mm, "grip_mm": round(self.grip_mm, 3), "washers": washer, "nut": nut,
                "projection_mm": round(self.length_mm - self.grip_mm - self.washers * self.washer_mm - self.nut_mm, 3),
                "category": self.category, "preload": "preloaded" if self.preloaded else "non-preloaded",
                "quantity": self.quantity}




def bolt_set(splice: str, beam: str, pieces: tuple[str, str], spec: BoltSpec, category: str, cover_mm: float,
             beam_mm: float, bolts: int, projection: float) -> BoltSet:
    """The bolt sets of one splice: grip ``2·cover + beam``, two washers (under head and nut), one nut."""
    if category not in CATEGORIES:
        raise DesignError("category", f"{category!r} is not a bolt category; use 'A', 'B' or 'C' (EN 1993-1-8 §3.4.1)")
    preloaded = category in ("B", "C")
    if preloaded and spec.grade not in PRELOADED_GRADES:
        raise DesignError("category", f"category {category} needs preloaded bolts of grade 8.8 or 10.9, "
                                      f"[splices] bolt is grade {spec.grade}")
    grip = 2.0 * cover_mm + beam_mm
    washer = (WASHER_EN14399_6 if preloaded else WASHER_ISO7089)[spec.size]
    nut = NUT_HEIGHT[spec.size]
    length = standard_length(grip + 2 * washer + nut + projection)
    return BoltSet(splice, beam, pieces, spec.size, spec.grade, category, grip, 2, washer, nut, projection, length,
                   bolts)


def splice_bolts(splices, params) -> list[BoltSet]:
    """One :class:`BoltSet` per bolted splice (named by its first cover plate), in splice order."""
    spec = BoltSpec.parse(params.bolt)
    return [bolt_set(s.part_ids[0], s.beam_id, tuple(s.pieces), spec, params.category, s.thickness,
                     s.beam_thickness, len(s.holes), params.thread_projection) for s in splices]


def total_bolts(sets: list[BoltSet]) -> int:
    """How many bolt sets the splices take altogether."""
    return int(math.fsum(s.quantity for s in sets))
