"""The ``total`` engine's parts: max-plus powers, the large-graph branch-and-bound, lazy ties."""

from __future__ import annotations

from unittest import mock

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from proleg.gait import MAX_TIES, optimal_gaits
from proleg.gait.bruteforce import brute_force_gaits
from proleg.gait.maxplus import ClosingBound, Graph, powers, walk_bounds
from proleg.transitions import TransitionTable
from test_gait_oracle import assert_matches_oracle, tables


def naive_power(reward: np.ndarray, allowed: np.ndarray, r: int) -> np.ndarray:
    a = np.where(allowed, reward, -np.inf)
    np.fill_diagonal(a, -np.inf)
    p = np.full(a.shape, -np.inf)
    np.fill_diagonal(p, 0.0)
    for _ in range(r):
        p = np.max(a[:, :, None] + p[None, :, :], axis=1)
    return p


@settings(max_examples=100, deadline=None)
@given(table=tables(durations=False), r=st.integers(0, 5))
def test_maxplus_powers_are_the_best_walks_of_exactly_r_transitions(table, r):
    reward, allowed = table.dense()
    np.fill_diagonal(allowed, False)
    g = Graph.from_edges(table.n_states, table.src, table.dst, table.reward)
    np.testing.assert_allclose(powers(g, r)[r], naive_power(reward, allowed, r), rtol=1e-12)
    out_ub, in_ub = walk_bounds(g, r)
    p = naive_power(reward, allowed, r)
    np.testing.assert_allclose(out_ub[r], p.max(axis=1))
    np.testing.assert_allclose(in_ub[r], p.max(axis=0))


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(table=tables(), direction=st.sampled_from(["+x", "-x"]), bound=st.sampled_from([None, 2, 3, 4, 5]))
def test_total_without_the_full_powers_finds_the_same_optimum_and_ties(table, direction, bound):
    # large robots do not fit the full powers: the branch-and-bound over walk bounds runs
    with mock.patch("proleg.gait.maxplus.EXACT_ENTRIES", 0):
        assert not ClosingBound(Graph.from_edges(2, [0], [1], [1.0]), 2).exact
        assert_matches_oracle(table, "total", direction, bound)


def test_flat_rewards_list_ties_lazily_up_to_the_cap_best_ranked_first():
    # every transition worth 1 on 16 fully connected states: every closed walk of 8 ties
    # (2-cycles run 4 times, 4-walks twice, 8-walks once): far more than MAX_TIES
    n = 16
    t = TransitionTable.from_dense((n,), np.ones((n, n)))
    result = optimal_gaits(t, "total", "+x", max_transitions=8)
    assert result.value == 8.0 and result.truncated and len(result.gaits) == MAX_TIES
    two_cycles = [g for g in result.gaits if g.transitions == 2]
    assert len(two_cycles) == n * (n - 1) // 2 and all(g.repeats == 4 for g in two_cycles)
    assert result.gaits[: len(two_cycles)] == tuple(two_cycles)  # fewest transitions first
    assert result.gaits[len(two_cycles)].transitions == 4
    assert all(g.total == 8.0 for g in result.gaits)


def test_odd_bounds_leave_a_remainder_and_the_oracle_agrees():
    # 0 <-> 1 worth 3 per pass; bound 5: two passes (4 transitions) fit, J = 6
    t = TransitionTable.from_dense((3,), np.array([[0, 2, 0], [1, 0, 0], [0, 0, 0]]), np.array(
        [[0, 1, 0], [1, 0, 1], [1, 1, 0]], dtype=bool))
    result = optimal_gaits(t, "total", "+x", 5)
    assert (result.value, result.gaits[0].states, result.gaits[0].repeats) == (6.0, (0, 1, 0), 2)
    assert brute_force_gaits(t, "total", "+x", 5) == (6.0, {(0, 1, 0)})


def test_a_search_still_running_after_slow_s_says_so_once():
    """A 625-state robot searched 12 minutes without a word (it looked hung); now the search
    says, once, what it is doing and what makes it faster. The answer is unchanged."""
    import logging

    import proleg.gait.total as total

    said: list[str] = []
    handler = logging.Handler()
    handler.emit = lambda record: said.append(record.getMessage())  # type: ignore[method-assign]
    logger = logging.getLogger(total.__name__)  # the CLI's "proleg" logger may not propagate: listen here
    logger.addHandler(handler)
    try:
        n = 16
        t = TransitionTable.from_dense((n,), np.ones((n, n)))
        quick = optimal_gaits(t, "total", "+x", max_transitions=8)
        assert said == []
        with mock.patch.object(total, "SLOW_S", 0.0):
            slow = optimal_gaits(t, "total", "+x", max_transitions=8)
    finally:
        logger.removeHandler(handler)
    assert said == ["gait search: 16 states, 240 allowed transitions, gaits of up to 8 transitions: still "
                    "searching (the search grows with the gait length: a smaller --max-transitions or [gaits] "
                    "max_transitions is faster)"]
    assert (slow.value, slow.gaits) == (quick.value, quick.gaits)


tied_rewards = st.sampled_from([-1.0, 0.0, 1.0, 2.0])


@st.composite
def tied_tables(draw):
    n = draw(st.integers(3, 6))
    reward = np.array(draw(st.lists(tied_rewards, min_size=n * n, max_size=n * n))).reshape(n, n)
    allowed = np.array(draw(st.lists(st.booleans(), min_size=n * n, max_size=n * n))).reshape(n, n)
    return TransitionTable.from_dense((n,), reward, allowed | draw(st.sampled_from([False, True])))


def _value_search_yields_only_better_walks(monkeypatch_target):
    """Wrap total._closed_walks: in the value search (raise_threshold) every block it yields
    must beat every block before it; a block no better is a walk the search had no use for."""
    import proleg.gait.total as total

    real = total._closed_walks

    def checked(g, bound, L, threshold, slack, *, raise_threshold, slow=None):
        for walks, weights in real(g, bound, L, threshold, slack, raise_threshold=raise_threshold, slow=slow):
            if raise_threshold:
                best = monkeypatch_target.get("best")
                assert best is None or float(weights.max()) > best, (L, best, weights.max())
                monkeypatch_target["best"] = float(weights.max())
            yield walks, weights

    return checked


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(table=tied_tables(), direction=st.sampled_from(["+x", "-x"]), bound=st.sampled_from([None, 2, 3, 4, 5]))
def test_the_value_search_stops_listing_walks_once_one_is_found_and_agrees_with_the_oracle(table, direction, bound):
    # 256 states, any transition, rewards -3..3 (every bound reached by some walk): the value
    # search listed every walk of 16 transitions worth the best after the first had proved it,
    # and `proleg gait` / `proleg build` ran for ever. Tied rewards make the same shape small
    # (and small blocks of the depth-first search, many of them).
    import proleg.gait.total as total

    seen: dict[str, float] = {}
    with mock.patch("proleg.gait.maxplus.EXACT_ENTRIES", 0), mock.patch.object(total, "_EXPAND", 4), \
            mock.patch.object(total, "_closed_walks", _value_search_yields_only_better_walks(seen)):
        assert_matches_oracle(table, "total", direction, bound)


def test_flat_rewards_too_many_for_the_full_powers_find_the_optimum_with_one_walk():
    import proleg.gait.total as total

    n = 10
    t = TransitionTable.from_dense((n,), np.ones((n, n)))
    seen: dict[str, float] = {}
    with mock.patch("proleg.gait.maxplus.EXACT_ENTRIES", 0), \
            mock.patch.object(total, "_closed_walks", _value_search_yields_only_better_walks(seen)):
        result = optimal_gaits(t, "total", "+x", max_transitions=8)
    assert result.value == 8.0 and seen["best"] == 8.0
