"""Planar objectives: motion along a heading, penalised by variance and per-transition cost.

For a robot file with planar statistics (``[transitions]`` dy, dtheta_deg, var_*; issue 17)
the score of a transition a → b is

    cos(h)·Δx + sin(h)·Δy − (λx·var_dx + λy·var_dy + λθ·var_dtheta_deg) − κ

for a heading h (0° = +x, 180° = −x), variance weights λ and a transition cost κ; a gait's
score is the sum over its transitions. The score is linear in the transitions, so the exact
engines of ``optimal_gaits`` answer it unchanged on a table whose rewards are the scores
(``total``: best score of a closed walk of at most N transitions, repeats counted;
``rate``: best score per transition), with every tie, checked against the same oracle.

With a rotation cap (``total`` only so far), a gait counts only when one pass turns the
robot by at most the cap, |ΣΔθ| ≤ cap: the engine lists the walks above a threshold with
the same pruned enumeration as ``total`` (``total._closed_walks``), keeps those within the
cap, and lowers the threshold from the uncapped optimum in steps until some walk is kept.
Exact: every walk above the final threshold is listed, so the best capped one is found.

Not here yet: the cap for ``rate``, the simple-cycle restriction for ``total``, rotation
gaits and "best of the negatives" when nothing scores above zero.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..errors import GaitError
from ..transitions import TransitionTable
from .evaluate import canonical_rotation, is_primitive
from .maxplus import ClosingBound, Graph
from .optimal import _check_request, _finish, optimal_gaits
from .result import RELATIVE_TOLERANCE, GaitResult
from .total import _best_value, _closed_walks, _Threshold

#: A capped search that must list more walks than this gives up with a GaitError.
MAX_CAPPED_WALKS = 200_000


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
    rotation_cap_deg: float | None = None,
) -> GaitResult:
    """Every gait with the best planar score (``kind`` "total", "rate" or "speed"), ranked.
    ``value`` is in score units; gaits carry their scores as ``reward``. With
    ``rotation_cap_deg`` only gaits turning by at most that much per pass count."""
    scored = planar_table(table, objective)
    if rotation_cap_deg is None:
        return optimal_gaits(scored, kind, "+x", max_transitions)
    if kind != "total":
        raise GaitError(f"a rotation cap is only supported with objective total so far, not {kind}")
    if table.planar is None or table.planar.dtheta_deg is None:
        raise GaitError("a rotation cap needs [transitions].dtheta_deg in the robot file, and it has none")
    if not (math.isfinite(rotation_cap_deg) and rotation_cap_deg >= 0):
        raise GaitError(f"rotation cap must be a number of degrees >= 0, got {rotation_cap_deg!r}")
    K = _check_request(scored, "total", "+x", max_transitions)
    assert K is not None
    return _capped_total(scored, table.planar.dtheta_deg, K, float(rotation_cap_deg))


def _capped_total(scored: TransitionTable, dtheta: np.ndarray, K: int, cap: float) -> GaitResult:
    n, w = scored.n_states, np.asarray(scored.reward, dtype=np.float64)
    empty = GaitResult("+x", "total", K, None, (), False)
    if len(w) == 0 or not np.any(w > 0) or K < 2:
        return empty
    tol = RELATIVE_TOLERANCE * float(np.abs(w).max())
    g = Graph.from_edges(n, scored.src, scored.dst, w)
    turn = Graph.from_edges(n, scored.src, scored.dst, dtheta)
    bound = ClosingBound(g, K)
    slack = 1e-12 * (float(np.abs(w).max()) + 1.0) * K
    top = _best_value(g, bound, K, tol, slack)
    if top is None:
        return empty
    gap = top - tol
    for step in range(12, -1, -1):  # thresholds top − gap/4096, ..., tol
        threshold = top - gap / (1 << step) if step else tol
        found = _capped_walks(g, turn, bound, K, threshold, cap, slack)
        if found:
            best = max(v for v, _, _ in found)
            ties = [(c, k) for v, c, k in sorted(found, key=lambda f: f[1]) if v >= best - tol]
            return _finish(scored, "total", "+x", K, [c for c, _ in ties], tol, False, [k for _, k in ties])
    return empty


def _capped_walks(
    g: Graph, turn: Graph, bound: ClosingBound, K: int, threshold: float, cap: float, slack: float
) -> list[tuple[float, tuple[int, ...], int]]:
    """(k·J, primitive canonical walk, k) for every walk with k·J >= threshold within the cap."""
    out: list[tuple[float, tuple[int, ...], int]] = []
    listed = 0
    for L in range(2, K + 1):
        k = K // L
        for walks, weights in _closed_walks(g, bound, L, _Threshold(threshold / k), slack, raise_threshold=False):
            listed += len(walks)
            if listed > MAX_CAPPED_WALKS:
                raise GaitError(
                    f"the rotation cap leaves more than {MAX_CAPPED_WALKS:,} walks to check; give a smaller max_transitions"
                )
            rot = turn.edge_weight(walks.ravel(), np.roll(walks, -1, axis=1).ravel()).reshape(walks.shape).sum(axis=1)
            for row, j, r in zip(walks.tolist(), weights.tolist(), rot.tolist()):
                cyc = tuple(row)
                if abs(r) <= cap + 1e-9 and is_primitive(cyc) and canonical_rotation(cyc) == cyc:
                    out.append((k * j, cyc, k))
    return out
