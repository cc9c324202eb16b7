"""Maximum cycle ratio by Howard's policy iteration (multichain max-plus version).

For edge weights w and positive times t, find λ* = max over cycles C of w(C) / t(C)
(t = 1 gives the maximum cycle mean). Following Cochet-Terrasson, Cohen, Gaubert,
McGettrick and Quadrat (1998), "Numerical computation of spectral elements in max-plus
algebra", and Dasdan (2004), "Experimental analysis of the fastest optimum cycle ratio
and mean algorithms":

* a *policy* picks one out-edge per node; following it from any node ends in a cycle
  (a node without out-edges keeps a virtual self-loop of ratio -B, B larger than any
  |w/t|, so policies can leave dead ends behind; η = -B is reported as -inf);
* *value determination* gives every node the ratio η of the cycle it ends in and a
  potential x with x[v] = w(π v) - η t(π v) + x[succ v] (the cycle is cut at its lowest
  node, whose potential is carried over from the previous round);
* *improvement* first moves nodes to a successor with a larger η; when none can, it moves
  nodes, inside their η class, to a successor with a larger w - η t + x. It stops when
  neither helps: then η[v] is the best ratio of a cycle reachable from v, and x satisfies
  x[u] >= w - η t + x[v] on every edge inside an η class.

Everything is vectorised over the edge arrays (sorted by source). Cycles and potentials of
the policy's functional graph are found by pointer doubling, O(n log n) per round. Nodes
with no out-edge get η = -inf. Graphs need not be strongly connected.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class HowardSolution:
    """η (best reachable cycle ratio, -inf when no cycle is reachable) and potentials x per node,
    the final policy (edge position per node, -1 for nodes without out-edges) and rounds used."""

    eta: np.ndarray
    potential: np.ndarray
    policy: np.ndarray
    iterations: int

    @property
    def value(self) -> float | None:
        best = float(self.eta.max()) if len(self.eta) else -np.inf
        return None if best == -np.inf else best


class _Segments:
    """Edges grouped by source (edges sorted by source): per-node reductions via reduceat."""

    def __init__(self, n: int, src: np.ndarray) -> None:
        deg = np.bincount(src, minlength=n)
        self.nonempty = deg > 0
        self.nodes = np.flatnonzero(self.nonempty)
        self.counts = deg[self.nonempty]
        self.starts = np.zeros(len(self.nodes), dtype=np.int64)
        np.cumsum(self.counts[:-1], out=self.starts[1:])
        self.src = src
        self.positions: np.ndarray | None = None  # arange(m), made when first needed

    def max(self, values: np.ndarray) -> np.ndarray:
        """Max of ``values`` over each non-empty node's edges (indexed like ``nodes``)."""
        return np.maximum.reduceat(values, self.starts)

    def argmax_for(self, values: np.ndarray, best: np.ndarray, which: np.ndarray) -> np.ndarray:
        """For the non-empty nodes flagged in ``which`` (indexed like ``nodes``): the first
        edge position whose value reaches that node's ``best``."""
        big = np.iinfo(np.int64).max
        if 2 * int(which.sum()) >= len(which):  # most nodes: one pass over every edge
            if self.positions is None:
                self.positions = np.arange(len(self.src))
            hit = values >= np.repeat(best, self.counts)
            return np.minimum.reduceat(np.where(hit, self.positions, big), self.starts)[which]
        counts = self.counts[which]
        offsets = np.zeros(len(counts), dtype=np.int64)
        np.cumsum(counts[:-1], out=offsets[1:])
        # edge positions of the flagged nodes only
        edges = np.repeat(self.starts[which] - offsets, counts) + np.arange(int(counts.sum()))
        hit = values[edges] >= np.repeat(best[which], counts)
        return np.minimum.reduceat(np.where(hit, edges, big), offsets)


def _doubling_rounds(n: int) -> int:
    return max(1, int(n).bit_length())


def _evaluate(
    n: int,
    succ: np.ndarray,
    cw: np.ndarray,
    ct: np.ndarray,
    x_old: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """η and x of the functional graph v -> succ[v] with edge weight cw, time ct."""
    rounds = _doubling_rounds(n)
    ar = np.arange(n)
    # low[v] = lowest node among succ^i(v), i < 2^rounds; jump = succ^(2^rounds)
    low = ar.copy()
    jump = succ.copy()
    for _ in range(rounds):
        low = np.minimum(low, low[jump])
        jump = jump[jump]
    on_cycle = np.zeros(n, dtype=bool)
    on_cycle[jump] = True  # succ^(>= n) lands on cycles, and is onto each cycle
    rep = low[jump]  # every node -> lowest node of the cycle it ends in
    cyc_nodes = np.flatnonzero(on_cycle)
    wsum = np.bincount(rep[cyc_nodes], weights=cw[cyc_nodes], minlength=n)
    tsum = np.bincount(rep[cyc_nodes], weights=ct[cyc_nodes], minlength=n)
    with np.errstate(invalid="ignore", divide="ignore"):
        eta = wsum[rep] / tsum[rep]
    # potentials: cut each cycle at its representative; x = x_old at the representative
    is_rep = rep == ar
    step = np.where(is_rep, 0.0, cw - eta * ct)
    parent = np.where(is_rep, ar, succ)
    acc = step
    for _ in range(rounds):
        acc = acc + acc[parent]
        grand = parent[parent]
        if np.array_equal(grand, parent):  # every node now points at its root
            break
        parent = grand
    return eta, acc + x_old[rep]


def max_cycle_ratio(
    n: int,
    src: np.ndarray,
    dst: np.ndarray,
    weight: np.ndarray,
    time: np.ndarray | None = None,
    max_iterations: int = 100_000,
) -> HowardSolution:
    """Howard policy iteration on edges (src sorted ascending); ``time`` None means 1 per edge."""
    src = np.asarray(src, dtype=np.int64)
    dst = np.asarray(dst, dtype=np.int64)
    w = np.asarray(weight, dtype=np.float64)
    t = np.ones(len(w)) if time is None else np.asarray(time, dtype=np.float64)
    m = len(w)
    if m > 1 and np.any(src[1:] < src[:-1]):
        raise ValueError("max_cycle_ratio needs the edges sorted by source")
    if m == 0:
        return HowardSolution(np.full(n, -np.inf), np.zeros(n), np.full(n, -1, dtype=np.int64), 0)
    seg = _Segments(n, src)
    dead = ~seg.nonempty
    ar = np.arange(n)
    unit_time = time is None
    ratio_scale = float(np.abs(w / t).max())
    dead_ratio = -(2.0 * ratio_scale + 1.0)  # the virtual self-loops of nodes without out-edges
    scale = float(np.abs(w).max() + (2.0 * ratio_scale + 1.0) * max(1.0, t.max()))
    eps = 1e-12 * scale * max(1.0, np.log2(n))

    # initial policy: the locally best ratio edge
    policy = np.zeros(n, dtype=np.int64)  # dead nodes: unused
    r0 = w / t
    policy[seg.nodes] = seg.argmax_for(r0, seg.max(r0), np.ones(len(seg.nodes), dtype=bool))
    x = np.zeros(n)
    succ = np.where(dead, ar, dst[policy])
    cw = np.where(dead, dead_ratio, w[policy])
    ct = np.where(dead, 1.0, t[policy])
    for it in range(1, max_iterations + 1):
        eta, x = _evaluate(n, succ, cw, ct, x)
        step = _improvement(seg, eta, x, dst, w, t, unit_time, eps)
        if step is None:  # no edge improves the policy: optimal
            eta = np.where(eta < 0.5 * (dead_ratio - ratio_scale), -np.inf, eta)
            return HowardSolution(eta, x, np.where(dead, -1, policy), it)
        up, chosen = step
        nodes = seg.nodes[up]
        policy[nodes] = chosen
        succ[nodes] = dst[chosen]
        cw[nodes] = w[chosen]
        ct[nodes] = t[chosen]
    raise RuntimeError(f"Howard policy iteration did not converge in {max_iterations} rounds")


def _improvement(
    seg: "_Segments", eta: np.ndarray, x: np.ndarray, dst: np.ndarray, w: np.ndarray, t: np.ndarray,
    unit_time: bool, eps: float,
) -> tuple[np.ndarray, np.ndarray] | None:
    """Howard's improvement step: (nodes that switch, as a mask over ``seg.nodes``, and their
    new edges), or None when the policy is optimal. First a better cycle ratio within reach
    (η of the successor); failing that, better potentials inside each η class."""
    eta_ne = eta[seg.nodes]
    one_class = float(eta.max() - eta.min()) <= eps  # then no node can reach a better cycle
    if not one_class:
        eta_dst = eta.take(dst)
        best = seg.max(eta_dst)
        up = best > eta_ne + eps
        if up.any():
            return up, seg.argmax_for(eta_dst, best, up)
    val = x.take(dst)
    val += w
    if one_class:
        val -= eta[0] if unit_time else eta[0] * t
    else:
        eta_src = np.repeat(eta_ne, seg.counts)
        val -= eta_src if unit_time else eta_src * t
        val[eta_dst < eta_src - eps] = -np.inf
    best = seg.max(val)
    up = best > x[seg.nodes] + eps
    if not up.any():
        return None
    return up, seg.argmax_for(val, best, up)
