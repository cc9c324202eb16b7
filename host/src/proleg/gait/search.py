"""Bounded exhaustive search for the best closed walks or simple cycles.

Depth-first search from each start s over states >= s (s is then the walk's lowest
state, where its canonical rotation begins), pruned by a max-plus upper bound:

    ub[k][v] = the largest weight of a walk of at most k steps from v back to s over
               states >= s (ub[0][s] = 0, ub[0][v != s] = -inf),

computed per start by k rounds of a vectorised max-plus product over the edge arrays.
A prefix of weight R at v with r steps left can still reach a walk worth R + ub[r][v];
it is abandoned when that cannot reach the best value found so far (minus the tie
tolerance). Ratio objectives (J per transition, J per second) are bounded the parametric
way: a cycle reaches ratio L iff  Σ (w - L·t) >= 0, and the table is built for the
threshold current at each start (a stale, lower threshold only loosens the bound).

Exponential in the bound in the worst case (many ties, flat rewards), fast when the
rewards separate walks. Up to ``limit`` optimal walks are kept; beyond it the result is
marked truncated.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .evaluate import canonical_rotation, is_primitive


@dataclass(frozen=True)
class SearchResult:
    """Open cycles (start not repeated, starting at their lowest state) whose value is at
    least ``best - tol``; ``best`` is None when nothing reached the threshold."""

    best: float | None
    cycles: list[tuple[int, ...]]
    truncated: bool


def _upper_bounds(n: int, s: int, src: np.ndarray, dst: np.ndarray, a: np.ndarray, k_max: int) -> list[np.ndarray]:
    """ub[k] for k = 0..k_max on the edges given (already restricted to states >= s)."""
    ub0 = np.full(n, -np.inf)
    ub0[s] = 0.0
    out = [ub0]
    if len(src) == 0:
        return out + [ub0] * k_max
    starts = np.flatnonzero(np.r_[True, src[1:] != src[:-1]])
    heads = src[starts]
    for _ in range(k_max):
        prev = out[-1]
        cur = prev.copy()
        cur[heads] = np.maximum(prev[heads], np.maximum.reduceat(a + prev[dst], starts))
        out.append(cur)
    return out


def bounded_search(
    n: int,
    src: np.ndarray,
    dst: np.ndarray,
    weight: np.ndarray,
    max_transitions: int,
    tol: float,
    *,
    time: np.ndarray | None = None,
    simple: bool,
    ratio: bool,
    floor: float | None = None,
    ceiling: float | None = None,
    limit: int | None = None,
) -> SearchResult:
    """Best closed walks (``simple=False``) or simple cycles (``simple=True``).

    Value = Σw (``ratio=False``) or Σw / Σt (``ratio=True``; t = 1 per edge when ``time`` is
    None). Only walks worth at least ``floor`` (default ``tol``: they must move) count;
    walks within ``tol`` of the best are all kept. Walks that repeat a shorter walk are
    skipped. ``ceiling``, a known upper bound on the value, lets the search stop once
    ``limit`` walks at that value are found. Edges must be sorted by source.
    """
    src = np.asarray(src, dtype=np.int64)
    dst = np.asarray(dst, dtype=np.int64)
    w = np.asarray(weight, dtype=np.float64)
    t = np.ones(len(w)) if time is None else np.asarray(time, dtype=np.float64)
    K = int(max_transitions)
    first = float(tol if floor is None else floor)
    lower = first
    best: float | None = None
    kept: list[tuple[float, tuple[int, ...]]] = []
    skipped_best = -np.inf
    ptr_all = np.searchsorted(src, np.arange(n + 1))
    stop = False

    def offer(value: float, cyc: tuple[int, ...]) -> None:
        nonlocal best, lower, kept, skipped_best, stop
        if value < lower:
            return
        if best is None or value > best:
            best = value
            lower = max(first, best - tol)
            kept = [kv for kv in kept if kv[0] >= lower]
        if limit is not None and len(kept) >= limit:
            skipped_best = max(skipped_best, value)
            if ceiling is not None and best >= ceiling - tol:
                stop = True
            return
        kept.append((value, cyc))

    for s in range(n):
        if stop:
            break
        lo = ptr_all[s]
        keep = dst[lo:] >= s
        e_src, e_dst, e_w, e_t = src[lo:][keep], dst[lo:][keep], w[lo:][keep], t[lo:][keep]
        if len(e_src) == 0:
            continue
        lam_tab = lower if ratio else 0.0
        a = e_w - lam_tab * e_t if ratio else e_w
        ub = _upper_bounds(n, s, e_src, e_dst, a, K)
        # can any walk from s reach the threshold?
        if not ratio and ub[K][s] < lower:
            continue
        ptr = np.searchsorted(e_src, np.arange(n + 1))
        gain = [None] + [a + ub[r - 1][e_dst] for r in range(1, K + 1)]
        slack = 1e-12 * (float(np.abs(a).max()) + 1.0) * K

        path = [s]
        on_path = np.zeros(n, dtype=bool)
        on_path[s] = True
        # frames: (node, steps left, Σw, Σt, candidate edge positions, next candidate)
        frames: list[list] = []

        def push(v: int, r: int, rw: float, rt: float) -> None:
            seg = slice(ptr[v], ptr[v + 1])
            g = gain[r][seg]
            if ratio:  # Σ(w - lower·t) over the finished cycle <= rw - lower·rt + g, as lam_tab <= lower
                cand = np.flatnonzero(rw - lower * rt + g >= -slack)
            else:
                cand = np.flatnonzero(rw + g >= lower)
            cand = cand[np.argsort(-g[cand], kind="stable")] + ptr[v]
            frames.append([v, r, rw, rt, cand.tolist(), 0])

        push(s, K, 0.0, 0.0)
        while frames and not stop:
            fr = frames[-1]
            v, r, rw, rt, cand, i = fr
            if i >= len(cand):
                frames.pop()
                if frames:
                    on_path[path.pop()] = False
                continue
            fr[5] = i + 1
            e = cand[i]
            u = int(e_dst[e])
            nw, nt = rw + float(e_w[e]), rt + float(e_t[e])
            # re-check against the current threshold (it may have risen since the push)
            if ratio:
                if nw - lower * nt + float(ub[r - 1][u]) < -slack:
                    continue
            elif nw + float(ub[r - 1][u]) < lower:
                continue
            if u == s:
                cyc = tuple(path)
                value = nw / nt if ratio else nw
                if value >= lower and (simple or (is_primitive(cyc) and canonical_rotation(cyc) == cyc)):
                    offer(value, cyc)
                if simple or r - 1 < 2:
                    continue
            elif simple and on_path[u]:
                continue
            if r - 1 < 1:
                continue
            path.append(u)
            on_path[u] = simple
            push(u, r - 1, nw, nt)

    final = [c for val, c in kept if val >= lower]
    truncated = bool(skipped_best >= lower)
    return SearchResult(best, final, truncated)
