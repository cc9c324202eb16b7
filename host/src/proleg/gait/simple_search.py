"""Exact branch and bound for the best simple cycle under linear side constraints.

The simple-cycle half of ``constrained.best_constrained``: among the simple cycles of
2..K transitions whose constraint sums lie in [lo_i, hi_i] (and pass ``accept``), every one
with the best value — ``total``: the score J of one pass; ``rate``: J / L.

One depth-first search per start state s (the cycle's lowest state, so each cycle is met
once, in its canonical rotation), over states > s, each visited at most once (a bitmask).
The incumbent (best value found so far, minus the tie tolerance) prunes: a prefix of p
transitions, score J, at state v is dropped when no completion of l ≤ K − p transitions
back to s can reach it. The completion bound for each l is the smaller of

* the best *walk* of exactly l transitions from v to s over states > s (max-plus powers,
  computed once per start; repeats allowed, so it also bounds every simple path), and
* the best in-transition of s plus the l − 1 best in-transitions of distinct unvisited
  states, every one from an unvisited state (a simple completion from a child w enters
  l − 1 distinct states not yet visited, then s, each time from w or a state not yet
  visited: the parent's unvisited set, which holds w, covers both).

The second bound is what makes long cycles cheap to rule out: a walk bound can repeat a
good two-cycle forever, a simple path cannot. Constraint sums are bounded the same way
(largest and smallest sum, each with both bounds). Every bound holds for every simple
completion, so nothing that could qualify is dropped, and the result is exact; children are
tried best bound first, and a first pass over cycles of at most three transitions gives the
incumbent a head start. Still exponential in the worst case (the question is NP-hard).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from ..errors import GaitError

#: A search that must keep more tied cycles than this gives up with a GaitError.
MAX_TIES = 200_000
#: The per-start walk bounds are dense: n · n · (K + 1) entries per bounded quantity. Above
#: this many in all (64 MB of float64) constrained.py keeps its own threshold search.
MAX_BOUND_ENTRIES = 1 << 23
_NEG = -np.inf


def fits_simple_search(n: int, K: int, n_constraints: int) -> bool:
    """Whether the dense bounds of this search fit MAX_BOUND_ENTRIES."""
    K = min(int(K), n)
    return n * n * (K + 1) * (1 + 2 * n_constraints) <= MAX_BOUND_ENTRIES


class _Start:
    """Per start state s: the walk bounds of completions back to s (score, constraint sums)."""

    def __init__(self, s: int, W: np.ndarray, C_hi: list[np.ndarray], C_lo: list[np.ndarray], K: int):
        self.s = s
        # walks back to s over intermediate states > s: exactly l transitions, l = 0..K
        self.walk = _walk_bounds(W, s, K)
        self.c_hi = [_walk_bounds(c, s, K) for c in C_hi]
        self.c_lo = [-_walk_bounds(-c, s, K) for c in C_lo]


def _walk_bounds(W: np.ndarray, s: int, K: int) -> np.ndarray:
    """[K + 1, n]: best walk of exactly l transitions from v to s, intermediate states > s."""
    n = W.shape[0]
    out = np.full((K + 1, n), _NEG)
    out[0, s] = 0.0
    inner = W.copy()
    inner[:, : s + 1] = _NEG  # steps that do not end the walk stay above s
    inner[:s, :] = _NEG
    into = np.full(n, _NEG)
    into[s:] = W[s:, s]
    if K >= 1:
        out[1] = into
    for r in range(2, K + 1):
        out[r] = np.max(inner + out[r - 1][None, :], axis=1)
    out[:, :s] = _NEG
    return out


def best_simple_cycles(
    n: int,
    src: np.ndarray,
    dst: np.ndarray,
    weight: np.ndarray,
    K: int,
    kind: str,
    constraints: Sequence = (),
    accept: Callable[[np.ndarray], np.ndarray] | None = None,
    tol: float = 0.0,
) -> tuple[float | None, list[tuple[tuple[int, ...], int]]]:
    """(best value or None, ties as (open canonical cycle, 1) sorted) — see the module doc."""
    if kind not in ("total", "rate"):
        raise GaitError(f"simple-cycle search answers total or rate, not {kind}")
    K = min(int(K), n)
    src = np.asarray(src, dtype=np.int64)
    dst = np.asarray(dst, dtype=np.int64)
    if K < 2 or len(src) == 0:
        return None, []
    W = np.full((n, n), _NEG)
    W[src, dst] = np.asarray(weight, dtype=np.float64)
    C = []
    for con in constraints:
        c = np.zeros((n, n))
        c[src, dst] = np.asarray(con.values, dtype=np.float64)
        C.append(c)
    cmask = np.isfinite(W)
    slack = 1e-12 * (float(np.abs(weight).max()) + 1.0) * K
    c_slack = [1e-9 * (float(np.abs(np.asarray(con.values)).max(initial=0.0)) + 1.0) * K for con in constraints]
    search = _BranchAndBound(n, W, C, cmask, K, kind, list(constraints), accept, tol, slack, c_slack)
    if K > 3:
        search.run(min(K, 3))  # a head start for the incumbent; the full run lists everything again
    search.found.clear()
    search.run(K)
    if not search.found:
        return None, []
    best = max(v for v, _ in search.found)
    ties = sorted((c, 1) for v, c in search.found if v >= best - tol)
    return best, ties


class _BranchAndBound:
    def __init__(self, n, W, C, cmask, K, kind, constraints, accept, tol, slack, c_slack):
        self.n, self.W, self.C, self.cmask, self.K, self.kind = n, W, C, cmask, K, kind
        self.constraints, self.accept, self.tol = constraints, accept, tol
        self.slack, self.c_slack = slack, c_slack
        self.level = -np.inf
        self.found: list[tuple[float, tuple[int, ...]]] = []
        self.Chi = [np.where(cmask, c, _NEG) for c in C]  # missing transitions: never the largest
        self.Clo = [np.where(cmask, c, np.inf) for c in C]  # ... nor the smallest
        self.starts = [_Start(s, W, self.Chi, self.Clo, K) for s in range(n)]

    def _value(self, J: float, L: int) -> float:
        return J / L if self.kind == "rate" else J

    def run(self, K: int) -> None:
        for st in self.starts:
            if np.isfinite(st.walk[2:K + 1, st.s].max(initial=_NEG)):
                self._search(st, K)

    def _search(self, st: _Start, K: int) -> None:
        s, W, nc = st.s, self.W, len(self.C)
        n = self.n
        Chi, Clo = self.Chi, self.Clo
        free0 = np.zeros(n, dtype=bool)
        free0[s + 1:] = True
        # stack entries: (path, free mask, J, constraint sums)
        stack = [([s], free0, 0.0, np.zeros(nc))]
        while stack:
            path, free, J, sums = stack.pop()
            v = path[-1]
            p = len(path) - 1  # transitions so far
            left = K - p
            # close the cycle
            if p >= 1 and self.cmask[v, s]:
                self._close(path, J + W[v, s], sums + np.array([c[v, s] for c in self.C]) if nc else sums)
            if left < 2:
                continue
            kids = np.flatnonzero(free & self.cmask[v])
            if len(kids) == 0:
                continue
            # completions from a child w take l = 1..left-1 transitions back to s, entering
            # l - 1 distinct states of free - {w}, then s, each from a state of free
            ls = left - 1
            Jk = J + W[v, kids]
            into = W[free].max(axis=0)
            top = np.sort(into[free])[::-1][: ls - 1]
            simple = np.full(ls, _NEG)
            simple[0] = 0.0
            simple[1 : len(top) + 1] = np.cumsum(top)
            simple += into[s]
            walk = st.walk[1:ls + 1][:, kids]  # [ls, k]
            comp = np.minimum(walk, simple[:, None])
            if self.kind == "rate":
                L = (p + 1 + np.arange(1, ls + 1))[:, None]
                bound = ((Jk[None, :] + comp) / L).max(axis=0)
            else:
                bound = Jk + comp.max(axis=0)
            ok = bound >= self.level - self.slack
            sk = None
            if nc:
                sk = sums[None, :] + np.stack([c[v, kids] for c in self.C], axis=1)  # [k, nc]
                for i, con in enumerate(self.constraints):
                    hi_in = Chi[i][free].max(axis=0)
                    lo_in = Clo[i][free].min(axis=0)
                    hi_s = np.full(ls, _NEG)
                    lo_s = np.full(ls, np.inf)
                    hi_s[0] = lo_s[0] = 0.0
                    t_hi = np.sort(hi_in[free])[::-1][: ls - 1]
                    t_lo = np.sort(lo_in[free])[: ls - 1]
                    hi_s[1 : len(t_hi) + 1] = np.cumsum(t_hi)
                    lo_s[1 : len(t_lo) + 1] = np.cumsum(t_lo)
                    hi_s += hi_in[s]
                    lo_s += lo_in[s]
                    up = np.minimum(st.c_hi[i][1:ls + 1][:, kids], hi_s[:, None]).max(axis=0)
                    down = np.maximum(st.c_lo[i][1:ls + 1][:, kids], lo_s[:, None]).min(axis=0)
                    ok &= (sk[:, i] + up >= con.lo - self.c_slack[i]) & (sk[:, i] + down <= con.hi + self.c_slack[i])
            idx = np.flatnonzero(ok)
            if len(idx) == 0:
                continue
            # best bound last on the stack: popped first
            for j in idx[np.argsort(bound[idx], kind="stable")]:
                w = int(kids[j])
                f = free.copy()
                f[w] = False
                stack.append((path + [w], f, float(Jk[j]), sk[j] if nc else sums))

    def _close(self, path: list[int], J: float, sums: np.ndarray) -> None:
        L = len(path)
        if L < 2:
            return
        v = self._value(J, L)
        if v < self.level - self.slack:
            return
        for i, con in enumerate(self.constraints):
            if not (con.lo - self.c_slack[i] <= sums[i] <= con.hi + self.c_slack[i]):
                return
        if self.accept is not None and not bool(self.accept(sums[None, :])[0]):
            return
        self.found.append((v, tuple(path)))
        if v - self.tol > self.level:
            self.level = v - self.tol
            if len(self.found) > 64:
                self.found = [f for f in self.found if f[0] >= self.level - self.slack]
        if len(self.found) > MAX_TIES:
            raise GaitError(f"more than {MAX_TIES:,} planar gaits tie; give a smaller max_transitions")
