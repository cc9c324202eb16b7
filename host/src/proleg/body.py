"""Body shape from coil contractions: curvature → centre line → contact angles, gaps, loads.

The body is a slender beam of arc length L lying on its contacts (limbs, evenly spaced along
it, the first at s = 0, the last at s = L). Each SMA coil runs in a channel at height d above
the neutral axis over a span of the body; contracting by a working strain ε it bends that
span with curvature κ = ε / d (a contracting fibre at offset d, Euler–Bernoulli; the body's
elastic resistance is folded into the working strain ε, the strain the coil actually achieves
against the body). Overlapping spans add. The centre line is integrated segment by segment
(exact chords for constant-curvature segments).

Between two neighbouring contacts the body is an arch standing on the ground: the ground is
the chord through the two contacts, the contact angle ψ at each end is the angle between the
body tangent and that chord (ψ_p + ψ_q = total turning of the section), the section's ground
length (the gap between the contacts) is the chord length, and its weight splits between
the two contacts by the lever rule about its centre of mass (statics of a two-support body).

For one or two coils the shape quantities are tabulated on a grid of contractions when the
plant is built and interpolated bilinearly while it runs (the hot path stays small). For
more coils each section between neighbouring contacts is tabulated on its own: its contact
angles, chord and centre of mass, measured from its own ends, depend only on the coils that
bend it (at most two on the usual layout: its two contacts' coils), and the body is their
sum; a section that three or more coils bend leaves the whole body computed directly.

How long the body is, when the robot file does not say (``[plant] length_mm``): the paper's
80 mm body for two contacts, and 40 mm between neighbouring contacts for more
(``default_length_mm``): a body with more contacts is longer, not more finely divided. A
coil bends the section on either side of its contact, so the angle it can give its contact
is about κ_max × section / 2 (the tangent–chord angle of an arc); squeezing four contacts
into 80 mm would leave each contact ≈ 22° of reach, less than most mechanisms need.
``own_reach_deg`` gives each contact's reach with its own coil alone, at full stroke: what
the robot-file check compares with the limb's critical angles (``proleg.robot``).
"""

from __future__ import annotations

import math
from collections.abc import Collection, Sequence
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np

N_SEGMENTS = 64
GRID = 41
PAPER_LENGTH_MM = 80.0     # the paper's two-contact body (R1-class, 80 × 8 × 4 mm)
SECTION_MM = 40.0          # between neighbouring contacts of a longer body: about one coil (30 mm) and its anchors
DEFAULT_OVERLAP_MM = 8.0   # [plant] overlap_mm's default
DEFAULT_WORKING_STRAIN = 0.06  # [plant] working_strain's default: an estimate (docs/control.md, "Is the open
                               # loop's full stroke physically plausible?")


@dataclass(frozen=True)
class BodyGeometry:
    length_mm: float = 80.0
    coil_offset_mm: float = 2.0       # channel height above the neutral axis
    working_strain: float = DEFAULT_WORKING_STRAIN  # coil contraction achieved against the body at α = 1
    spans: tuple[tuple[float, float], ...] = ((0.0, 48.0), (32.0, 80.0))  # per coil, mm
    contacts_mm: tuple[float, ...] = (0.0, 80.0)

    @property
    def kappa_max_per_mm(self) -> float:
        return self.working_strain / self.coil_offset_mm


def default_spans(n_contacts: int, homes: list[int], length_mm: float, overlap_mm: list[float]) -> tuple:
    """Each coil spans the half-section on either side of its home contact plus ``overlap``."""
    pos = np.linspace(0.0, length_mm, n_contacts)
    half = length_mm / (n_contacts - 1) / 2.0
    out = []
    for h, ov in zip(homes, overlap_mm):
        a = max(0.0, pos[h] - half - ov) if h > 0 else 0.0
        b = min(length_mm, pos[h] + half + ov) if h < n_contacts - 1 else length_mm
        out.append((float(a), float(b)))
    return tuple(out)


def default_length_mm(n_contacts: int) -> float:
    """The body length a robot file without ``[plant] length_mm`` gets (see the module text)."""
    return max(PAPER_LENGTH_MM, SECTION_MM * (n_contacts - 1))


def coil_homes(limb_actuators: list[int], n_actuators: int) -> list[int]:
    """The contact each coil bends: the first limb (in the robot file's order) that names it,
    else contact 0. Not "the limb of the coil's own index when it names the coil": a shared
    coil then sat at another limb when the [[actuator]] tables were listed in another order,
    and the body, its reach warnings, measured matrix and fallbacks changed with it."""
    return [next((i for i, a in enumerate(limb_actuators) if a == j), 0) for j in range(n_actuators)]


def body_geometry(limb_actuators: list[int], n_actuators: int, length_mm: float,
                  overlap_mm: list[float], coil_offset_mm: float = 2.0,
                  working_strain: float = DEFAULT_WORKING_STRAIN) -> BodyGeometry:
    """Contacts evenly along ``length_mm`` in limb order, each coil over its home contact's sections."""
    n = len(limb_actuators)
    contacts = tuple(float(x) for x in np.linspace(0.0, length_mm, n))
    spans = default_spans(n, coil_homes(limb_actuators, n_actuators), length_mm, overlap_mm)
    return BodyGeometry(length_mm, coil_offset_mm, working_strain, spans, contacts)


#: The most a coil's section may bend at full stroke in this model: past a half turn the body
#: would curl over itself and off its contacts, which the quasi-static crawl (contacts on the
#: ground, ψ in (−180°, 180°]) does not describe.
MAX_BEND_DEG = 180.0


def curl_problem(geo: BodyGeometry, names: Sequence[str] = ()) -> str:
    """Why the model cannot describe this body ("" when it can): a coil whose section bends
    past ``MAX_BEND_DEG`` at full stroke (curvature × its span; a long body with few coils).
    The coil is named by its ``[[actuator]]`` name where ``names`` gives them (messages name
    actuators as the robot file does: "coil 2" of a file whose coils are c0..c4 was c1)."""
    for j, (a, b) in enumerate(geo.spans):
        bend = math.degrees(geo.kappa_max_per_mm * (b - a))
        if bend > MAX_BEND_DEG:
            coil = f"coil {names[j]!r}" if j < len(names) else f"coil {j + 1}"
            return (f"{coil} spans {b - a:.0f} mm of the {geo.length_mm:g} mm body and bends it by "
                    f"{bend:.0f}° at full stroke, past the {MAX_BEND_DEG:.0f}° the physical plant models "
                    f"(the body would curl over itself): give a shorter body ([plant] length_mm) or a stiffer one "
                    f"(a smaller working_strain than {geo.working_strain:g}), or the robot more limbs and coils "
                    f"along it")
    return ""


def curl_key(given: Collection[str]) -> str:
    """The ``[plant]`` key a ``curl_problem`` line is filed under: ``working_strain`` where the
    file gives it and not ``length_mm`` (a body too soft, not too long: R1 with working_strain
    0.2 was told of plant.length_mm, a key it does not have), else ``length_mm``."""
    return "working_strain" if "working_strain" in given and "length_mm" not in given else "length_mm"


def own_reach_deg(geo: BodyGeometry, limb_actuators: list[int]) -> list[float]:
    """Per contact: ψ with its own coil at full stroke and every other coil cold."""
    shape = Shape(geo, tabulate=False)
    c = np.zeros((len(limb_actuators), shape.n_coils))
    for i, j in enumerate(limb_actuators):
        c[i, j] = 1.0
    psi = shape.compute(c)[0]
    return [float(psi[i, i]) for i in range(len(limb_actuators))]


def coil_reach_deg(geo: BodyGeometry, actuator: int) -> list[float]:
    """Per contact: ψ with coil ``actuator`` at full stroke and every other coil cold (how far
    that coil alone lifts each limb: ``limbloss`` remaps a lost coil's limb only onto one that
    lifts it)."""
    shape = Shape(geo, tabulate=False)
    c = np.zeros((1, shape.n_coils))
    c[0, actuator] = 1.0
    return [float(p) for p in shape.compute(c)[0][0]]


def _wrap_deg(a: np.ndarray) -> np.ndarray:
    """Angles in degrees into (−180, 180]."""
    return 180.0 - np.mod(180.0 - a, 360.0)


class Shape:
    """Shape quantities as functions of the coils' contractions c ∈ [0, 1]^n.

    ``evaluate(c)`` → (ψ per contact in degrees, gap per section in mm, load fraction per
    contact (sums to 1), centre-of-mass position along the ground measured from contact 0 in mm).
    """

    def __init__(self, geo: BodyGeometry, tabulate: bool = True):
        self.geo = geo
        n = N_SEGMENTS
        self.ds = geo.length_mm / n
        mids = (np.arange(n) + 0.5) * self.ds
        self._w = np.array([[(a <= m < b) for m in mids] for a, b in geo.spans], dtype=float)
        self._w *= geo.kappa_max_per_mm
        self._cnode = [int(round(s / self.ds)) for s in geo.contacts_mm]
        self.n_contacts = len(self._cnode)
        self.n_coils = len(geo.spans)
        total = float(geo.length_mm)
        self._frac = [(q - p) * self.ds / total for p, q in zip(self._cnode, self._cnode[1:])]
        self._all_coils = list(range(self.n_coils))
        self._tlist: list | None = None
        self._sec_tables: list[tuple[list[int], list]] | None = None
        if tabulate:
            self._tlist, self._sec_tables = _tables(geo)
        # per section, (its coils' contractions, its values) at its last evaluation
        self._sec_last: list[tuple[tuple[float, ...], list[float]] | None] = [None] * len(self._sec_tables or ())

    # -- exact computation (vectorised over a batch of contraction vectors) ------------------
    def _sections(self, c: np.ndarray) -> list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
        """Per section between neighbouring contacts: (ψ at its first contact, ψ at its second,
        its chord (the gap), its centre of mass along the chord from its first contact). Each is
        the section's own shape, whatever the body does before it: the same under a rigid
        rotation, so it depends only on the coils that bend the section."""
        c = np.atleast_2d(np.asarray(c, dtype=float))              # (B, n_coils)
        kappa = c @ self._w                                          # (B, n_seg)
        dphi = kappa * self.ds
        phi_nodes = -np.concatenate([np.zeros((len(c), 1)), np.cumsum(dphi, axis=1)], axis=1)
        phi_mid = (phi_nodes[:, :-1] + phi_nodes[:, 1:]) / 2.0
        half = dphi / 2.0
        sinc = np.where(np.abs(half) > 1e-9, np.sin(half) / np.where(half == 0, 1, half), 1.0)
        chord = self.ds * sinc
        x = np.concatenate([np.zeros((len(c), 1)), np.cumsum(chord * np.cos(phi_mid), axis=1)], axis=1)
        y = np.concatenate([np.zeros((len(c), 1)), np.cumsum(chord * np.sin(phi_mid), axis=1)], axis=1)
        xm = (x[:, :-1] + x[:, 1:]) / 2.0
        ym = (y[:, :-1] + y[:, 1:]) / 2.0
        out = []
        for k in range(self.n_contacts - 1):
            p, q = self._cnode[k], self._cnode[k + 1]
            vx, vy = x[:, q] - x[:, p], y[:, q] - y[:, p]
            g = np.hypot(vx, vy)
            chi = np.arctan2(vy, vx)
            # Both differences into (−180°, 180°]: the tangent's angle accumulates along the
            # body, the chord's comes from atan2, and once the body has turned more than 180°
            # in all (a long body with several coils drawn) they differ by a whole turn; an
            # interior contact averages two of them, so an unwrapped turn read as ±180° there.
            psi_p = _wrap_deg(np.degrees(phi_nodes[:, p] - chi))
            psi_q = _wrap_deg(np.degrees(chi - phi_nodes[:, q]))
            ux, uy = vx / g, vy / g
            u = ((xm[:, p:q] - x[:, p:p + 1]) * ux[:, None] + (ym[:, p:q] - y[:, p:p + 1]) * uy[:, None]).mean(axis=1)
            out.append((psi_p, psi_q, g, u))
        return out

    def _assemble(self, sections) -> tuple[list, list, list, Any]:
        """The body from its sections' (ψ at the first contact, ψ at the second, chord, centre of
        mass along it): ψ per contact (an inner one the mean of its two sections'), gap per
        section, each contact's share of the weight by the lever rule, and the centre of mass
        from contact 0. Each quantity a float, or an array over a batch: ``compute`` and the
        section tables' ``evaluate`` make the same sum."""
        nc = self.n_contacts
        psi = [0.0] * nc
        load = [0.0] * nc
        gaps = []
        com = start = 0.0
        for k, (psi_p, psi_q, g, u) in enumerate(sections):
            psi[k] += psi_p if k == 0 else psi_p / 2.0
            psi[k + 1] += psi_q if k == nc - 2 else psi_q / 2.0
            frac = self._frac[k]                                     # section's share of the mass
            load[k] += frac * (1.0 - u / g)
            load[k + 1] += frac * (u / g)
            com += frac * (start + u)
            gaps.append(g)
            start = start + g
        return psi, gaps, load, com

    def compute(self, c: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        c = np.atleast_2d(np.asarray(c, dtype=float))
        psi, gaps, load, com = self._assemble(self._sections(c))
        b = len(c)
        return _columns(psi, b), _columns(gaps, b), _columns(load, b), np.broadcast_to(com, (b,)).astype(float)

    # -- tabulated ------------------------------------------------------------------------------
    def _body_table(self) -> list:
        """One or two coils: the whole body's quantities on a grid of contractions."""
        psi, gaps, load, com = self.compute(_grid(self.n_coils))
        flat = np.concatenate([psi, gaps, load, com[:, None]], axis=1)
        return flat.reshape((GRID,) * self.n_coils + (flat.shape[1],)).tolist()

    def _section_tables(self) -> list[tuple[list[int], list]] | None:
        """More than two coils: a table per section over the (at most two) coils that bend it,
        its four quantities (``_sections``) interpolated as the two-coil body's are; None when
        a section is bent by three or more coils (the whole body is then computed directly)."""
        tables = []
        for k in range(self.n_contacts - 1):
            p, q = self._cnode[k], self._cnode[k + 1]
            coils = [j for j in range(self.n_coils) if self._w[j, p:q].any()]
            if len(coils) > 2:
                return None
            mesh = _grid(len(coils))
            c = np.zeros((len(mesh), self.n_coils))
            c[:, coils] = mesh
            flat = np.stack(self._sections(c)[k], axis=1)            # (GRID^m, 4)
            tables.append((coils, flat.reshape((GRID,) * len(coils) + (4,)).tolist()))
        return tables

    def _evaluate_sections(self, c: list[float]) -> list[float]:
        """``evaluate`` from the section tables. A section whose coils' contractions are those
        of its last evaluation takes its last values (the interpolation is a function of them
        alone): while one coil moves, the sections it does not bend are not looked up again."""
        last = self._sec_last
        sections = []
        for k, (coils, table) in enumerate(self._sec_tables):
            key = tuple([c[j] for j in coils])
            got = last[k]
            if got is None or got[0] != key:
                got = last[k] = (key, _interpolate(coils, table, c))
            sections.append(got[1])
        psi, gaps, load, com = self._assemble(sections)
        return [*psi, *gaps, *load, com]

    def evaluate(self, c: list[float]) -> list[float]:
        """Flat list: ψ per contact, gap per section, load per contact, centre of mass."""
        if self._tlist is not None:
            return _interpolate(self._all_coils, self._tlist, c)
        if self._sec_tables is not None:
            return self._evaluate_sections(c)
        sections = [tuple(float(v[0]) for v in section) for section in self._sections(np.array(c))]
        psi, gaps, load, com = self._assemble(sections)
        return [*psi, *gaps, *load, com]


def _columns(values: list, batch: int) -> np.ndarray:
    """``_assemble``'s quantities (arrays over the batch; 0.0 where no section reached one) as
    the columns of a (batch, n) array."""
    if not values:
        return np.zeros((batch, 0))
    return np.stack([np.broadcast_to(np.asarray(v, dtype=float), (batch,)) for v in values], axis=1)


def _grid(m: int) -> np.ndarray:
    """Every point of the GRID^m grid of m contractions in [0, 1], one row each (m = 0: one row)."""
    if m == 0:
        return np.zeros((1, 0))
    axes = [np.linspace(0.0, 1.0, GRID)] * m
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, m)


def _interpolate(coils: list[int], table: list, c: list[float]) -> list[float]:
    """Linear (one coil) or bilinear (two) interpolation in ``table`` (nested lists, GRID per
    coil, then the quantities) at the contractions of ``coils`` in ``c``, each clamped to [0, 1]."""
    if not coils:
        return table
    g1 = GRID - 1
    u = min(max(c[coils[0]], 0.0), 1.0) * g1
    i = min(int(u), g1 - 1)
    fu = u - i
    if len(coils) == 1:
        return [x + (y - x) * fu for x, y in zip(table[i], table[i + 1])]
    v = min(max(c[coils[1]], 0.0), 1.0) * g1
    j = min(int(v), g1 - 1)
    fv = v - j
    a, b, cc, d = table[i][j], table[i + 1][j], table[i][j + 1], table[i + 1][j + 1]
    w00, w10, w01, w11 = (1 - fu) * (1 - fv), fu * (1 - fv), (1 - fu) * fv, fu * fv
    return [p * w00 + q * w10 + r * w01 + s * w11 for p, q, r, s in zip(a, b, cc, d)]


@lru_cache(maxsize=32)
def _tables(geo: BodyGeometry) -> tuple[list | None, list[tuple[list[int], list]] | None]:
    """The interpolation tables of a body (``Shape``'s ``_body_table`` for one or two coils, else
    its ``_section_tables``), built once per geometry: a check or a sweep builds a plant per
    row, and an eight-limb body's tables take 0.15 s. Shared read-only."""
    shape = Shape(geo, tabulate=False)
    if shape.n_coils <= 2:
        return shape._body_table(), None
    return None, shape._section_tables()
