"""Planar objectives: motion along a heading, penalised by variance and per-transition cost.

For a robot file with planar statistics (``[transitions]`` dy, dtheta_deg, var_*; issue 17)
the score of a transition a → b is

    cos(h)·Δx + sin(h)·Δy − (λx·var_dx + λy·var_dy + λθ·var_dtheta_deg) − κ

for a heading h (0° = +x, 180° = −x), variance weights λ and a transition cost κ; a gait's
score is the sum over its transitions. The score is linear in the transitions, so the exact
engines of ``optimal_gaits`` answer it unchanged on a table whose rewards are the scores
(``total``: best score of a closed walk of at most N transitions, repeats counted;
``rate``: best score per transition), with every tie, checked against the same oracle.

Everything else goes to the exact constrained search (``constrained.py``):

* a rotation cap: a gait counts only when one pass turns the robot by at most the cap,
  |ΣΔθ| ≤ cap (``total`` and ``rate``);
* ``simple_cycles``: only simple cycles of at least two transitions (each state once per
  pass); ``total`` is then the score of one pass (repeats = 1), as in a synthesiser that
  picks one cycle (Freeman et al.'s binary integer programme over simple cycles);
* rotation gaits (``rotate="cw"|"ccw"``): the score is the turn, −Δθ or +Δθ in degrees
  (counter-clockwise = +θ, from +x towards +y), minus the same variance and transition
  terms, with the translation of one pass capped, |(ΣΔx, ΣΔy)| ≤ ``translation_cap``;
* when no gait scores above zero, the best one is still reported (``below_zero``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from ..errors import GaitError
from ..transitions import TransitionTable
from .constrained import Constraint, best_constrained
from .evaluate import make_gaits
from .optimal import TOTAL_DEFAULT_LIMIT_STATES, _check_request, optimal_gaits, rank_gaits
from .result import RELATIVE_TOLERANCE, GaitResult

ROTATIONS = ("cw", "ccw")
#: The largest transition cost κ and variance weight λ (``--transition-cost``, ``--variance-weight``,
#: ``[gaits]``), the bound of a matrix entry: a gait sums the penalties, and 1e308 overflowed the
#: sums to −inf (RuntimeWarnings, and "no gait" where 1e300 listed the best one).
MAX_PENALTY = 1e9


@dataclass(frozen=True)
class PlanarObjective:
    """Heading in degrees (0 = +x, 90 = +y), variance weights (λx, λy, λθ), transition cost κ."""

    heading_deg: float = 0.0
    variance_weight: tuple[float, float, float] = (0.0, 0.0, 0.0)
    transition_cost: float = 0.0


def heading_cos_sin(heading_deg: float) -> tuple[float, float]:
    """cos and sin of a heading in degrees, exact at multiples of 90° (``math.sin(math.pi)``
    is 1.2e-16, which would make heading 180 need Δy data and score Δx-only gaits a hair
    above zero)."""
    quarter, rest = divmod(float(heading_deg), 90.0)
    if rest == 0.0:
        return ((1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0))[int(quarter) % 4]
    h = math.radians(heading_deg)
    return math.cos(h), math.sin(h)


def _score_terms(table: TransitionTable, objective: PlanarObjective) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """A transition's score is Σ motion − Σ penalties − κ: the motion terms (cos h·Δx and, off
    the x axis, sin h·Δy) and the weighted variances with a non-zero weight, each an array
    aligned with ``table.src``/``dst``. GaitError for an objective that is not finite or a
    statistic the robot file does not give."""
    h = math.radians(objective.heading_deg)
    planar = table.planar
    given = planar.given() if planar is not None else {}
    lx, ly, lt = (float(x) for x in objective.variance_weight)
    if not all(math.isfinite(v) for v in (h, lx, ly, lt, objective.transition_cost)):
        raise GaitError("planar objective: heading, variance weights and transition cost must be finite numbers")
    if min(lx, ly, lt) < 0:
        raise GaitError(f"planar objective: variance weights must be >= 0, got {objective.variance_weight}")
    cos_h, sin_h = heading_cos_sin(objective.heading_deg)
    needed = {"dy": sin_h != 0.0, "var_dx": lx != 0, "var_dy": ly != 0, "var_dtheta_deg": lt != 0}
    missing = [k for k, used in needed.items() if used and k not in given]
    if missing:
        what = (f"heading {objective.heading_deg:g}° (off the x axis)" if missing[0] == "dy"
                else f"variance weight on {missing[0][4:]}")
        raise GaitError(f"{what} needs [transitions].{missing[0]} in the robot file, and it has none")
    motion = [cos_h * np.asarray(table.reward, dtype=np.float64)]
    if sin_h != 0.0:
        motion.append(sin_h * given["dy"])
    penalties = [w * given[k] for k, w in (("var_dx", lx), ("var_dy", ly), ("var_dtheta_deg", lt)) if w != 0]
    return motion, penalties


def planar_scores(table: TransitionTable, objective: PlanarObjective) -> np.ndarray:
    """The score of every transition (aligned with ``table.src``/``dst``)."""
    motion, penalties = _score_terms(table, objective)
    score = sum(motion[1:], motion[0])
    for p in penalties:
        score = score - p
    return score - float(objective.transition_cost)


def score_scale(table: TransitionTable, objective: PlanarObjective, rotate: str | None = None) -> float:
    """The largest magnitude any term of a transition's score has: the scale against which
    a score is "zero". A score that cancels (heading 45° with Δx = −Δy) is rounding noise
    the size of its terms, not of itself, so a tolerance relative to the scores alone would
    call that noise a gain. A rotation gait's motion is its turn, |Δθ|."""
    motion, penalties = _score_terms(table, objective if rotate is None else replace(objective, heading_deg=0.0))
    if rotate is not None:
        motion = [dtheta_of(table, "a rotation gait")]
    size = sum(np.abs(t) for t in motion + penalties) + abs(float(objective.transition_cost))
    return float(size.max()) if table.n_transitions else 0.0


def planar_table(table: TransitionTable, objective: PlanarObjective) -> TransitionTable:
    """The table with each reward replaced by its planar score (durations kept)."""
    return replace(table, reward=planar_scores(table, objective))


def rotation_scores(table: TransitionTable, objective: PlanarObjective, rotate: str) -> np.ndarray:
    """Per-transition score of a rotation gait: the turn in degrees (+Δθ for ccw, −Δθ for
    cw) minus the variance and transition-cost terms of ``objective`` (its heading unused)."""
    if rotate not in ROTATIONS:
        raise GaitError(f"rotate must be one of {', '.join(ROTATIONS)}, got {rotate!r}")
    theta = dtheta_of(table, "a rotation gait")
    sign = 1.0 if rotate == "ccw" else -1.0
    level = replace(objective, heading_deg=0.0, transition_cost=0.0)
    penalties = np.asarray(table.reward, dtype=np.float64) - planar_scores(table, level)
    return sign * theta - penalties - float(objective.transition_cost)


def dtheta_of(table: TransitionTable, what: str) -> np.ndarray:
    """The per-transition rotation (°) ``what`` needs; GaitError when the robot file gives none."""
    if table.planar is None or table.planar.dtheta_deg is None:
        raise GaitError(f"{what} needs [transitions].dtheta_deg in the robot file, and it has none")
    return np.asarray(table.planar.dtheta_deg, dtype=np.float64)


def default_translation_cap(table: TransitionTable) -> float:
    """The translation a rotation gait may drift per pass when none is given: the mean
    length |(Δx, Δy)| of one transition of the table."""
    dy = table.planar.dy if table.planar is not None and table.planar.dy is not None else 0.0
    step = np.hypot(np.asarray(table.reward, dtype=np.float64), dy)
    return float(step.mean()) if len(step) else 0.0


def optimal_planar_gaits(
    table: TransitionTable,
    objective: PlanarObjective,
    kind: str = "total",
    max_transitions: int | None = None,
    rotation_cap_deg: float | None = None,
    *,
    simple_cycles: bool = False,
    rotate: str | None = None,
    translation_cap: float | None = None,
) -> GaitResult:
    """Every gait with the best planar score (``kind`` "total", "rate" or "speed"), ranked.

    ``value`` is in score units; gaits carry their scores as ``reward``. With
    ``rotation_cap_deg`` only gaits turning by at most that much per pass count; with
    ``simple_cycles`` only simple cycles; with ``rotate`` ("cw"/"ccw") the gait that turns
    the most that way, its translation per pass capped at ``translation_cap`` (default
    ``default_translation_cap``). When no gait scores above zero the best one is returned
    with ``below_zero=True``. ``max_transitions`` defaults to the number of states (at most
    16) for ``total`` and for every constrained question.
    """
    if rotate is not None:
        scored = replace(table, reward=rotation_scores(table, objective, rotate))
    else:
        scored = planar_table(table, objective)
    tol = RELATIVE_TOLERANCE * score_scale(table, objective, rotate)
    constraints: list[Constraint] = []
    accept: Callable[[np.ndarray], np.ndarray] | None = None
    if rotation_cap_deg is not None and rotate is None:
        if not (isinstance(rotation_cap_deg, (int, float)) and math.isfinite(rotation_cap_deg) and rotation_cap_deg >= 0):
            raise GaitError(f"rotation cap must be a number of degrees >= 0, got {rotation_cap_deg!r}")
        cap = float(rotation_cap_deg)
        constraints.append(Constraint(dtheta_of(table, "a rotation cap"), -cap, cap))
    if rotate is not None:
        cap = default_translation_cap(table) if translation_cap is None else translation_cap
        if not (isinstance(cap, (int, float)) and math.isfinite(cap) and cap >= 0):
            raise GaitError(f"translation cap must be a number >= 0, got {cap!r}")
        cap = float(cap)
        dy = table.planar.dy if table.planar is not None and table.planar.dy is not None else np.zeros(table.n_transitions)
        constraints += [Constraint(np.asarray(table.reward, dtype=np.float64), -cap, cap), Constraint(dy, -cap, cap)]
        accept = _translation_within(cap)

    constrained = bool(constraints) or simple_cycles
    if kind == "speed" and constrained:
        raise GaitError("rotation caps, simple cycles and rotation gaits are answered for total and rate, not speed")
    if not constrained:
        result = optimal_gaits(scored, kind, "+x", max_transitions)
        if (result.value is not None and result.value > tol) or kind == "speed" or scored.n_transitions == 0:
            return result
        # nothing scores above zero (a value within rounding of 0 is zero, as ties are):
        # the best of the rest, over the same gaits
        # (rate: simple cycles, as optimal_gaits answers it)
        return _constrained(scored, kind, max_transitions, kind == "rate", [], None, tol)
    return _constrained(scored, kind, max_transitions, simple_cycles, constraints, accept, tol)


def _translation_within(cap: float) -> Callable[[np.ndarray], np.ndarray]:
    """Accepts walks whose (ΣΔx, ΣΔy) — the first two constraint sums — has length ≤ cap."""

    def accept(sums: np.ndarray) -> np.ndarray:
        return np.hypot(sums[:, 0], sums[:, 1]) <= cap * (1 + 1e-12) + 1e-12

    return accept


def _default_bound(table: TransitionTable, kind: str, max_transitions: int | None, simple: bool) -> int:
    K = _check_request(table, kind, "+x", max_transitions)
    if K is not None:
        return K
    n = table.n_states
    if n > TOTAL_DEFAULT_LIMIT_STATES and not simple:
        raise GaitError(
            f"this planar question on {n} states needs an explicit max_transitions "
            f"(the default, the number of states, is only used up to {TOTAL_DEFAULT_LIMIT_STATES} states)"
        )
    return n


def _constrained(
    scored: TransitionTable, kind: str, max_transitions: int | None, simple: bool, constraints, accept, tol: float
) -> GaitResult:
    K = _default_bound(scored, kind, max_transitions, simple)
    w = np.asarray(scored.reward, dtype=np.float64)
    empty = GaitResult("+x", kind, K, None, (), False)
    if len(w) == 0 or K < 2:
        return empty
    found = best_constrained(scored.n_states, scored.src, scored.dst, w, K, kind, simple, constraints, accept, tol)
    if found.best is None:
        return empty
    gaits = [replace(g, repeats=k) for g, (_, k) in zip(make_gaits(scored, [c for c, _ in found.ties]), found.ties)]
    ranked = rank_gaits(gaits, "+x", tol)
    return GaitResult("+x", kind, K, found.best, tuple(ranked), False, below_zero=bool(found.best <= tol))
