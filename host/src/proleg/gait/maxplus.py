"""Max-plus matrix powers over the sparse transition graph.

In the max-plus semiring (⊕ = max, ⊗ = +) the transition graph is the matrix A with
A[a][b] = reward of a → b (−∞ where forbidden), and (A^⊗r)[v][s] is the largest reward of
a walk of exactly r transitions from v to s. Its diagonal answers the ``total`` objective
directly: the best closed walk of at most N transitions is worth

    max over 2 ≤ r ≤ N, s  of  (A^⊗r)[s][s]

(Baccelli, Cohen, Olsder & Quadrat, *Synchronization and Linearity*, 1992, ch. 3;
Butkovič, *Max-linear Systems*, 2010, §1.6). Each power costs one pass over the edge list
per column block: O(N · m · n) time, O(N · n²) memory for n states and m transitions.

Above ``EXACT_ENTRIES`` matrix entries the full powers do not fit, and two vectors bound
them instead (both O(N · m), kept for the states a transition touches): ``out_ub[r][v]`` the
best r-transition walk *from* v, and
``in_ub[r][s]`` the best one *into* s, so (A^⊗r)[v][s] ≤ min(out_ub[r][v], in_ub[r][s]);
one transition is looked up exactly.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Full powers are kept while (N + 1) · n² entries stay below this (64 MB of float64)...
EXACT_ENTRIES = 1 << 23
#: ...and N · m · n, the work to compute them, stays below this.
EXACT_WORK = 60_000_000
#: Rows of a dense block are computed this many entries (edges × columns) at a time.
_BLOCK = 1 << 22


@dataclass(frozen=True)
class Graph:
    """Edges sorted by source, with their CSR row pointers and a sorted key for look-ups."""

    n: int
    src: np.ndarray      # int64[m]
    dst: np.ndarray      # int64[m]
    weight: np.ndarray   # float64[m]
    ptr: np.ndarray      # int64[n + 1]: edges of v are ptr[v]:ptr[v + 1]
    keys: np.ndarray     # int64[m]: src · n + dst, ascending

    @classmethod
    def from_edges(cls, n: int, src, dst, weight) -> "Graph":
        src = np.asarray(src, dtype=np.int64)
        dst = np.asarray(dst, dtype=np.int64)
        w = np.asarray(weight, dtype=np.float64)
        order = np.lexsort((dst, src))
        src, dst, w = src[order], dst[order], w[order]
        ptr = np.searchsorted(src, np.arange(n + 1))
        return cls(n, src, dst, w, ptr, src * n + dst)

    def out_edges(self, cur: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Every edge leaving each state of ``cur`` (vectorised): (row of ``cur`` it leaves
        from, edge index), rows ascending, each row's edges in CSR order."""
        lo, hi = self.ptr[cur], self.ptr[cur + 1]
        deg = hi - lo
        rows = np.repeat(np.arange(len(cur)), deg)
        first = np.cumsum(deg) - deg
        return rows, lo[rows] + (np.arange(len(rows)) - first[rows])

    def edge_weight(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Reward of a → b, −∞ where there is no such transition (vectorised)."""
        want = a * self.n + b
        if len(self.keys) == 0:
            return np.full(len(want), -np.inf)
        pos = np.minimum(np.searchsorted(self.keys, want), len(self.keys) - 1)
        return np.where(self.keys[pos] == want, self.weight[pos], -np.inf)


def _max_by_group(values: np.ndarray, groups: np.ndarray, n: int) -> np.ndarray:
    """out[g] = max of values[i] over i with groups[i] == g (rows of a 2-D array), −∞ if none.
    ``groups`` must be sorted."""
    out = np.full((n,) + values.shape[1:], -np.inf)
    if len(groups):
        starts = np.flatnonzero(np.r_[True, groups[1:] != groups[:-1]])
        out[groups[starts]] = np.maximum.reduceat(values, starts, axis=0)
    return out


def fits_exactly(n: int, m: int, max_transitions: int) -> bool:
    """Whether the full powers A^⊗0..A^⊗N fit the time and memory budget."""
    return (max_transitions + 1) * n * n <= EXACT_ENTRIES and max_transitions * m * n <= EXACT_WORK


def powers(g: Graph, max_transitions: int) -> list[np.ndarray]:
    """[A^⊗0, A^⊗1, ..., A^⊗N] as dense n × n arrays (−∞ = no walk of that length)."""
    n = g.n
    eye = np.full((n, n), -np.inf)
    np.fill_diagonal(eye, 0.0)
    out = [eye]
    cols = max(1, _BLOCK // max(1, len(g.src)))
    for _ in range(max_transitions):
        prev = out[-1]
        cur = np.empty((n, n))
        for c0 in range(0, n, cols):  # (A ⊗ P)[v, s] = max over v → u of w + P[u, s]
            block = g.weight[:, None] + prev[g.dst, c0:c0 + cols]
            cur[:, c0:c0 + cols] = _max_by_group(block, g.src, n)
        out.append(cur)
    return out


def walk_bounds(g: Graph, max_transitions: int) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """(out_ub, in_ub): for r = 0..N, the best r-transition walk from / into each state."""
    n = g.n
    by_dst = np.argsort(g.dst, kind="stable")
    d_src, d_dst, d_w = g.src[by_dst], g.dst[by_dst], g.weight[by_dst]
    out_ub, in_ub = [np.zeros(n)], [np.zeros(n)]
    for _ in range(max_transitions):
        out_ub.append(_max_by_group(g.weight + out_ub[-1][g.dst], g.src, n))
        in_ub.append(_max_by_group(d_w + in_ub[-1][d_src], d_dst, n))
    return out_ub, in_ub


class ClosingBound:
    """Upper bound on the best walk of exactly r transitions from ``cur`` back to ``start``:
    exact (from the powers) when they fit, else from ``walk_bounds`` and one exact step."""

    def __init__(self, g: Graph, max_transitions: int):
        self.graph = g
        self.exact = fits_exactly(g.n, len(g.src), max_transitions)
        if self.exact:
            self.powers = powers(g, max_transitions)
        else:
            # the bounds over the states some transition touches (O(N · m), as the module says),
            # each other state on one row past them that no walk leaves or enters: over all n
            # states they were O(N · n), 1.7 GB for a million states with four transitions
            active = np.union1d(g.src, g.dst)
            self.row = np.full(g.n, len(active), dtype=np.int64)
            self.row[active] = np.arange(len(active))
            packed = Graph.from_edges(len(active) + 1, self.row[g.src], self.row[g.dst], g.weight)
            self.out_ub, self.in_ub = walk_bounds(packed, max_transitions)

    def __call__(self, r: int, cur: np.ndarray, start: np.ndarray) -> np.ndarray:
        if self.exact:
            return self.powers[r][cur, start]
        if r == 0:
            return np.where(cur == start, 0.0, -np.inf)
        if r == 1:
            return self.graph.edge_weight(cur, start)
        return np.minimum(self.out_ub[r][self.row[cur]], self.in_ub[r][self.row[start]])

    def closed_walk_bound(self, r: int) -> float:
        """An upper bound on every closed walk of exactly r transitions (exact when the
        powers fit: the largest diagonal entry of A^⊗r)."""
        if self.exact:
            return float(np.max(np.diagonal(self.powers[r]), initial=-np.inf))
        return float(np.max(np.minimum(self.out_ub[r], self.in_ub[r]), initial=-np.inf))
