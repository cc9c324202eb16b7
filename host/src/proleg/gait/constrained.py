"""Exact search for the best cycle under linear side constraints (the planar objectives).

The question: among the primitive closed walks (or, with ``simple``, the simple cycles) of
2..K transitions whose sums of some per-transition quantities c_i lie in [lo_i, hi_i]
(e.g. the rotation ΣΔθ within ±cap) and that pass a final check on those sums (e.g. the
translation |(ΣΔx, ΣΔy)| within a cap), find every one with the best value, where the
value of a walk of L transitions and score J is

* ``total`` over closed walks: k·J with k = ⌊K / L⌋ when J > 0 (the walk repeated as often
  as fits, as ``total.py`` counts it), else J (repeating a losing walk only loses more);
* ``total`` over simple cycles: J (one pass; a simple cycle is its own gait);
* ``rate``: J / L.

Values may be negative: when nothing scores above zero the best is still found.

How: for each length L, a depth-first enumeration of the walks from every start s over
states ≥ s (s is where the canonical rotation begins; > s and unvisited for simple cycles),
vectorised in blocks like ``total._closed_walks``. A prefix is dropped when

* its score plus the best walk of the remaining steps back to s (``ClosingBound``, max-plus
  powers) cannot reach the threshold, or
* for a constraint, its sum plus the largest (smallest) sum any walk of the remaining steps
  back to s can add stays below lo (above hi) — the same bound on c and on −c.

Both bounds hold for every walk, hence for every simple path: nothing that could qualify is
dropped. The threshold starts at the best value any walk could reach (the unconstrained
bound) and is lowered, at growing steps, until some walk qualifies; everything at or above
the final threshold has been listed, so the best one and every tie within ``tol`` of it are
exact. While listing, the threshold rises to (best found − tol), so the enumeration keeps
only candidates for the best and its ties (plain branch and bound). The work is exponential in the worst case (the simple-cycle question is NP-hard);
the listing gives up with a GaitError past ``MAX_LISTED_WALKS`` walks.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import GaitError
from .evaluate import canonical_rotation, is_primitive
from .maxplus import ClosingBound, Graph
from .simple_search import best_simple_cycles, fits_simple_search

#: A search that must list more qualifying walks than this gives up with a GaitError.
MAX_LISTED_WALKS = 200_000
#: Prefix rows expanded at once.
_EXPAND = 1 << 17


@dataclass(frozen=True)
class Constraint:
    """Σ values over one pass of the walk must lie in [lo, hi] (``values`` per edge)."""

    values: np.ndarray
    lo: float
    hi: float


@dataclass(frozen=True)
class Found:
    """The best value (None when no walk qualifies) and its ties as (open canonical cycle,
    repeats), sorted by cycle."""

    best: float | None
    ties: list[tuple[tuple[int, ...], int]]


def best_constrained(
    n: int,
    src: np.ndarray,
    dst: np.ndarray,
    weight: np.ndarray,
    K: int,
    kind: str,
    simple: bool,
    constraints: Sequence[Constraint] = (),
    accept: Callable[[np.ndarray], np.ndarray] | None = None,
    tol: float = 0.0,
    *,
    levels: bool = False,
) -> Found:
    """Every walk with the best value (see the module doc). ``accept`` gets the constraint
    sums of qualifying walks as a [k, len(constraints)] array and returns a bool mask.
    Simple cycles go to ``simple_search.best_simple_cycles`` (branch and bound with
    simple-path bounds) unless ``levels`` asks for the threshold search below (kept as a
    second exact method: the benchmark's "before" and a cross-check in the tests)."""
    if kind not in ("total", "rate"):
        raise GaitError(f"constrained search answers total or rate, not {kind}")
    K = min(int(K), n) if simple else int(K)
    if simple and not levels and fits_simple_search(n, K, len(constraints)):  # branch and bound with simple-path bounds (simple_search.py)
        best, ties = best_simple_cycles(n, src, dst, weight, K, kind, constraints, accept, tol)
        return Found(best, ties)
    g = Graph.from_edges(n, src, dst, weight)
    if K < 2 or len(g.src) == 0:
        return Found(None, [])
    cons = [Graph.from_edges(n, src, dst, c.values) for c in constraints]
    search = _Search(g, K, kind, simple, constraints, cons, accept, tol)
    return search.run()


class _Search:
    def __init__(self, g, K, kind, simple, constraints, cons, accept, tol):
        self.g, self.K, self.kind, self.simple = g, K, kind, simple
        self.constraints, self.accept, self.tol = list(constraints), accept, tol
        self.bound = ClosingBound(g, K)
        self.c_hi = [ClosingBound(c, K) for c in cons]
        self.c_lo = [ClosingBound(Graph.from_edges(c.n, c.src, c.dst, -c.weight), K) for c in cons]
        self.c_graph = cons
        scale = float(np.abs(g.weight).max()) + 1.0
        self.slack = 1e-12 * scale * K
        self.c_slack = [1e-9 * (float(np.abs(c.weight).max()) + 1.0) * K for c in cons]

    # value of a walk of length L and score J, and the J a value threshold asks for
    def value(self, L: int, J: np.ndarray) -> np.ndarray:
        if self.kind == "rate":
            return J / L
        if self.simple:
            return J
        return np.where(J > 0, J * (self.K // L), J)

    def j_threshold(self, L: int, t: float) -> float:
        if self.kind == "rate":
            return t * L
        if self.simple or t <= 0:
            return t
        return t / (self.K // L)

    def run(self) -> Found:
        lengths = range(2, self.K + 1)
        tops = [float(self.value(L, np.array([self.bound.closed_walk_bound(L)]))[0]) for L in lengths]
        top = max(tops)
        if not np.isfinite(top):
            return Found(None, [])
        w = self.g.weight
        lows = [float(self.value(L, np.array([L * float(w.min())]))[0]) for L in lengths]
        low = min(lows) - 1.0
        step = 2.0 ** -10 * (abs(top) + float(np.abs(w).max()) + 1e-300)
        t = top - step
        while True:
            t = max(t, low)
            found = self._list(t)
            if found:
                best = max(v for v, _, _ in found)
                if best - self.tol < t:  # ties may lie below the threshold: list them too
                    found = self._list(best - self.tol)
                    best = max(v for v, _, _ in found)
                ties = sorted((c, k) for v, c, k in found if v >= best - self.tol)
                return Found(best, ties)
            if t <= low:
                return Found(None, [])
            step *= 4.0
            t = top - step

    def _list(self, t: float) -> list[tuple[float, tuple[int, ...], int]]:
        """Every qualifying walk worth at least ``t``, and at least (best found so far − tol):
        the threshold rises as walks are found (branch and bound), so only candidates for
        the best and its ties are kept."""
        out: list[tuple[float, tuple[int, ...], int]] = []
        self.level = t
        tops = {L: float(self.value(L, np.array([self.bound.closed_walk_bound(L)]))[0]) for L in range(2, self.K + 1)}
        for L in sorted(tops, key=lambda L: -tops[L]):  # most promising lengths first: the level rises sooner
            if tops[L] < self.level - self.slack:
                continue
            for walks, J, sums in self._walks(L):
                values = self.value(L, J)
                keep = values >= self.level - self.slack
                if self.accept is not None and keep.any():
                    keep &= self.accept(sums)
                k = 1 if (self.kind == "rate" or self.simple) else self.K // L
                for row, v in zip(walks[keep].tolist(), values[keep].tolist()):
                    cyc = tuple(row)
                    if self.simple or (is_primitive(cyc) and canonical_rotation(cyc) == cyc):
                        out.append((v, cyc, k if v > 0 else 1))
                        self.level = max(self.level, v - self.tol)
                if len(out) > MAX_LISTED_WALKS:
                    out = [f for f in out if f[0] >= self.level - self.slack]
                if len(out) > MAX_LISTED_WALKS:
                    raise GaitError(
                        f"more than {MAX_LISTED_WALKS:,} planar gaits tie; give a smaller max_transitions"
                    )
        return [f for f in out if f[0] >= self.level - self.slack]

    def _walks(self, L: int):
        """Closed walks of exactly L transitions worth at least ``self.level`` (as it stands
        when each block is expanded) within every constraint:
        yields (walks [k, L] as open cycles, J [k], constraint sums [k, nc])."""
        g, nc = self.g, len(self.constraints)
        starts = np.flatnonzero(np.diff(g.ptr) > 0)
        chunk = max(1, _EXPAND // max(1, int(np.diff(g.ptr).max())))
        stack = [(starts[:, None], np.zeros(len(starts)), np.zeros((len(starts), nc)))]
        while stack:
            paths, reward, sums = stack.pop()
            if len(paths) > chunk:
                stack.append((paths[chunk:], reward[chunk:], sums[chunk:]))
                paths, reward, sums = paths[:chunk], reward[:chunk], sums[:chunk]
            rows, edge = g.out_edges(paths[:, -1])
            nxt = g.dst[edge]
            new_reward = reward[rows] + g.weight[edge]
            new_sums = sums[rows] + np.stack([c.weight[edge] for c in self.c_graph], axis=1) if nc else sums[rows]
            start = paths[rows, 0]
            left = L - paths.shape[1]
            if left == 0:
                keep = nxt == start
            elif self.simple:
                keep = (nxt > start) & ~(paths[rows] == nxt[:, None]).any(axis=1)
            else:
                keep = nxt >= start
            reach = new_reward + (self.bound(left, nxt, start) if left else 0.0)
            keep &= reach >= self.j_threshold(L, self.level) - self.slack
            for i, con in enumerate(self.constraints):
                if not keep.any():
                    break
                s = new_sums[:, i]
                if left:
                    up = s + self.c_hi[i](left, nxt, start)
                    down = s - self.c_lo[i](left, nxt, start)
                else:
                    up = down = s
                keep &= (up >= con.lo - self.c_slack[i]) & (down <= con.hi + self.c_slack[i])
            if not keep.any():
                continue
            if left == 0:
                yield paths[rows[keep]], new_reward[keep], new_sums[keep]
                continue
            best_first = np.flatnonzero(keep)[np.argsort(-reach[keep], kind="stable")]
            grown = np.hstack([paths[rows[best_first]], nxt[best_first, None]])
            stack.append((grown, new_reward[best_first], new_sums[best_first]))
