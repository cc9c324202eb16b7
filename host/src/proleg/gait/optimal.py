"""``optimal_gaits``: pick the algorithm for an objective and turn its cycles into Gaits.

* ``total`` — the largest J over closed walks (states may recur, repeated walks count) of
  at most ``max_transitions`` transitions: max-plus matrix powers for the optimum, a lazy
  pruned enumeration for the ties (``total.py``, ``maxplus.py``).
* ``rate`` / ``speed`` — the largest J per transition / per second over simple cycles:
  Howard policy iteration for the optimum (``howard.py``) and Johnson on the critical
  subgraph for every tie (``critical.py``, ``cycles.py``). With a bound on the number of
  transitions: the unbounded ties that fit when there are any (then the optimum is
  unchanged), else a bounded exhaustive search over simple cycles.

-x is +x on the negated rewards. Tolerances: see ``result.RELATIVE_TOLERANCE``. Ties are
ranked (``rank_gaits``): best rate first, then fewest transitions, then by states.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from ..errors import GaitError
from ..transitions import TransitionTable
from .critical import critical_cycles
from .cycles import short_cycles
from .evaluate import make_gaits
from .howard import max_cycle_ratio
from .result import MAX_LISTED_STATES, MAX_TIES, RELATIVE_TOLERANCE, Gait, GaitResult, reward_scale, speed_scale
from .search import bounded_search
from .total import best_total_walks

OBJECTIVES = ("total", "rate", "speed")
DIRECTIONS = ("+x", "-x")
#: ``total`` without an explicit bound uses max_transitions = n_states up to this size.
TOTAL_DEFAULT_LIMIT_STATES = 16


def whole_body_bound(levels: Sequence[int], objective: str) -> int | None:
    """The bound on a gait's transitions when none is given, as the firmware build takes it:
    None (the engine's own default) up to ``TOTAL_DEFAULT_LIMIT_STATES`` states; for the
    total objective on a larger robot one pass of every limb up through its levels and down
    again, 2 · Σ(levels − 1) transitions (a whole-body wave)."""
    if objective != "total" or math.prod(levels) <= TOTAL_DEFAULT_LIMIT_STATES:
        return None
    return 2 * sum(k - 1 for k in levels)


def _objective_value(g: Gait, objective: str) -> float:
    if objective == "total":
        return g.total
    if objective == "rate":
        return g.rate
    assert g.duration is not None
    return g.reward / g.duration


def rank_gaits(gaits: list[Gait], direction: str, tol: float) -> list[Gait]:
    """Ties in rank order: best rate in ``direction`` first (rates within ``tol`` of each
    other are equal), then fewest transitions, then by states."""
    sign = 1.0 if direction == "+x" else -1.0
    by_rate = sorted(gaits, key=lambda g: -sign * g.rate)
    group, head, keyed = -1, 0.0, []
    for g in by_rate:
        if group < 0 or sign * (head - g.rate) > tol:  # a new, lower rate
            group, head = group + 1, g.rate
        keyed.append(((group, g.transitions, g.states), g))
    return [g for _, g in sorted(keyed, key=lambda kg: kg[0])]


def _finish(
    table: TransitionTable,
    objective: str,
    direction: str,
    bound: int | None,
    cycles: list[tuple[int, ...]],
    tol: float,
    truncated: bool,
    repeats: list[int] | None = None,
) -> GaitResult:
    """Gaits from open cycles: exact scores, keep the best ties, rank."""
    sign = 1.0 if direction == "+x" else -1.0
    gaits = make_gaits(table, cycles)
    if repeats is not None:
        gaits = [replace(g, repeats=k) for g, k in zip(gaits, repeats)]
    scored = [(sign * _objective_value(g, objective), g) for g in gaits]
    scored = [(v, g) for v, g in scored if v > tol]
    if not scored:
        return GaitResult(direction, objective, bound, None, (), False)
    best = max(v for v, _ in scored)
    keep = list({g.states: g for v, g in scored if v >= best - tol}.values())
    rate_tol = tol if objective == "rate" else RELATIVE_TOLERANCE * _rate_scale(table, sign, bound)
    return GaitResult(direction, objective, bound, sign * best, tuple(rank_gaits(keep, direction, rate_tol)), truncated)


def _rate_scale(table: TransitionTable, sign: float, bound: int | None) -> float:
    """The scale ties of rate are judged against when gaits of another objective are ranked."""
    longest = table.n_states if bound is None else min(bound, table.n_states)
    return reward_scale(sign * np.asarray(table.reward, dtype=np.float64), longest)


def optimal_gaits(
    table: TransitionTable,
    objective: str = "total",
    direction: str = "+x",
    max_transitions: int | None = None,
) -> GaitResult:
    """Every optimal gait of ``table`` for ``objective`` in ``direction``, ranked.

    objective: "total" (J of a closed walk of at most N transitions, paper Eq. 4; a gait
    repeated to fill N counts, see ``Gait.repeats``), "rate" (J per transition) or "speed"
    (J per second; needs durations). direction: "+x" maximises and counts only J > 0; "-x"
    minimises and counts only J < 0 (``value`` is then negative). ``max_transitions``
    bounds N; for "total" it defaults to the number of states (tables of at most 16
    states; larger ones must give it). Ties within 1e-9 of the table's ``reward_scale``
    (``speed_scale`` for speed) are all listed, each rotated to its canonical start, in
    rank order (``rank_gaits``): gait 0 is the one the firmware runs by default.
    """
    max_transitions = _check_request(table, objective, direction, max_transitions)
    time = _durations(table) if objective == "speed" else None
    sign = 1.0 if direction == "+x" else -1.0
    w = sign * np.asarray(table.reward, dtype=np.float64)
    if len(w) == 0 or not np.any(w > 0) or (max_transitions is not None and max_transitions < 2):
        return GaitResult(direction, objective, max_transitions, None, (), False)
    if objective == "total":
        assert max_transitions is not None
        return _best_total(table, direction, max_transitions, w)
    return _best_ratio(table, objective, direction, max_transitions, w, time)


def _check_request(table: TransitionTable, objective: str, direction: str, max_transitions: int | None) -> int | None:
    """The bound to use (the default for total filled in); GaitError for a bad request."""
    if objective not in OBJECTIVES:
        raise GaitError(f"objective {objective!r} is not one of {', '.join(OBJECTIVES)}")
    if direction not in DIRECTIONS:
        raise GaitError(f"direction {direction!r} is not one of {', '.join(DIRECTIONS)}")
    if max_transitions is not None:
        if isinstance(max_transitions, bool) or not isinstance(max_transitions, (int, np.integer)):
            raise GaitError(f"max_transitions must be a whole number, got {max_transitions!r}")
        if max_transitions < 1:
            raise GaitError(f"max_transitions must be at least 1, got {max_transitions}")
        return int(max_transitions)
    n = table.n_states
    if objective == "total":
        if n > TOTAL_DEFAULT_LIMIT_STATES:
            raise GaitError(
                f"objective total on {n} states needs an explicit max_transitions "
                f"(the default, the number of states, is only used up to {TOTAL_DEFAULT_LIMIT_STATES} states)"
            )
        return n
    return None


def _durations(table: TransitionTable) -> np.ndarray:
    if table.duration is None:
        raise GaitError("objective speed needs per-transition durations, and this table has none")
    time = np.asarray(table.duration, dtype=np.float64)
    if not np.all(np.isfinite(time) & (time > 0)):
        raise GaitError("objective speed needs every transition duration to be a positive number of seconds")
    return time


def _best_total(table: TransitionTable, direction: str, K: int, w: np.ndarray) -> GaitResult:
    tol_j = RELATIVE_TOLERANCE * reward_scale(w, K)
    res = best_total_walks(table.n_states, table.src, table.dst, w, K, tol_j, limit=MAX_TIES, max_states=MAX_LISTED_STATES)
    cycles = [c for c, _ in res.ties]
    repeats = [k for _, k in res.ties]
    return _finish(table, "total", direction, K, cycles, tol_j, res.truncated, repeats)


def _best_ratio(
    table: TransitionTable, objective: str, direction: str, K: int | None, w: np.ndarray, time: np.ndarray | None
) -> GaitResult:
    """rate / speed: Howard for the optimum, the critical subgraph for its ties, and a
    bounded search when no optimal cycle fits the bound."""
    n = table.n_states
    sign = 1.0 if direction == "+x" else -1.0
    longest = n if K is None else min(K, n)  # an optimal cycle of a ratio is simple
    scale = reward_scale(w, longest)
    tol_j = RELATIVE_TOLERANCE * scale
    t = np.ones(len(w)) if time is None else time
    tol_r = RELATIVE_TOLERANCE * (scale if time is None else speed_scale(w, t, longest))
    sol = max_cycle_ratio(n, table.src, table.dst, w, time)
    if sol.value is None or sol.value <= tol_r:
        return GaitResult(direction, objective, K, None, (), False)
    crit = critical_cycles(n, table.src, table.dst, w, t, sol, tol_j, tol_r, MAX_TIES)
    if K is None or K >= n:
        return _finish(table, objective, direction, K, crit.cycles, tol_r, crit.truncated)
    if crit.truncated:  # the listing was cut short: list the short tight cycles afresh
        fitting, truncated = short_cycles(crit.graph, K, MAX_TIES, MAX_LISTED_STATES)
    else:
        fitting, truncated = [c for c in crit.cycles if len(c) <= K], False
    if fitting:  # an unbounded optimum fits the bound, so it is the bounded optimum too
        result = _finish(table, objective, direction, K, fitting, tol_r, truncated)
        if result.value is not None and sign * result.value >= crit.value - tol_r:
            return result
    # no optimal cycle is short enough: the bounded optimum is lower; search for it exactly
    res = bounded_search(n, table.src, table.dst, w, K, tol_r, time=time, limit=MAX_TIES)
    return _finish(table, objective, direction, K, res.cycles, tol_r, res.truncated)
