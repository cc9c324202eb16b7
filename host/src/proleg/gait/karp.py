"""Maximum cycle mean by Karp's theorem (1978): the textbook cross-check for Howard.

With D_k(v) = the largest weight of a walk of exactly k edges ending at v (starting
anywhere, D_0 = 0 — a zero-weight super source joined to every node),

    λ* = max over v with D_n(v) > -inf of  min over 0 <= k < n of (D_n(v) - D_k(v)) / (n - k).

Time O(n·m), memory O(n²) (the whole D table is kept); fine up to a few thousand nodes.
"""

from __future__ import annotations

import numpy as np


def max_cycle_mean(n: int, src: np.ndarray, dst: np.ndarray, weight: np.ndarray) -> float | None:
    """λ* over all cycles, or None when the graph has no cycle."""
    src = np.asarray(src, dtype=np.int64)
    dst = np.asarray(dst, dtype=np.int64)
    w = np.asarray(weight, dtype=np.float64)
    if n == 0 or len(w) == 0:
        return None
    order = np.argsort(dst, kind="stable")
    s, d, ww = src[order], dst[order], w[order]
    indeg = np.bincount(d, minlength=n)
    has_in = indeg > 0
    seg = np.zeros(n, dtype=np.int64)
    np.cumsum(indeg[:-1], out=seg[1:])
    seg = seg[has_in]
    table = np.full((n + 1, n), -np.inf)
    table[0] = 0.0
    for k in range(1, n + 1):
        cand = table[k - 1][s] + ww
        row = np.full(n, -np.inf)
        row[has_in] = np.maximum.reduceat(cand, seg)
        table[k] = row
    dn = table[n]
    ok = np.isfinite(dn)
    if not ok.any():
        return None
    ks = np.arange(n)[:, None]
    with np.errstate(invalid="ignore"):
        ratios = (dn[None, ok] - table[:n, ok]) / (n - ks)
    ratios = np.where(np.isfinite(table[:n, ok]), ratios, np.inf)
    return float(ratios.min(axis=0).max())
