"""The ``total`` objective: the largest reward of a closed walk of at most N transitions.

Repeated walks count. A closed walk is w^k for exactly one primitive walk w, and the
firmware runs a gait cyclically, so running w is running w^k: the candidate gaits are the
primitive closed walks w of at most N transitions, each worth

    total(w) = k · J(w),   k = ⌊N / |w|⌋ (the repeats that fit in N; J(w) > 0),

and the optimum over them equals the best closed walk of at most N transitions. A walk that
repeats a shorter walk is not a separate gait: ``(10 11)^2`` is the gait ``10 11`` with
``repeats = 2``.

1. The optimum: the largest diagonal entry of the max-plus powers A^⊗2..A^⊗N
   (``maxplus.powers``, polynomial). For graphs too large for the full powers, a
   branch-and-bound over walks from every start at once, bounded by ``maxplus.walk_bounds``,
   with a threshold lowered in steps from the bound down: exact, because no prefix whose bound
   reaches the threshold is dropped.
2. The ties, lazily: for each length L, a depth-first enumeration of the closed walks of
   exactly L transitions worth at least (best − tol) / ⌊N / L⌋, pruned by the bound on the
   rest of the walk, from each start s over states ≥ s only (s is the walk's lowest state,
   where its canonical rotation begins). Lengths are visited in rank order (best rate
   first, then fewest transitions), and the listing stops at ``limit`` ties.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from ..names import counted
from .evaluate import canonical_rotation, is_primitive
from .maxplus import ClosingBound, Graph

log = logging.getLogger(__name__)

#: A search still running after this long says so, once (it may take minutes on a large robot).
SLOW_S = 10.0

#: Frontier rows expanded at once (times the largest out-degree).
_EXPAND = 1 << 18


@dataclass(frozen=True)
class TotalResult:
    """``best`` (None when no closed walk earns more than ``tol``) and the tied gaits as
    (open cycle in canonical rotation, repeats), in rank order; ``truncated`` when more
    ties exist than were listed."""

    best: float | None
    ties: list[tuple[tuple[int, ...], int]]
    truncated: bool


class _Threshold:
    """The value a closed walk must reach (the value search raises it as it finds walks),
    and the best bound among the prefixes it cut off (where the next search may start).

    Once the value search has found a walk (``found``), only a better one is of use: a prefix
    whose bound merely equals the best found is cut too. Kept, it made a table of tied rewards
    (every bound reached: 256 states, any transition, rewards −3..3) list every walk of 16
    transitions worth the best, for ever, after the first had already proved the optimum."""

    def __init__(self, value: float):
        self.value = value
        self.found = False
        self.pruned = -np.inf
        self.pruned_exact = -np.inf  # the best cut value that is a closed walk's own value

    def keeps(self, values: np.ndarray, slack: float) -> np.ndarray:
        """Which of ``values`` (bounds or closed walks' values) the search still needs."""
        if self.found:
            return values > self.value + slack
        return values >= self.value - slack

    def cut(self, bounds: np.ndarray, exact: bool = False) -> None:
        if len(bounds):
            self.pruned = max(self.pruned, float(bounds.max()))
            if exact:
                self.pruned_exact = max(self.pruned_exact, float(bounds.max()))


def best_total_walks(
    n: int,
    src: np.ndarray,
    dst: np.ndarray,
    weight: np.ndarray,
    max_transitions: int,
    tol: float,
    *,
    limit: int,
    max_states: int,
) -> TotalResult:
    """Best closed walks of at most ``max_transitions`` transitions, repeats counted.

    Walks must earn more than ``tol``; those within ``tol`` of the best are ties. At most
    ``limit`` ties (and ``max_states`` states in all) are listed.
    """
    g = Graph.from_edges(n, src, dst, weight)
    K = int(max_transitions)
    if K < 2 or len(g.src) == 0:
        return TotalResult(None, [], False)
    bound = ClosingBound(g, K)
    slack = 1e-12 * (float(np.abs(g.weight).max()) + 1.0) * K
    slow = _SlowNotice(f"gait search: {n} states, {counted(len(g.src), 'allowed transition')}, gaits of up to {K} "
                       "transitions: still searching (the search grows with the gait length: a smaller "
                       "--max-transitions or [gaits] max_transitions is faster)")
    best = _best_value(g, bound, K, tol, slack, slow)
    if best is None:
        return TotalResult(None, [], False)
    ties, truncated = _ties(g, bound, K, best, tol, slack, limit, max_states, slow)
    return TotalResult(best, ties, truncated)


class _SlowNotice:
    """Logs ``text`` once, at the first ``check`` SLOW_S seconds or more after it was made."""

    def __init__(self, text: str):
        self.text, self.t0, self.said = text, time.monotonic(), False

    def check(self) -> None:
        if not self.said and time.monotonic() - self.t0 >= SLOW_S:
            self.said = True
            log.warning(self.text)


def _best_value(g: Graph, bound: ClosingBound, K: int, tol: float, slack: float,
                slow: _SlowNotice | None = None) -> float | None:
    """The optimum: exact from the powers' diagonals, else by branch-and-bound."""
    per_length = [bound.closed_walk_bound(r) for r in range(2, K + 1)]
    top = max(per_length)
    if bound.exact:
        return top if top > tol else None
    if not top > tol:
        return None
    # Thresholds from the bound down: each step at most halves the distance still to go
    # (top − gap/4096, top − gap/2048, ...), and jumps straight to the best bound cut off by
    # the last search when that is lower: no walk lies between the two.
    gap, level = top - tol, top
    for step in range(12, -1, -1):
        threshold = _Threshold(min(level, top - gap / (1 << step)) if step else tol)
        if threshold.value < tol:
            threshold.value = tol
        found = None
        for L in range(2, K + 1):
            if per_length[L - 2] < threshold.value - slack:
                threshold.cut(np.array([per_length[L - 2]]))
                continue
            for _, weights in _closed_walks(g, bound, L, threshold, slack, raise_threshold=True, slow=slow):
                found = max(found or -np.inf, float(weights.max()))
        if found is not None and found > tol:
            return found
        if threshold.value <= tol or not threshold.pruned > tol:
            return None
        if threshold.pruned_exact >= threshold.pruned:  # the best cut is itself a closed walk
            return threshold.pruned_exact
        level = threshold.pruned
    return None


def _rank_lengths(K: int) -> list[int]:
    """Lengths in rank order: a tie of length L is worth best / ⌊K/L⌋ per repeat, so its
    rate is best / (L·⌊K/L⌋); higher rate first, then fewer transitions."""
    return sorted(range(2, K + 1), key=lambda L: (L * (K // L), L))


def _ties(
    g: Graph, bound: ClosingBound, K: int, best: float, tol: float, slack: float, limit: int, max_states: int,
    slow: _SlowNotice | None = None,
) -> tuple[list[tuple[tuple[int, ...], int]], bool]:
    out: list[tuple[tuple[int, ...], int]] = []
    listed_states = 0
    for L in _rank_lengths(K):
        k = K // L
        threshold = _Threshold((best - tol) / k)
        found: list[tuple[tuple[int, ...], float]] = []
        for walks, weights in _closed_walks(g, bound, L, threshold, slack, raise_threshold=False, slow=slow):
            for row, j in zip(walks.tolist(), weights.tolist()):
                cyc = tuple(row)
                if is_primitive(cyc) and canonical_rotation(cyc) == cyc:
                    found.append((cyc, j))
            if len(out) + len(found) > limit or listed_states + L * len(found) > max_states:
                break
        for cyc, _ in sorted(found):  # within one length (one rank): by states
            if len(out) >= limit or listed_states + L > max_states:
                return out, True
            out.append((cyc, k))
            listed_states += L
    return out, False


def _closed_walks(
    g: Graph, bound: ClosingBound, L: int, threshold: _Threshold, slack: float, *, raise_threshold: bool,
    slow: _SlowNotice | None = None,
) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """Closed walks of exactly L transitions worth ≥ threshold, from every start s over
    states ≥ s, depth first in blocks: yields (walks [k, L] as open cycles, weights [k]).
    ``slow``: told of every block (a search still running after SLOW_S says so)."""
    starts = np.flatnonzero(np.diff(g.ptr) > 0)
    chunk = max(1, _EXPAND // max(1, int(np.diff(g.ptr).max())))
    stack: list[tuple[np.ndarray, np.ndarray]] = [(starts[:, None], np.zeros(len(starts)))]
    while stack:
        if slow is not None:
            slow.check()
        paths, reward = stack.pop()
        if len(paths) > chunk:
            stack.append((paths[chunk:], reward[chunk:]))
            paths, reward = paths[:chunk], reward[:chunk]
        rows, nxt, new_reward = _expand(g, paths[:, -1], reward)
        start = paths[rows, 0]
        left = L - paths.shape[1]  # transitions still to go after this one
        keep = nxt >= start
        if left == 0:
            keep &= nxt == start
            wanted = threshold.keeps(new_reward, slack)
            threshold.cut(new_reward[keep & ~wanted], exact=True)
            keep &= wanted
            if keep.any():
                weights = new_reward[keep]
                if raise_threshold:
                    threshold.value = max(threshold.value, float(weights.max()))
                    threshold.found = True
                yield paths[rows[keep]], weights
            continue
        reach = new_reward[keep] + bound(left, nxt[keep], start[keep])
        # one transition to go: the bound is that transition's own reward, so a cut prefix
        # is a closed walk of exactly that value (over states >= its start)
        wanted = threshold.keeps(reach, slack)
        threshold.cut(reach[~wanted], exact=left == 1)
        keep[keep] = wanted
        if keep.any():
            stack.append((np.hstack([paths[rows[keep]], nxt[keep, None]]), new_reward[keep]))


def _expand(g: Graph, cur: np.ndarray, reward: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every one-transition extension: (frontier row, next state, reward so far)."""
    rows, edge = g.out_edges(cur)
    return rows, g.dst[edge], reward[rows] + g.weight[edge]
