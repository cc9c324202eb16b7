"""The ``total`` engine's walk bounds on a large robot are kept for the states a transition
touches, not for every state: a million-state robot (six 10-level limbs) with four measured
transitions kept 2 × 109 vectors of a million floats, 1.7 GB, to find a 2-cycle. The bound
they give is the same, and still bounds every walk (max-plus powers as the oracle)."""

from __future__ import annotations

from unittest import mock

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from proleg.gait import optimal_gaits
from proleg.gait import maxplus
from proleg.gait.maxplus import ClosingBound, Graph, powers
from proleg.transitions import TransitionTable


@st.composite
def sparse_graphs(draw):
    """A few transitions among a handful of states scattered over many."""
    n = draw(st.integers(2, 60))
    k = draw(st.integers(2, min(n, 6)))
    states = draw(st.lists(st.integers(0, n - 1), min_size=k, max_size=k, unique=True))
    pairs = [(a, b) for a in states for b in states if a != b]
    edges = draw(st.lists(st.sampled_from(pairs), min_size=1, max_size=len(pairs), unique=True))
    weights = draw(st.lists(st.integers(-3, 3).map(float), min_size=len(edges), max_size=len(edges)))
    src, dst = zip(*edges)
    return Graph.from_edges(n, list(src), list(dst), weights)


@settings(max_examples=200, deadline=None)
@given(g=sparse_graphs(), r=st.integers(0, 5))
def test_the_packed_bounds_bound_every_walk_as_the_powers_say(g, r):
    exact = powers(g, r)[r]
    with mock.patch("proleg.gait.maxplus.EXACT_ENTRIES", 0):
        bound = ClosingBound(g, r)
    assert not bound.exact
    cur, start = (a.ravel() for a in np.meshgrid(np.arange(g.n), np.arange(g.n), indexing="ij"))
    got = bound(r, cur, start).reshape(g.n, g.n)
    assert np.all(got >= exact)  # an upper bound on the best walk of exactly r transitions
    if r == 1:
        np.testing.assert_array_equal(got, exact)  # one transition is looked up exactly
    if r >= 2:  # as tight as the per-state bounds: the best r-walk from v and the best one into s
        np.testing.assert_array_equal(got, np.minimum(exact.max(axis=1)[:, None], exact.max(axis=0)[None, :]))
        assert bound.closed_walk_bound(r) >= float(np.max(np.diagonal(exact), initial=-np.inf))
    touched = len(np.union1d(g.src, g.dst))
    assert all(len(v) == touched + 1 for v in bound.out_ub + bound.in_ub)  # not n


def test_a_million_states_with_four_transitions_keep_bounds_of_three_states():
    n = 10 ** 6
    src, dst, reward = np.array([0, 0, 1, 10]), np.array([1, 10, 0, 0]), np.array([1.0, -1.0, 0.5, -1.0])
    t = TransitionTable((10,) * 6, src, dst, reward)
    with mock.patch("proleg.gait.maxplus.walk_bounds", wraps=maxplus.walk_bounds) as wb:
        result = optimal_gaits(t, "total", "+x", max_transitions=108)
    assert result.value == 81.0  # 0 → 1 → 0, 1.5 a pass, 54 passes
    assert wb.called and all(call.args[0].n == 4 for call in wb.call_args_list)  # 0, 1, 10 and the row past them
    assert t.n_states == n
