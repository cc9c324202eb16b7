"""Bounded exhaustive search for the best simple cycles by ratio (J per transition or second).

Used when no optimal cycle of the unbounded problem fits the bound on the number of
transitions (``optimal.py``); ``total`` has its own polynomial method (``total.py``).

Depth-first search from each start s over states >= s (s is then the cycle's lowest state,
where its canonical rotation begins), pruned by a max-plus upper bound. A cycle reaches
ratio L iff Σ (w − L·t) >= 0 (the parametric method: Dantzig, Blattner & Rao, 1967), so with
a = w − L·t for the threshold L current when s is reached:

    ub[k][v] = the largest Σa of a walk of at most k steps from v back to s over states >= s
               (ub[0][s] = 0, ub[0][v != s] = −∞),

computed by k rounds of a vectorised max-plus product over the edge arrays. A prefix with
Σ(w − L·t) = R at v with r steps left is abandoned when R + ub[r][v] < 0 for the current L
(a stale, lower L in the table only loosens the bound). Exponential in the bound in the
worst case (many ties, flat rewards), fast when the rewards separate cycles. Up to
``limit`` optimal cycles are kept; beyond it the result is marked truncated.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class SearchResult:
    """Open simple cycles (start not repeated, starting at their lowest state) whose ratio
    is at least ``best - tol``; ``best`` is None when nothing reached the threshold."""

    best: float | None
    cycles: list[tuple[int, ...]]
    truncated: bool


def bounded_search(
    n: int,
    src: np.ndarray,
    dst: np.ndarray,
    weight: np.ndarray,
    max_transitions: int,
    tol: float,
    *,
    time: np.ndarray | None = None,
    limit: int | None = None,
) -> SearchResult:
    """Best simple cycles of 2..``max_transitions`` transitions by Σw / Σt.

    t = 1 per edge when ``time`` is None (J per transition), else seconds (J per second).
    Only cycles worth more than ``tol`` count; cycles within ``tol`` of the best are all
    kept (at most ``limit``). Edges must be sorted by source.
    """
    src = np.asarray(src, dtype=np.int64)
    dst = np.asarray(dst, dtype=np.int64)
    w = np.asarray(weight, dtype=np.float64)
    t = np.ones(len(w)) if time is None else np.asarray(time, dtype=np.float64)
    best = _Best(floor=float(tol), tol=float(tol), limit=limit)
    ptr = np.searchsorted(src, np.arange(n + 1))
    for s in range(n):
        keep = dst[ptr[s]:] >= s
        if keep.any():
            sub = _Subgraph(n, s, src[ptr[s]:][keep], dst[ptr[s]:][keep], w[ptr[s]:][keep], t[ptr[s]:][keep])
            _search_from(sub, int(max_transitions), best)
    return best.result()


@dataclass
class _Best:
    """The best ratio so far, the cycles within ``tol`` of it, and whether some were dropped."""

    floor: float
    tol: float
    limit: int | None
    best: float | None = None
    kept: list[tuple[float, tuple[int, ...]]] = field(default_factory=list)
    dropped_best: float = -np.inf

    @property
    def lower(self) -> float:
        """What a cycle must reach to be kept."""
        return self.floor if self.best is None else max(self.floor, self.best - self.tol)

    def offer(self, value: float, cycle: tuple[int, ...]) -> None:
        if value < self.lower:
            return
        if self.best is None or value > self.best:
            self.best = value
            self.kept = [kv for kv in self.kept if kv[0] >= self.lower]
        if self.limit is not None and len(self.kept) >= self.limit:
            self.dropped_best = max(self.dropped_best, value)
            return
        self.kept.append((value, cycle))

    def result(self) -> SearchResult:
        lower = self.lower
        return SearchResult(self.best, [c for v, c in self.kept if v >= lower], bool(self.dropped_best >= lower))


@dataclass
class _Subgraph:
    """The edges from states >= s to states >= s, sorted by source, for the search from s."""

    n: int
    s: int
    src: np.ndarray
    dst: np.ndarray
    w: np.ndarray
    t: np.ndarray

    def ptr(self) -> np.ndarray:
        return np.searchsorted(self.src, np.arange(self.n + 1))


def _upper_bounds(sub: _Subgraph, a: np.ndarray, k_max: int) -> list[np.ndarray]:
    """ub[k] for k = 0..k_max: the best Σa of at most k steps from each state back to s."""
    ub0 = np.full(sub.n, -np.inf)
    ub0[sub.s] = 0.0
    out = [ub0]
    starts = np.flatnonzero(np.r_[True, sub.src[1:] != sub.src[:-1]])
    heads = sub.src[starts]
    for _ in range(k_max):
        prev = out[-1]
        cur = prev.copy()
        cur[heads] = np.maximum(prev[heads], np.maximum.reduceat(a + prev[sub.dst], starts))
        out.append(cur)
    return out


def _search_from(sub: _Subgraph, K: int, best: _Best) -> None:
    """Every simple cycle through s (its lowest state) that can reach ``best.lower``."""
    a = sub.w - best.lower * sub.t
    ub = _upper_bounds(sub, a, K)
    ptr = sub.ptr()
    gain = [None] + [a + ub[r - 1][sub.dst] for r in range(1, K + 1)]
    slack = 1e-12 * (float(np.abs(a).max()) + 1.0) * K
    path = [sub.s]
    on_path = np.zeros(sub.n, dtype=bool)
    on_path[sub.s] = True
    # frames: [node, steps left, Σw, Σt, candidate edge positions, next candidate]
    frames: list[list] = [_frame(sub.s, K, 0.0, 0.0, gain[K], ptr, best.lower, slack)]
    while frames:
        fr = frames[-1]
        v, r, rw, rt, cand, i = fr
        if i >= len(cand):
            frames.pop()
            if frames:
                on_path[path.pop()] = False
            continue
        fr[5] = i + 1
        e = cand[i]
        u = int(sub.dst[e])
        nw, nt = rw + float(sub.w[e]), rt + float(sub.t[e])
        if nw - best.lower * nt + float(ub[r - 1][u]) < -slack:  # the threshold may have risen
            continue
        if u == sub.s:
            best.offer(nw / nt, tuple(path))
            continue
        if on_path[u] or r - 1 < 1:
            continue
        path.append(u)
        on_path[u] = True
        frames.append(_frame(u, r - 1, nw, nt, gain[r - 1], ptr, best.lower, slack))


def _frame(v: int, r: int, rw: float, rt: float, gain: np.ndarray, ptr: np.ndarray, lower: float, slack: float) -> list:
    """A DFS frame at v: the edges out of v that can still reach ``lower``, best first.
    Σ(w − lower·t) over the finished cycle <= rw − lower·rt + gain, as the table's L <= lower."""
    g = gain[ptr[v]:ptr[v + 1]]
    cand = np.flatnonzero(rw - lower * rt + g >= -slack)
    cand = cand[np.argsort(-g[cand], kind="stable")] + ptr[v]
    return [v, r, rw, rt, cand.tolist(), 0]
