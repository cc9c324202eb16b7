"""Gait libraries: the best gait for each of a set of headings and rotations.

A path planner steers by switching between gaits: one that heads along 0°, one along 90°,
one that turns on the spot clockwise, ... ``gait_library`` answers one planar question per
entry (``optimal_planar_gaits`` with the same weights, cost, cap and bound for all) and
keeps gait 0 of each answer (the first in rank order). ``library_gaits`` is the ordered
list the firmware's gait table would carry: entry i is (heading, gait); a host selects a
gait by looking its heading up (the nearest heading, or "rot-cw"/"rot-ccw").
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from ..errors import GaitError
from ..transitions import TransitionTable
from .planar import ROTATIONS, PlanarObjective, optimal_planar_gaits
from .result import Gait, GaitResult


@dataclass(frozen=True)
class Heading:
    """A library entry's question: a heading in degrees, or a rotation ("cw"/"ccw")."""

    name: str
    heading_deg: float | None = None
    rotate: str | None = None


@dataclass(frozen=True)
class LibraryEntry:
    heading: Heading
    result: GaitResult

    @property
    def gait(self) -> Gait | None:
        """The gait the library carries for this heading (gait 0), None when there is none."""
        return self.result.gaits[0] if self.result.gaits else None


def parse_headings(text: str) -> list[Heading]:
    """``"0,45,90,rot-cw,rot-ccw"`` → headings (degrees, any finite number; rot-cw / rot-ccw)."""
    out: list[Heading] = []
    for part in (p.strip() for p in text.split(",")):
        if not part:
            continue
        if part.lower().startswith("rot-") and part[4:].lower() in ROTATIONS:
            out.append(Heading(part.lower(), rotate=part[4:].lower()))
            continue
        try:
            deg = float(part)
        except ValueError:
            raise GaitError(f"--library: {part!r} is neither a heading in degrees nor rot-cw/rot-ccw") from None
        if not math.isfinite(deg):
            raise GaitError(f"--library: heading {part!r} must be a finite number of degrees")
        out.append(Heading(f"{deg:g}", heading_deg=deg))
    if not out:
        raise GaitError("--library: give at least one heading, e.g. 0,90,180,270,rot-cw,rot-ccw")
    names = [h.name for h in out]
    dup = next((n for n in names if names.count(n) > 1), None)
    if dup is not None:
        raise GaitError(f"--library: heading {dup} is given twice")
    return out


def gait_library(
    table: TransitionTable,
    headings: Sequence[Heading] | str,
    kind: str = "total",
    max_transitions: int | None = None,
    *,
    variance_weight: tuple[float, float, float] = (0.0, 0.0, 0.0),
    transition_cost: float = 0.0,
    rotation_cap_deg: float | None = None,
    simple_cycles: bool = False,
    translation_cap: float | None = None,
) -> list[LibraryEntry]:
    """One answer per heading, in the order given. The rotation cap applies to the heading
    entries, the translation cap to the rotation entries."""
    if isinstance(headings, str):
        headings = parse_headings(headings)
    out = []
    for h in headings:
        objective = PlanarObjective(h.heading_deg or 0.0, tuple(variance_weight), transition_cost)  # type: ignore[arg-type]
        if h.rotate is not None:
            res = optimal_planar_gaits(table, objective, kind, max_transitions, simple_cycles=simple_cycles,
                                       rotate=h.rotate, translation_cap=translation_cap)
        else:
            res = optimal_planar_gaits(table, objective, kind, max_transitions, rotation_cap_deg,
                                       simple_cycles=simple_cycles)
        out.append(LibraryEntry(h, res))
    return out


def library_gaits(entries: Sequence[LibraryEntry]) -> list[tuple[Heading, Gait]]:
    """The library as the firmware would carry it: (heading, gait) in order, entries without
    a gait left out."""
    return [(e.heading, e.gait) for e in entries if e.gait is not None]
