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
from dataclasses import dataclass, replace
from typing import Any

from ..errors import GaitError, RobotFileError
from ..transitions import TransitionTable
from .optimal import whole_body_bound
from .planar import MAX_PENALTY, ROTATIONS, PlanarObjective, dtheta_of, optimal_planar_gaits, planar_scores
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
    for k, part in enumerate(p.strip() for p in text.split(",") if text.strip()):
        if not part:
            raise GaitError(f"--library: entry {k + 1} of {text!r} is empty; expected a heading in degrees or "
                            "rot-cw/rot-ccw between the commas")
        if part.lower().startswith("rot-") and part[4:].lower() in ROTATIONS:
            out.append(Heading(part.lower(), rotate=part[4:].lower()))
            continue
        try:
            deg = float(part)
        except ValueError:
            raise GaitError(f"--library: {part!r} is neither a heading in degrees nor rot-cw/rot-ccw") from None
        if not math.isfinite(deg) or abs(deg) > MAX_HEADING_DEG:
            raise GaitError(f"--library: heading {part!r} must be a number of degrees within ±{MAX_HEADING_DEG:g}")
        out.append(Heading(f"{deg:g}", heading_deg=deg))
    if not out:
        raise GaitError("--library: give at least one heading, e.g. 0,90,180,270,rot-cw,rot-ccw")
    seen: dict[Any, str] = {}
    for h in out:  # 360 is the heading 0 is: the same entry twice
        key = h.rotate if h.rotate is not None else (h.heading_deg % 360.0) + 0.0  # type: ignore[operator]
        if key in seen:
            same = "" if seen[key] == h.name else f" (the same heading as {seen[key]})"
            raise GaitError(f"--library: heading {h.name} is given twice{same}")
        seen[key] = h.name
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
    if max_transitions is None:  # the bound the firmware build takes, simple cycles or not (past 16 states
        # they were refused: "objective total on 32 states needs an explicit max_transitions")
        max_transitions = whole_body_bound(table.levels, kind)
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


#: The robot file's ``[gaits]`` keys (the library the firmware carries) and what each holds.
#: The longest gait any search considers (``max_transitions``): a paper robot answers in under a
#: second, but the search grows with the bound (a 36-state robot takes about 30 s at 32), and
#: 99999 never finished.
MAX_GAIT_TRANSITIONS = 256
#: A heading is an angle: ten turns either way are plenty (−450 is −90); beyond is a typo
#: (1e308° was answered as a heading, its cosine meaningless). --heading takes the same.
MAX_HEADING_DEG = 3600.0
SPEC_KEYS = {
    "library": "headings in degrees and/or \"rot-cw\", \"rot-ccw\", e.g. [0, 90, 180, 270, \"rot-cw\"]",
    "objective": "\"total\" or \"rate\"",
    "max_transitions": f"a whole number in 2..{MAX_GAIT_TRANSITIONS}",
    "variance_weight": f"a number in [0, {MAX_PENALTY:g}] or [λx, λy, λθ]",
    "transition_cost": f"a number in [0, {MAX_PENALTY:g}] (a cost per transition, as --transition-cost)",
    "rotation_cap_deg": "a number of degrees >= 0",
    "simple_cycles": "true or false",
    "translation_cap": "a number >= 0 (rotation gaits)",
}
#: At most this many library entries (the firmware's gait count is a byte).
MAX_LIBRARY = 64


@dataclass(frozen=True)
class LibrarySpec:
    """Which gait library the firmware carries: the headings and the planar question asked
    for each (``gait_library``'s arguments)."""

    headings: tuple[Heading, ...]
    objective: str = "total"
    max_transitions: int | None = None
    variance_weight: tuple[float, float, float] = (0.0, 0.0, 0.0)
    transition_cost: float = 0.0
    rotation_cap_deg: float | None = None
    simple_cycles: bool = False
    translation_cap: float | None = None

    def entries(self, table: TransitionTable) -> list[LibraryEntry]:
        return gait_library(table, self.headings, self.objective, self.max_transitions,
                            variance_weight=self.variance_weight, transition_cost=self.transition_cost,
                            rotation_cap_deg=self.rotation_cap_deg, simple_cycles=self.simple_cycles,
                            translation_cap=self.translation_cap)

    def describe(self) -> str:
        """One line for generated headers."""
        parts = [f"headings {','.join(h.name for h in self.headings)}", f"objective {self.objective}"]
        if self.max_transitions is not None:
            parts.append(f"max_transitions {self.max_transitions}")
        if any(self.variance_weight):
            parts.append("variance weight " + ",".join(f"{w:g}" for w in self.variance_weight))
        if self.transition_cost:
            parts.append(f"transition cost {self.transition_cost:g}")
        if self.rotation_cap_deg is not None:
            parts.append(f"rotation cap {self.rotation_cap_deg:g} deg")
        if self.simple_cycles:
            parts.append("simple cycles")
        if self.translation_cap is not None:
            parts.append(f"translation cap {self.translation_cap:g}")
        return ", ".join(parts)

    def as_kwargs(self) -> dict[str, Any]:
        """The question's options (everything but the headings), as ``library_spec`` takes them."""
        out = self.as_json()
        del out["headings"]
        return {k: v for k, v in out.items() if v is not None}

    def as_json(self) -> dict[str, Any]:
        return {
            "headings": [h.name for h in self.headings], "objective": self.objective,
            "max_transitions": self.max_transitions, "variance_weight": list(self.variance_weight),
            "transition_cost": self.transition_cost, "rotation_cap_deg": self.rotation_cap_deg,
            "simple_cycles": self.simple_cycles, "translation_cap": self.translation_cap,
        }


def library_spec(headings: str | Sequence[Any], **options: Any) -> LibrarySpec:
    """A LibrarySpec from headings (``"0,90,rot-cw"`` or a list) and ``gait_library``'s
    keyword options; GaitError naming what is wrong."""
    if not isinstance(headings, str):
        if not isinstance(headings, (list, tuple)) or not all(
                isinstance(h, (str, int, float)) and not isinstance(h, bool) for h in headings):
            raise GaitError("library: expected a list of headings in degrees and/or \"rot-cw\", \"rot-ccw\"")
        headings = ",".join(str(h) for h in headings)
    parsed = parse_headings(headings)
    if len(parsed) > MAX_LIBRARY:
        raise GaitError(f"library: {len(parsed)} headings, at most {MAX_LIBRARY}")
    given = vw = options.get("variance_weight", 0.0)
    if isinstance(vw, (int, float)) and not isinstance(vw, bool):
        vw = (float(vw),) * 3
    if not (isinstance(vw, (list, tuple)) and len(vw) == 3 and all(
            isinstance(w, (int, float)) and not isinstance(w, bool) and 0 <= w <= MAX_PENALTY for w in vw)):
        raise GaitError(f"variance_weight: expected {SPEC_KEYS['variance_weight']}, got {given!r}")
    objective = options.get("objective", "total")
    if objective not in ("total", "rate"):
        raise GaitError(f"objective: expected {SPEC_KEYS['objective']}, got {objective!r}")
    mt = options.get("max_transitions")
    if mt is not None and (not isinstance(mt, int) or isinstance(mt, bool) or not 2 <= mt <= MAX_GAIT_TRANSITIONS):
        raise GaitError(f"max_transitions: expected {SPEC_KEYS['max_transitions']}, got {mt!r}")

    def number(key: str, low: float | None, default: Any, high: float = math.inf) -> Any:
        v = options.get(key, default)
        if v is None:
            return None
        if (not isinstance(v, (int, float)) or isinstance(v, bool) or not math.isfinite(v) or (low is not None and v < low)
                or v > high):
            raise GaitError(f"{key}: expected {SPEC_KEYS[key]}, got {v!r}")
        return float(v)

    simple = options.get("simple_cycles", False)
    if not isinstance(simple, bool):
        raise GaitError(f"simple_cycles: expected true or false, got {simple!r}")
    return LibrarySpec(tuple(parsed), objective, mt, tuple(float(w) for w in vw),  # type: ignore[arg-type]
                       number("transition_cost", 0.0, 0.0, MAX_PENALTY), number("rotation_cap_deg", 0.0, None), simple,
                       number("translation_cap", 0.0, None))


def one_weight(table: TransitionTable, weight: float) -> tuple[float, float, float]:
    """One variance weight λ as (λx, λy, λθ): on every variance ``table`` gives (a file learned or
    measured along x has var_dx only: λ on it, not an error about var_dy), and on var_dx always,
    so that a file with no variances at all is told so. ``proleg gait --variance-weight λ`` and a
    robot file's ``[gaits] variance_weight = λ`` alike."""
    have = table.planar.given() if table.planar is not None else {}
    return (weight, weight if "var_dy" in have else 0.0, weight if "var_dtheta_deg" in have else 0.0)


def library_from_robot_file(path: Any, value: Any, table: TransitionTable | None = None) -> LibrarySpec | None:
    """The robot file's ``[gaits]`` table → LibrarySpec (None without ``library``);
    RobotFileError naming file and key. One ``variance_weight`` number weighs the variances
    ``table`` gives, as ``proleg gait --variance-weight λ`` does (a file measured or learned
    along x has ``var_dx`` only; a list names each weight, and one on a variance the file
    lacks is refused)."""
    if not isinstance(value, dict):
        raise RobotFileError(f"{path}: gaits: expected a table [gaits]")
    unknown = sorted(set(value) - set(SPEC_KEYS))
    if unknown:
        raise RobotFileError(f"{path}: gaits: unknown key {unknown[0]!r} (expected one of: {', '.join(sorted(SPEC_KEYS))})")
    if "library" not in value:
        if value:
            raise RobotFileError(f"{path}: gaits: the keys {', '.join(sorted(value))} describe a library; give gaits.library")
        return None
    try:
        spec = library_spec(value["library"], **{k: v for k, v in value.items() if k != "library"})
        weight = value.get("variance_weight")
        if table is not None and isinstance(weight, (int, float)) and not isinstance(weight, bool):
            spec = replace(spec, variance_weight=one_weight(table, spec.variance_weight[0]))
        return spec
    except GaitError as e:
        text = str(e).removeprefix("--library: ")
        key = text.split(":", 1)[0] if text.split(":", 1)[0] in SPEC_KEYS else "library"
        text = text.removeprefix(f"{key}: ") if text.startswith(f"{key}: ") else text
        raise RobotFileError(f"{path}: gaits.{key}: {text}") from None


def missing_statistics(spec: LibrarySpec, table: TransitionTable) -> str | None:
    """Why ``table`` lacks a planar statistic the library's questions need (a heading off the
    x axis needs ``dy``, a rotation or a rotation cap ``dtheta_deg``, a variance weight its
    ``var_*``), or None: checked when the robot file is read, so that ``gait`` and ``build``
    agree and the error names the file."""
    try:
        for h in spec.headings:
            objective = PlanarObjective(h.heading_deg or 0.0, spec.variance_weight, spec.transition_cost)
            planar_scores(table, objective)
            if h.rotate is not None:
                dtheta_of(table, f"gait {h.rotate}")
            elif spec.rotation_cap_deg is not None:
                dtheta_of(table, "gaits.rotation_cap_deg")
    except GaitError as e:
        return str(e)
    return None


def nearest_heading(entries: Sequence[tuple[Heading, Any]], heading_deg: float) -> tuple[Heading, Any, float] | None:
    """The entry (among heading entries, not rotations) whose heading is nearest
    ``heading_deg`` on the circle: (heading, payload, angular distance in degrees), or None
    when the library has no heading entry."""
    best = None
    for h, payload in entries:
        if h.heading_deg is None:
            continue
        d = abs((h.heading_deg - heading_deg + 180.0) % 360.0 - 180.0)
        if best is None or d < best[2] - 1e-9:
            best = (h, payload, d)
    return best
