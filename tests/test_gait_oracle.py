"""optimal_gaits against the brute-force oracle on random small tables.

Every objective and direction, with and without a bound: the optimum, the COMPLETE set of
ties, and their canonical rotations must match a listing of every closed walk.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from proleg.gait import RELATIVE_TOLERANCE, optimal_gaits
from proleg.gait.bruteforce import brute_force_gaits
from proleg.gait.result import speed_scale
from proleg.gait.evaluate import canonical_rotation, is_primitive
from proleg.transitions import TransitionTable

LEVELS = [(2,), (3,), (2, 2), (4,), (5,), (3, 2), (2, 3), (6,)]

integer_rewards = st.integers(-3, 3).map(float)
real_rewards = st.floats(-5, 5, allow_nan=False, allow_infinity=False).map(lambda v: round(v, 3))


@st.composite
def tables(draw, max_states: int = 6, durations: bool = True):
    levels = draw(st.sampled_from([lv for lv in LEVELS if int(np.prod(lv)) <= max_states]))
    n = int(np.prod(levels))
    values = draw(st.sampled_from([integer_rewards, real_rewards]))
    reward = np.array(draw(st.lists(values, min_size=n * n, max_size=n * n))).reshape(n, n)
    density = draw(st.sampled_from([0.4, 0.7, 1.0]))
    allowed = np.array(draw(st.lists(st.floats(0, 1), min_size=n * n, max_size=n * n))).reshape(n, n) < density
    dur = None
    if durations and draw(st.booleans()):
        dur_values = st.sampled_from([0.5, 1.0, 2.0, 3.0]) if draw(st.booleans()) else st.floats(0.1, 4.0)
        dur = np.array(draw(st.lists(dur_values, min_size=n * n, max_size=n * n))).reshape(n, n)
    return TransitionTable.from_dense(levels, reward, allowed, dur)


def assert_matches_oracle(table: TransitionTable, objective: str, direction: str, bound: int | None) -> None:
    result = optimal_gaits(table, objective, direction, bound)
    value, ties = brute_force_gaits(table, objective, direction, bound)
    got = [g.states for g in result.gaits]
    scale = float(np.abs(table.reward).max()) if table.n_transitions else 0.0
    if objective == "speed" and table.n_transitions:
        scale = speed_scale(table.reward, table.duration)
    if value is None:
        assert result.value is None and got == [], (objective, direction, bound, result)
        return
    assert result.value is not None
    assert abs(result.value - value) <= 2 * RELATIVE_TOLERANCE * scale + 1e-12
    assert set(got) == ties, (objective, direction, bound, sorted(ties), got)
    assert_ranked(result, scale)
    assert not result.truncated
    for g in result.gaits:
        cyc = g.states[:-1]
        assert g.states[0] == g.states[-1]
        assert canonical_rotation(cyc) == cyc and is_primitive(cyc)
        assert g.transitions == len(cyc)
        assert (g.reward > 0) == (direction == "+x")
        if objective != "total":
            assert len(set(cyc)) == len(cyc), "rate and speed rank simple cycles"
            assert g.repeats == 1
        else:  # the walk repeated as often as it fits in the bound is the walk it stands for
            assert g.repeats == result.max_transitions // g.transitions
            assert g.total == g.reward * g.repeats


def assert_ranked(result, scale: float) -> None:
    """Gait 0 first: best rate in the direction, then fewest transitions, then states."""
    sign = 1.0 if result.direction == "+x" else -1.0
    tol = 2 * RELATIVE_TOLERANCE * scale + 1e-12
    for a, b in zip(result.gaits, result.gaits[1:]):
        assert sign * a.rate >= sign * b.rate - tol, ("rate first", a, b)
        if abs(a.rate - b.rate) <= tol / 2:
            assert (a.transitions, a.states) < (b.transitions, b.states), ("then fewest transitions", a, b)


@settings(max_examples=500, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(table=tables(), direction=st.sampled_from(["+x", "-x"]), bound=st.sampled_from([None, 2, 3, 4, 5]))
def test_total_finds_the_best_closed_walks_and_every_tie(table, direction, bound):
    assert_matches_oracle(table, "total", direction, bound)


@settings(max_examples=500, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(table=tables(), direction=st.sampled_from(["+x", "-x"]), bound=st.sampled_from([None, 2, 3, 4, 5]))
def test_rate_finds_the_best_simple_cycles_and_every_tie(table, direction, bound):
    assert_matches_oracle(table, "rate", direction, bound)


@settings(max_examples=500, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(table=tables(), direction=st.sampled_from(["+x", "-x"]), bound=st.sampled_from([None, 2, 3, 4]))
def test_speed_finds_the_best_simple_cycles_per_second_and_every_tie(table, direction, bound):
    if table.duration is None:
        table = TransitionTable(table.levels, table.src, table.dst, table.reward, np.full(table.n_transitions, 1.5))
    assert_matches_oracle(table, "speed", direction, bound)


def test_a_repeated_short_cycle_beats_a_longer_walk_and_ranks_first():
    # 0 <-> 1 earns 2 per pass (2 transitions); 0 -> 1 -> 2 -> 0 earns 3 (3 transitions).
    # Within 4 transitions the short cycle run twice (J = 4) beats the triangle (J = 3);
    # within 3 the triangle wins; within 6 they tie at 6 and the short cycle (rate 1) ranks
    # before the triangle (rate 1, more transitions).
    reward = np.array([[0, 1, 0], [1, 0, 1], [1, 0, 0]], dtype=float)
    allowed = np.array([[0, 1, 0], [1, 0, 1], [1, 0, 0]], dtype=bool)
    t = TransitionTable.from_dense((3,), reward, allowed)
    four = optimal_gaits(t, "total", "+x", 4)
    assert (four.value, [(g.states, g.repeats) for g in four.gaits]) == (4.0, [((0, 1, 0), 2)])
    three = optimal_gaits(t, "total", "+x", 3)
    assert (three.value, [g.states for g in three.gaits]) == (3.0, [(0, 1, 2, 0)])
    six = optimal_gaits(t, "total", "+x", 6)
    assert six.value == 6.0
    assert [(g.states, g.repeats) for g in six.gaits] == [((0, 1, 0), 3), ((0, 1, 2, 0), 2)]
    assert brute_force_gaits(t, "total", "+x", 6) == (6.0, {(0, 1, 0), (0, 1, 2, 0)})


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    n=st.integers(5, 7),
    seed=st.integers(0, 2**32 - 1),
    direction=st.sampled_from(["+x", "-x"]),
    bound=st.sampled_from([None, 2, 3, 4]),
)
def test_flat_rewards_with_many_ties_list_all_of_them(n, seed, direction, bound):
    # rewards in {-1, 0, 1}: many equal cycles, the hardest case for a complete tie set
    rng = np.random.default_rng(seed)
    table = TransitionTable.from_dense((n,), rng.integers(-1, 2, (n, n)), rng.random((n, n)) < 0.8)
    assert_matches_oracle(table, "rate", direction, bound)
    assert_matches_oracle(table, "total", direction, min(bound or 4, 4))


def test_one_very_short_transition_does_not_hide_every_speed():
    """R1 with one transition of 1 ns and the rest 1 s: the speed objective answered "no
    gait" both ways (its tolerance was the largest |w/t| of one transition, 1e9 × 1e-9)."""
    from proleg.robot import load_robot

    r1 = load_robot(Path(__file__).resolve().parents[1] / "robots" / "paper-r1.toml").transitions
    dur = np.ones(r1.n_transitions)
    dur[r1.lookup(r1.index("00"), r1.index("10"))] = 1e-9
    table = TransitionTable(r1.levels, r1.src, r1.dst, r1.reward, dur)
    for direction in ("+x", "-x"):
        assert optimal_gaits(table, "speed", direction).value is not None
        assert_matches_oracle(table, "speed", direction, None)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(table=tables(durations=False), direction=st.sampled_from(["+x", "-x"]), objective=st.sampled_from(["total", "rate"]),
       bound=st.sampled_from([None, 2, 3, 4]), pick=st.integers(0, 10_000))
def test_a_penalty_no_walk_can_afford_changes_nothing(table, direction, objective, bound, pick):
    """One transition made a penalty of 1e9 against the direction: no walk that moves that way
    can use it, so the answer is the table's without that transition. The tie tolerance was
    1e-9 of the largest |reward|: with the penalty every J within 1 tied (R1 with 11->00 at
    -1e9 listed J = 2 gaits as optimal beside J = 3), and rate found no gait at all."""
    if table.n_transitions < 2:
        return
    k = pick % table.n_transitions
    sign = 1.0 if direction == "+x" else -1.0
    reward = table.reward.copy()
    reward[k] = -sign * 1e9
    penalised = TransitionTable(table.levels, table.src, table.dst, reward)
    keep = np.arange(table.n_transitions) != k
    without = TransitionTable(table.levels, table.src[keep], table.dst[keep], table.reward[keep])
    got, want = optimal_gaits(penalised, objective, direction, bound), optimal_gaits(without, objective, direction, bound)
    assert (got.value is None) == (want.value is None), (got, want)
    if want.value is not None:
        assert abs(got.value - want.value) <= 1e-9 * max(1.0, abs(want.value))
        assert [g.states for g in got.gaits] == [g.states for g in want.gaits]


def test_rate_finds_its_cycle_beside_a_penalty_edge_that_lifts_howards_potentials():
    """Found by the property above: one reward of 1.672 among zeros, and a penalty of -1e9 on
    0 -> 1. Howard's potentials came out near 6e9, where one ulp (1e-6) is above the tie
    tolerance, so no edge of the optimal cycle counted as tight and rate answered "no gait"
    (the critical subgraph now takes potentials of its own, from zero)."""
    src = np.array([0, 0, 0, 0, 0, 1, 1, 1, 1, 1, 2, 2, 2, 2, 2, 4, 4, 4, 4, 5, 5])
    dst = np.array([1, 2, 3, 4, 5, 0, 2, 3, 4, 5, 0, 1, 3, 4, 5, 1, 2, 3, 5, 3, 4])
    reward = np.zeros(len(src))
    reward[4] = 1.672  # 0 -> 5
    penalised = reward.copy()
    penalised[0] = -1e9  # 0 -> 1
    got = optimal_gaits(TransitionTable((3, 2), src, dst, penalised), "rate", "+x")
    assert got.value is not None and abs(got.value - 1.672 / 4) < 1e-12
    assert [g.states for g in got.gaits] == [(0, 5, 4, 1, 0), (0, 5, 4, 2, 0)]


def test_r1_with_a_penalty_of_1e9_has_one_optimal_gait_and_a_rate():
    from proleg.robot import load_robot

    r1 = load_robot(Path(__file__).resolve().parents[1] / "robots" / "paper-r1.toml").transitions
    reward = r1.reward.copy()
    reward[r1.lookup(r1.index("11"), r1.index("00"))] = -1e9
    table = TransitionTable(r1.levels, r1.src, r1.dst, reward)
    total = optimal_gaits(table, "total", "+x", 4)
    assert total.value == 3.0 and [r1.label(s) for s in total.gaits[0].states] == ["00", "10", "11", "01", "00"]
    assert len(total.gaits) == 1
    assert optimal_gaits(table, "rate", "+x").value == 0.75
