"""optimal_gaits: argument checking, defaults, truncation, and larger tables."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from proleg.errors import GaitError
from proleg.gait import MAX_TIES, GaitResult, evaluate_sequence, optimal_gaits
from proleg.gait.karp import max_cycle_mean
from proleg.transitions import TransitionTable


def complete(n: int, reward: float = 1.0) -> TransitionTable:
    return TransitionTable.from_dense((n,), np.full((n, n), reward))


def hypercube(bits: int, seed: int) -> TransitionTable:
    n = 1 << bits
    v = np.repeat(np.arange(n), bits)
    d = v ^ (1 << np.tile(np.arange(bits), n))
    rng = np.random.default_rng(seed)
    return TransitionTable.from_edges((2,) * bits, v, d, rng.integers(-9, 10, len(v)))


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"objective": "fastest"}, "objective 'fastest' is not one of total, rate, speed"),
        ({"direction": "+y"}, r"direction '\+y' is not one of"),
        ({"max_transitions": 0}, "max_transitions must be at least 1"),
        ({"max_transitions": 2.5}, "max_transitions must be a whole number"),
        ({"objective": "speed"}, "needs per-transition durations"),
    ],
)
def test_bad_requests_raise_gait_error(kwargs, message):
    with pytest.raises(GaitError, match=message):
        optimal_gaits(complete(4), **kwargs)


def test_total_on_more_than_16_states_needs_an_explicit_bound():
    big = complete(17)
    with pytest.raises(GaitError, match="needs an explicit max_transitions"):
        optimal_gaits(big, "total")
    assert optimal_gaits(big, "total", max_transitions=2).value == 2.0


def test_default_bound_for_total_is_the_number_of_states_and_is_reported():
    result = optimal_gaits(complete(3), "total")
    assert isinstance(result, GaitResult) and result.max_transitions == 3
    assert optimal_gaits(complete(3), "rate").max_transitions is None


def test_one_transition_and_empty_tables_have_no_gait():
    assert optimal_gaits(complete(4), "total", max_transitions=1).value is None
    empty = TransitionTable.from_dense((2,), np.zeros((2, 2)), np.zeros((2, 2), bool))
    for objective in ("total", "rate"):
        assert optimal_gaits(empty, objective) == GaitResult("+x", objective, 2 if objective == "total" else None, None, ())


def test_too_many_ties_are_truncated_and_flagged():
    # complete graph on 9 states, every transition worth 1: 62,227 simple cycles of rate 1
    result = optimal_gaits(complete(9), "rate")
    assert result.value == 1.0 and result.truncated and len(result.gaits) == MAX_TIES
    assert len({g.states for g in result.gaits}) == MAX_TIES


def test_bounded_ties_are_complete_even_when_the_unbounded_listing_was_truncated():
    # ties of at most 3 transitions: C(9,2) two-cycles + 2*C(9,3) three-cycles = 36 + 168
    result = optimal_gaits(complete(9), "rate", max_transitions=3)
    assert result.value == 1.0 and not result.truncated
    assert len(result.gaits) == math.comb(9, 2) + 2 * math.comb(9, 3)


def test_bounded_rate_below_every_optimal_cycle_length_searches_exactly():
    # a ring 0->1->...->5->0 worth 1 per step (rate 1, 6 transitions) and 2-cycles worth 0.5
    n = 6
    reward = np.zeros((n, n))
    allowed = np.zeros((n, n), bool)
    for i in range(n):
        reward[i, (i + 1) % n] = 1.0
        allowed[i, (i + 1) % n] = True
        allowed[(i + 1) % n, i] = True
        reward[(i + 1) % n, i] = -0.5
    t = TransitionTable.from_dense((n,), reward, allowed)
    assert optimal_gaits(t, "rate").value == 1.0
    bounded = optimal_gaits(t, "rate", max_transitions=5)
    assert bounded.value == 0.25 and len(bounded.gaits) == n


def test_speed_divides_by_seconds():
    # 0->1->0 worth 2 in 4 s; 0->2->0 worth 1 in 1 s: faster although it moves less
    reward = np.array([[0, 1, 0.5], [1, 0, 0], [0.5, 0, 0]])
    allowed = np.array([[0, 1, 1], [1, 0, 0], [1, 0, 0]], bool)
    dur = np.array([[1, 2, 0.5], [2, 1, 1], [0.5, 1, 1]])
    t = TransitionTable.from_dense((3,), reward, allowed, dur)
    assert [g.states for g in optimal_gaits(t, "total").gaits] == [(0, 1, 0)]
    speed = optimal_gaits(t, "speed")
    assert speed.value == 1.0 and [g.states for g in speed.gaits] == [(0, 2, 0)]
    assert speed.gaits[0].duration == 1.0


def test_multi_level_limbs_use_the_mixed_radix_state_space():
    rng = np.random.default_rng(3)
    t = TransitionTable.from_dense((3, 2), rng.integers(-3, 4, (6, 6)))
    for objective in ("total", "rate"):
        result = optimal_gaits(t, objective)
        for g in result.gaits:
            # one pass of the gait, as typed; ``total`` also says how many passes it counts
            assert replace(evaluate_sequence(t, [t.label(s) for s in g.states]), repeats=g.repeats) == g
            assert g.repeats == (6 // g.transitions if objective == "total" else 1)


@pytest.mark.parametrize("seed", range(3))
def test_rate_on_a_1024_state_hypercube_agrees_with_karp(seed):
    t = hypercube(10, seed)
    result = optimal_gaits(t, "rate")
    assert math.isclose(result.value, max_cycle_mean(t.n_states, t.src, t.dst, t.reward))
    for g in result.gaits:
        assert evaluate_sequence(t, g.states) == g and math.isclose(g.rate, result.value)
    minus = optimal_gaits(t, "rate", "-x")
    assert math.isclose(minus.value, -max_cycle_mean(t.n_states, t.src, t.dst, -t.reward))


def test_total_on_64_dense_states_with_6_transitions_keeps_every_tie():
    rng = np.random.default_rng(0)
    t = TransitionTable.from_dense((2,) * 6, rng.integers(-5, 6, (64, 64)))
    result = optimal_gaits(t, "total", max_transitions=6)
    assert result.gaits and all(g.total == result.value and g.transitions * g.repeats <= 6 for g in result.gaits)
    # 2-cycles worth 10 run three times tie with primitive 6-transition walks worth 30; the
    # repeated 2-cycles have no more transitions and rank first
    assert result.value == 3 * (t.dense()[0] + t.dense()[0].T)[~np.eye(64, dtype=bool)].max() == 30
    assert [g.transitions for g in result.gaits] == sorted(g.transitions for g in result.gaits)
    # a walk of 6 transitions is worth at most 6 times the best transition
    assert result.value <= 6 * t.reward.max()
    short = optimal_gaits(t, "total", max_transitions=2)
    top2 = (t.dense()[0] + t.dense()[0].T)[~np.eye(64, dtype=bool)].max()
    assert short.value == top2


def test_ties_in_several_components_are_all_found():
    # Three strongly connected parts joined one way: A -> B -> C.
    # A = {0,1,2}: 0->1->2->0 worth 3 each (rate 3), B = {3,4}: 3->4->3 worth 3+3 (rate 3),
    # C = {5,6,7}: 5->6->7->5 worth 1+1+3 (rate 5/3) and 5->7->5 worth 3+3 (rate 3).
    # Every part has a rate-3 cycle; the potentials must be right in each, or a tie is lost.
    edges = {
        (0, 1): 3, (1, 2): 3, (2, 0): 3, (1, 0): -5,
        (2, 3): 7,
        (3, 4): 3, (4, 3): 3,
        (4, 5): -9,
        (5, 6): 1, (6, 7): 1, (5, 7): 3, (7, 5): 3,
    }
    src, dst = zip(*edges)
    t = TransitionTable.from_edges((8,), src, dst, list(edges.values()))
    result = optimal_gaits(t, "rate")
    assert result.value == 3.0
    # equal rates: fewest transitions first, then by states
    assert [g.states for g in result.gaits] == [(3, 4, 3), (5, 7, 5), (0, 1, 2, 0)]
    assert [g.states for g in optimal_gaits(t, "rate", max_transitions=2).gaits] == [(3, 4, 3), (5, 7, 5)]


def test_a_flat_table_with_a_flood_of_ties_lists_short_ones_quickly():
    # 1024 states, every one-limb change worth 1: every cycle of the hypercube has rate 1
    bits = 10
    n = 1 << bits
    v = np.repeat(np.arange(n), bits)
    d = v ^ (1 << np.tile(np.arange(bits), n))
    t = TransitionTable.from_edges((2,) * bits, v, d, np.ones(len(v)))
    result = optimal_gaits(t, "rate")
    assert result.value == 1.0 and result.truncated and len(result.gaits) == MAX_TIES
    assert max(g.transitions for g in result.gaits) <= 6  # the short ties come first
    bounded = optimal_gaits(t, "rate", max_transitions=2)
    assert len(bounded.gaits) == n * bits // 2 and bounded.truncated is False  # each 2-cycle once


def test_one_long_optimal_cycle_in_a_large_tight_subgraph_is_still_found():
    # a ring of 6000 states worth 1 per step, and every reverse step worth -1
    n = 6000
    a = np.arange(n)
    t = TransitionTable.from_edges((n,), np.r_[a, (a + 1) % n], np.r_[(a + 1) % n, a], np.r_[np.ones(n), -np.ones(n)])
    result = optimal_gaits(t, "rate")
    assert result.value == 1.0 and not result.truncated
    assert [g.states for g in result.gaits] == [tuple(range(n)) + (0,)]
