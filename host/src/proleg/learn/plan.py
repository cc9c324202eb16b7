"""What to measure next: exploration plans from the estimates so far.

``extra_plan``: the fewest extra trials per transition that reach a requested CI
half-width (``estimate.extra_trials``) turned into closed tours (``tours.exploration``).
``adaptive_demand``: the adaptive scheme of ``bench/bench_learn.py`` — one more trial of each
of the transitions whose interval is widest (the top ``fraction``; transitions without a
variance first), so trials go where the matrix is least known rather than everywhere.
"""

from __future__ import annotations

import numpy as np

from .estimate import Estimates
from .tours import Exploration, exploration, strongly_connected_components


def closable(est: Estimates) -> np.ndarray:
    """Mask of transitions a closed tour can make (both ends in one strongly connected part)."""
    t = est.table
    comp = strongly_connected_components(t.n_states, list(zip(t.src.tolist(), t.dst.tolist())))
    return np.array([comp[a] == comp[b] for a, b in zip(t.src.tolist(), t.dst.tolist())], dtype=bool)


def extra_plan(est: Estimates, half_width: float, *, component: str = "dx", start: int = 0,
               seed: int | None = None) -> tuple[np.ndarray, Exploration]:
    """(extra trials per transition, tours that make them) for the requested half-width."""
    need = est.extra_trials(half_width, component)
    need = np.where(closable(est), need, 0)
    return need, exploration(est.table, demand=need, start=start, seed=seed)


def adaptive_demand(est: Estimates, fraction: float = 0.25, component: str = "dx") -> np.ndarray:
    """One trial for each transition among the widest ``fraction`` of intervals."""
    c = est.components[component]
    ok = closable(est)
    width = np.where(np.isnan(c.half_width), np.inf, c.half_width)
    width = np.where(ok, width, -np.inf)
    k = max(1, int(round(fraction * ok.sum())))
    order = np.argsort(-width, kind="stable")[:k]
    demand = np.zeros(len(width), dtype=np.int64)
    demand[order[np.isfinite(width[order]) | np.isposinf(width[order])]] = 1
    return demand
