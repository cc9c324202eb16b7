"""Planar objectives (heading, variance weight, transition cost) against the brute-force oracle."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from proleg.errors import GaitError
from proleg.gait.bruteforce import brute_force_gaits
from proleg.gait.planar import PlanarObjective, optimal_planar_gaits, planar_scores
from proleg.transitions import PlanarRewards, TransitionTable


def planar_table(n: int, seed: int, density: float = 0.8):
    rng = np.random.default_rng(seed)
    allowed = rng.random((n, n)) < density
    np.fill_diagonal(allowed, False)
    dense = {k: rng.integers(-3, 4, (n, n)).astype(float) for k in ("dx", "dy", "dth")}
    var = {k: rng.integers(0, 3, (n, n)).astype(float) for k in ("vx", "vy", "vth")}
    src, dst = np.nonzero(allowed)
    planar = PlanarRewards(dy=dense["dy"][src, dst], dtheta_deg=dense["dth"][src, dst], var_dx=var["vx"][src, dst],
                           var_dy=var["vy"][src, dst], var_dtheta_deg=var["vth"][src, dst])
    table = TransitionTable.from_edges((n,), src, dst, dense["dx"][src, dst], None, planar)
    return table, allowed, dense, var


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    n=st.integers(2, 5),
    seed=st.integers(0, 2**32 - 1),
    heading=st.sampled_from([0.0, 90.0, 180.0, 270.0, 45.0]),
    weights=st.sampled_from([(0.0, 0.0, 0.0), (0.5, 0.5, 0.5), (1.0, 0.0, 0.25)]),
    cost=st.sampled_from([0.0, 1.0]),
    kind=st.sampled_from(["total", "rate"]),
    bound=st.sampled_from([2, 3, 4]),
)
def test_planar_gaits_match_the_oracle_on_the_dense_score_matrix(n, seed, heading, weights, cost, kind, bound):
    table, allowed, dense, var = planar_table(n, seed)
    h = math.radians(heading)
    score = (math.cos(h) * dense["dx"] + math.sin(h) * dense["dy"]
             - weights[0] * var["vx"] - weights[1] * var["vy"] - weights[2] * var["vth"] - cost)
    oracle_table = TransitionTable.from_dense((n,), score, allowed)
    value, ties = brute_force_gaits(oracle_table, kind, "+x", bound)
    result = optimal_planar_gaits(table, PlanarObjective(heading, weights, cost), kind, bound)
    if value is None:  # nothing above zero: the best of the rest is reported, marked (test_planar_objectives)
        assert result.value is None or result.below_zero
    else:
        assert result.value == pytest.approx(value, abs=1e-9)
        assert {g.states for g in result.gaits} == ties


def test_heading_180_scores_minus_x_motion_positively():
    table, *_ = planar_table(4, 7)
    np.testing.assert_allclose(planar_scores(table, PlanarObjective(180.0)), -table.reward, atol=1e-12)


def test_a_planar_objective_needs_the_statistics_it_weighs():
    t = TransitionTable.from_dense((2,), np.array([[0, 1], [1, 0]]))
    with pytest.raises(GaitError, match=r"needs \[transitions\]\.dy"):
        planar_scores(t, PlanarObjective(heading_deg=90.0))
    with pytest.raises(GaitError, match="variance weights must be >= 0"):
        planar_scores(t, PlanarObjective(variance_weight=(-1.0, 0.0, 0.0)))


def capped_oracle(table: TransitionTable, dtheta_dense: np.ndarray, score: np.ndarray, allowed, K: int, cap: float):
    """Every primitive closed walk of at most K transitions, listed; the best within the cap."""
    from proleg.gait.bruteforce import closed_walks

    scored = []
    for c in closed_walks(TransitionTable.from_dense(table.levels, score, allowed), K, simple=False):
        steps = list(zip(c, c[1:] + c[:1]))
        j = math.fsum(score[a, b] for a, b in steps)
        turn = math.fsum(dtheta_dense[a, b] for a, b in steps)
        if j > 1e-9 and abs(turn) <= cap + 1e-9:
            scored.append((j * (K // len(c)), c))
    if not scored:
        return None, set()
    best = max(v for v, _ in scored)
    return best, {c + (c[0],) for v, c in scored if v >= best - 1e-9 * np.abs(score[allowed]).max()}


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    n=st.integers(2, 5),
    seed=st.integers(0, 2**32 - 1),
    heading=st.sampled_from([0.0, 180.0, 90.0]),
    cap=st.sampled_from([0.0, 1.0, 2.0, 5.0]),
    bound=st.sampled_from([2, 3, 4]),
)
def test_the_rotation_cap_keeps_the_best_walk_that_turns_little_enough(n, seed, heading, cap, bound):
    table, allowed, dense, var = planar_table(n, seed)
    h = math.radians(heading)
    score = math.cos(h) * dense["dx"] + math.sin(h) * dense["dy"] - 0.25 * var["vx"] - 0.5
    objective = PlanarObjective(heading, (0.25, 0.0, 0.0), 0.5)
    value, ties = capped_oracle(table, dense["dth"], score, allowed, bound, cap)
    result = optimal_planar_gaits(table, objective, "total", bound, rotation_cap_deg=cap)
    if value is None:  # nothing above zero: the best of the rest is reported, marked (test_planar_objectives)
        assert result.value is None or result.below_zero
    else:
        assert result.value == pytest.approx(value, abs=1e-9)
        assert {g.states for g in result.gaits} == ties
