"""Planar objectives: motion along a heading, penalised by variance and per-transition cost.

For a robot file with planar statistics (``[transitions]`` dy, dtheta_deg, var_*; issue 17)
the score of a transition a → b is

    cos(h)·Δx + sin(h)·Δy − (λx·var_dx + λy·var_dy + λθ·var_dtheta_deg) − κ

for a heading h (0° = +x, 180° = −x), variance weights λ and a transition cost κ; a gait's
score is the sum over its transitions. The score is linear in the transitions, so the exact
engines of ``optimal_gaits`` answer it unchanged on a table whose rewards are the scores
(``total``: best score of a closed walk of at most N transitions, repeats counted;
``rate``: best score per transition), with every tie, checked against the same oracle.

Not here yet: the rotation cap |ΣΔθ| ≤ cap per cycle, the simple-cycle restriction for
``total``, rotation gaits and "best of the negatives" when nothing scores above zero.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..errors import GaitError
from ..transitions import TransitionTable
from .optimal import optimal_gaits
from .result import GaitResult


@dataclass(frozen=True)
class PlanarObjective:
    """Heading in degrees (0 = +x, 90 = +y), variance weights (λx, λy, λθ), transition cost κ."""

    heading_deg: float = 0.0
    variance_weight: tuple[float, float, float] = (0.0, 0.0, 0.0)
    transition_cost: float = 0.0


def planar_scores(table: TransitionTable, objective: PlanarObjective) -> np.ndarray:
    """The score of every transition (aligned with ``table.src``/``dst``)."""
    h = math.radians(objective.heading_deg)
    planar = table.planar
    given = planar.given() if planar is not None else {}
    lx, ly, lt = (float(x) for x in objective.variance_weight)
    if not all(math.isfinite(v) for v in (h, lx, ly, lt, objective.transition_cost)):
        raise GaitError("planar objective: heading, variance weights and transition cost must be finite numbers")
    if min(lx, ly, lt) < 0:
        raise GaitError(f"planar objective: variance weights must be >= 0, got {objective.variance_weight}")
    needed = {"dy": math.sin(h) != 0.0, "var_dx": lx != 0, "var_dy": ly != 0, "var_dtheta_deg": lt != 0}
    missing = [k for k, used in needed.items() if used and k not in given]
    if missing:
        raise GaitError(f"planar objective needs [transitions].{missing[0]} in the robot file, and it has none")
    zero = np.zeros(table.n_transitions)
    score = math.cos(h) * np.asarray(table.reward, dtype=np.float64)
    if math.sin(h) != 0.0:
        score = score + math.sin(h) * given["dy"]
    score = score - lx * given.get("var_dx", zero) - ly * given.get("var_dy", zero) - lt * given.get("var_dtheta_deg", zero)
    return score - float(objective.transition_cost)


def planar_table(table: TransitionTable, objective: PlanarObjective) -> TransitionTable:
    """The table with each reward replaced by its planar score (durations kept)."""
    return replace(table, reward=planar_scores(table, objective))


def optimal_planar_gaits(
    table: TransitionTable,
    objective: PlanarObjective,
    kind: str = "total",
    max_transitions: int | None = None,
) -> GaitResult:
    """Every gait with the best planar score (``kind`` "total", "rate" or "speed"), ranked.
    ``value`` is in score units; gaits carry their scores as ``reward``."""
    return optimal_gaits(planar_table(table, objective), kind, "+x", max_transitions)
