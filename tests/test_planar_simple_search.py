"""The simple-cycle branch and bound (gait/simple_search.py) against plain enumeration of
every simple cycle, and against the threshold search it replaced (constrained.py, levels)."""

from __future__ import annotations

import itertools

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from proleg.gait.constrained import Constraint, best_constrained
from proleg.gait.simple_search import best_simple_cycles

TOL = 1e-9


def random_graph(n: int, seed: int, density: float):
    rng = np.random.default_rng(seed)
    allowed = (rng.random((n, n)) < density) & ~np.eye(n, dtype=bool)
    src, dst = np.nonzero(allowed)
    # a few exact ties: scores on a coarse grid
    w = np.round(rng.normal(-0.2, 1.0, len(src)) * 4) / 4
    c = np.round(rng.normal(0, 6.0, len(src)))
    return src, dst, w, c


def brute(n, src, dst, w, c, K, kind, cap, accept_cap):
    """(best, sorted ties) over every simple cycle of 2..K transitions, canonical start."""
    W = {(int(a), int(b)): (float(x), float(y)) for a, b, x, y in zip(src, dst, w, c)}
    found = []
    for L in range(2, min(K, n) + 1):
        for s in range(n):
            for rest in itertools.permutations(range(s + 1, n), L - 1):
                cyc = (s,) + rest
                steps = list(zip(cyc, cyc[1:] + cyc[:1]))
                if not all(e in W for e in steps):
                    continue
                J = sum(W[e][0] for e in steps)
                turn = sum(W[e][1] for e in steps)
                if cap is not None and abs(turn) > cap:
                    continue
                if accept_cap is not None and abs(turn) > accept_cap:
                    continue
                found.append((J / L if kind == "rate" else J, cyc))
    if not found:
        return None, []
    best = max(v for v, _ in found)
    return best, sorted(cyc for v, cyc in found if v >= best - TOL)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    n=st.integers(2, 7),
    seed=st.integers(0, 10_000),
    density=st.sampled_from([0.35, 0.7, 1.0]),
    K=st.integers(2, 7),
    kind=st.sampled_from(["total", "rate"]),
    cap=st.one_of(st.none(), st.sampled_from([0.0, 3.0, 10.0])),
    accept_cap=st.one_of(st.none(), st.sampled_from([2.0, 8.0])),
)
def test_branch_and_bound_lists_exactly_the_best_simple_cycles(n, seed, density, K, kind, cap, accept_cap):
    src, dst, w, c = random_graph(n, seed, density)
    cons = [Constraint(c, -cap, cap)] if cap is not None else [Constraint(c, -1e9, 1e9)]
    accept = None if accept_cap is None else (lambda sums: np.abs(sums[:, 0]) <= accept_cap)
    want_best, want_ties = brute(n, src, dst, w, c, K, kind, cap, accept_cap)
    best, ties = best_simple_cycles(n, src, dst, w, K, kind, cons, accept, TOL)
    if want_best is None:
        assert best is None and ties == []
        return
    assert best is not None and abs(best - want_best) <= 1e-9
    assert [cyc for cyc, _ in ties] == want_ties
    assert all(k == 1 for _, k in ties)
    levels = best_constrained(n, src, dst, w, K, kind, True, cons, accept, TOL, levels=True)
    assert levels.best is not None and abs(levels.best - best) <= 1e-9
    assert levels.ties == ties


def test_a_cycle_is_never_its_own_better_completion_on_a_graph_with_a_good_two_cycle():
    """A walk bound would repeat 0↔1 (worth +10) forever; the simple-path bound knows a
    simple cycle can use it once, so the long cycles are cut and the answer is still exact."""
    n = 8
    src, dst, w = [], [], []
    for a in range(n):
        for b in range(n):
            if a != b:
                src.append(a)
                dst.append(b)
                w.append(5.0 if {a, b} == {0, 1} else -1.0)
    best, ties = best_simple_cycles(n, np.array(src), np.array(dst), np.array(w), n, "total", (), None, TOL)
    assert best == 10.0 and [c for c, _ in ties] == [(0, 1)]
