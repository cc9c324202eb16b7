"""All optimal simple cycles of a cycle-ratio problem: the critical subgraph.

Given λ* (from Howard) and potentials x with x[u] >= w - λ*·t + x[v] on every edge among
the nodes whose best reachable ratio is λ*, a cycle C there has Σ_C (w - λ* t) <= 0 with
equality iff every edge of C is *tight* (x[u] = w - λ* t + x[v]). So the optimal cycles
are exactly the simple cycles of the subgraph of tight edges, listed by Johnson.

Howard's own potentials satisfy the inequality; to be safe against rounding (and against
λ* being recomputed exactly from one optimal cycle) they are re-relaxed Bellman-Ford style
on that node set before the tight edges are taken. Nodes that cannot be on a cycle of the
tight subgraph (no tight in- or out-edge) are peeled off with vectorised rounds before the
pure-Python cycle search sees the rest. When the tight subgraph is large (a flat table:
thousands of equal cycles), the short cycles are listed first, so that a truncated answer
holds short gaits rather than a few enormous ones.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .cycles import Adjacency, short_cycles, simple_cycles
from .howard import HowardSolution
from .result import MAX_LISTED_STATES


#: Tight subgraphs with more edges than this list their cycles of at most
#: SHORT_FIRST_LENGTH transitions first (then Johnson, only if those were not too many).
SHORT_FIRST_EDGES = 5_000
SHORT_FIRST_LENGTH = 6


@dataclass(frozen=True)
class CriticalCycles:
    value: float                      # λ*, computed exactly from one optimal cycle
    cycles: list[tuple[int, ...]]     # open simple cycles, each starting at its lowest node
    truncated: bool
    edges: np.ndarray                 # positions (in the input edge arrays) of the tight edges
    graph: Adjacency                  # the tight edges that can lie on a cycle, as adjacency


def policy_cycle(sol: HowardSolution, dst: np.ndarray) -> list[int]:
    """Edge positions of the policy cycle reached from the node with the largest η."""
    v = int(np.argmax(sol.eta))
    seen: dict[int, int] = {}
    order: list[int] = []
    while v not in seen:
        seen[v] = len(order)
        e = int(sol.policy[v])
        order.append(e)
        v = int(dst[e])
    return order[seen[v]:]


def critical_cycles(
    n: int,
    src: np.ndarray,
    dst: np.ndarray,
    w: np.ndarray,
    t: np.ndarray,
    sol: HowardSolution,
    edge_tol: float,
    ratio_tol: float,
    limit: int | None,
) -> CriticalCycles:
    """The simple cycles whose ratio Σw/Σt is λ* (within the tolerances)."""
    cyc_edges = policy_cycle(sol, dst)
    lam = math.fsum(w[cyc_edges].tolist()) / math.fsum(t[cyc_edges].tolist())

    node_ok = np.isfinite(sol.eta) & (sol.eta >= lam - ratio_tol)
    sel = np.flatnonzero(node_ok[src] & node_ok[dst])
    es, ed = src[sel], dst[sel]
    a = w[sel] - lam * t[sel]
    # Potentials of the subgraph, from zero: x[u] >= a + x[v] on every edge (then a cycle is
    # tight on every edge iff its Σa is 0). Not Howard's own potentials: a penalty edge
    # (-1e9) elsewhere in the table put them near 6e9, where one ulp is 1e-6, above the
    # tolerance, and no edge was tight: rate answered "no gait" (tests/test_gait_oracle.py).
    x = np.zeros(n)
    # Bellman-Ford: raise x[u] to max(a + x[v]) until it holds on every edge.
    if len(sel):
        starts = np.flatnonzero(np.r_[True, es[1:] != es[:-1]])
        heads = es[starts]
        for _ in range(n + 1):  # from zero, without a positive cycle: at most n rounds
            best = np.maximum.reduceat(a + x[ed], starts)
            gap = best - x[heads]
            if not (gap > 0).any():
                break
            x[heads] = np.maximum(x[heads], best)
    slack = x[es] - a - x[ed]
    tight = slack <= edge_tol
    es, ed, pos = es[tight], ed[tight], sel[tight]

    # peel nodes with no tight in- or out-edge (cannot lie on a tight cycle)
    alive = np.ones(len(es), dtype=bool)
    for _ in range(64):
        outdeg = np.bincount(es[alive], minlength=n)
        indeg = np.bincount(ed[alive], minlength=n)
        ok = (outdeg > 0) & (indeg > 0)
        new_alive = alive & ok[es] & ok[ed]
        if new_alive.sum() == alive.sum():
            break
        alive = new_alive
    es, ed, pos = es[alive], ed[alive], pos[alive]

    adj: dict[int, list[int]] = {int(v): [] for v in np.unique(np.r_[es, ed])}
    for u, v in zip(es.tolist(), ed.tolist()):
        adj[u].append(v)
    if len(es) > SHORT_FIRST_EDGES:
        # a large tight subgraph usually means a flat table with a flood of ties: list the
        # short ones first, so that a truncated answer holds the most useful gaits
        short, truncated = short_cycles(adj, SHORT_FIRST_LENGTH, limit, MAX_LISTED_STATES)
        if truncated:
            return CriticalCycles(lam, short, True, pos, adj)
    cycles, truncated = simple_cycles(adj, limit, MAX_LISTED_STATES)
    return CriticalCycles(lam, cycles, truncated, pos, adj)
