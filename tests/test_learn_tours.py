"""Exploration tours: coverage, chaining, allowed transitions only, minimal balancing."""

from __future__ import annotations

import itertools
from collections import Counter
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from proleg.learn.pieces import PieceLimits, split
from proleg.learn.tours import TourError, balance, exploration
from proleg.protocol.definition import MAX_GAIT_STEPS
from proleg.robot import load_robot
from proleg.transitions import TransitionTable

ROBOTS = Path(__file__).resolve().parent.parent / "robots"


@st.composite
def tables(draw, max_states: int = 5):
    n = draw(st.integers(2, max_states))
    pairs = [(a, b) for a in range(n) for b in range(n) if a != b]
    mask = draw(st.lists(st.booleans(), min_size=len(pairs), max_size=len(pairs)))
    chosen = [p for p, m in zip(pairs, mask) if m] or [pairs[0]]
    src, dst = zip(*chosen)
    return TransitionTable.from_edges((n,), src, dst, np.zeros(len(chosen)))


def _scc_oracle(table: TransitionTable) -> dict[int, set[int]]:
    """Reachability by brute force (Floyd–Warshall on booleans)."""
    n = table.n_states
    r = np.eye(n, dtype=bool)
    r[table.src, table.dst] = True
    for k in range(n):
        r |= r[:, [k]] & r[[k], :]
    return {a: {b for b in range(n) if r[a, b] and r[b, a]} for a in range(n)}


@settings(max_examples=150, deadline=None)
@given(tables(), st.integers(1, 3), st.integers(0, 10_000))
def test_every_edge_that_a_closed_tour_can_make_is_made_at_least_r_times_and_nothing_else(table, r, seed):
    ex = exploration(table, r, seed=seed)
    scc = _scc_oracle(table)
    allowed = set(zip(table.src.tolist(), table.dst.tolist()))
    inner = {(a, b) for a, b in allowed if b in scc[a]}
    assert set(ex.uncoverable) == allowed - inner
    made = Counter()
    for tour in ex.tours:
        assert tour.states[0] == tour.states[-1]
        for a, b in tour.transitions:
            assert (a, b) in allowed
            made[(a, b)] += 1
    for e in inner:
        assert made[e] >= r
    assert sum(made.values()) == r * len(inner) + sum(t.extra for t in ex.tours)


def _balance_oracle(n: int, edges: list[tuple[int, int]], demand: list[int], bound: int = 3) -> int | None:
    best = None
    for extra in itertools.product(range(bound + 1), repeat=len(edges)):
        total = sum(extra)
        if best is not None and total >= best:
            continue
        deg = [0] * n
        for (a, b), k, x in zip(edges, demand, extra):
            deg[a] += k + x
            deg[b] -= k + x
        if not any(deg):
            best = total
    return best


@settings(max_examples=120, deadline=None)
@given(tables(max_states=4), st.integers(0, 10_000))
def test_balancing_adds_the_fewest_transitions_of_any_balancing(table, seed):
    edges = list(zip(table.src.tolist(), table.dst.tolist()))
    if len(edges) > 6:
        edges = edges[:6]
    scc = _scc_oracle(TransitionTable.from_edges(table.levels, *zip(*edges), np.zeros(len(edges))))
    if any(b not in scc[a] for a, b in edges):
        return  # balancing exists only inside a strongly connected part
    rng = np.random.default_rng(seed)
    demand = rng.integers(1, 3, len(edges)).tolist()
    extra = balance(table.n_states, edges, demand)
    oracle = _balance_oracle(table.n_states, edges, demand, bound=4)
    if oracle is None:  # every balancing needs more than 4 copies of some edge
        assert max(extra) > 4
    else:
        assert sum(extra) == oracle
    deg = Counter()
    for (a, b), k, x in zip(edges, demand, extra):
        deg[a] += k + x
        deg[b] -= k + x
    assert not any(deg.values())


@settings(max_examples=100, deadline=None)
@given(tables(), st.integers(1, 3), st.integers(1, 8), st.floats(0.5, 20), st.integers(0, 1000))
def test_pieces_chain_stay_within_limits_and_are_loadable_when_they_say_so(table, r, k, on, seed):
    ex = exploration(table, r, seed=seed)
    limits = PieceLimits(max_transitions=k, max_on_s=on, rest_s=2.0, default_duration_s=1.0)
    for tour in ex.tours:
        pieces = split(table, tour.states, limits)
        assert [s for p in pieces for s in p.states[:-1]] + [pieces[-1].states[-1]] == list(tour.states)
        for p, q in zip(pieces, pieces[1:]):
            assert p.states[-1] == q.states[0]
            assert p.rest_after_s == 2.0
        assert pieces[-1].rest_after_s == 0.0
        for p in pieces:
            assert 1 <= len(p.transitions) <= k
            assert len(p.transitions) == 1 or p.est_time_s <= on
            if p.loadable:
                g = p.gait()
                assert 2 <= len(g) <= MAX_GAIT_STEPS
                assert all(table.lookup(a, b) is not None for a, b in zip(g, g[1:] + g[:1]))


def test_tours_are_random_but_reproducible_with_a_seed():
    table = load_robot(ROBOTS / "paper-r1.toml").transitions
    assert exploration(table, 3, seed=5) == exploration(table, 3, seed=5)
    assert len({exploration(table, 3, seed=s).tours[0].states for s in range(10)}) > 1


def test_the_one_actuator_robot_reports_what_it_cannot_come_back_from():
    table = load_robot(ROBOTS / "paper-r1-one-actuator.toml").transitions
    ex = exploration(table, 2, seed=0)
    assert ex.tours and all(t.states[0] == t.states[-1] for t in ex.tours)
    assert len(ex.uncoverable_labels) == len(ex.uncoverable)


def test_a_demanded_transition_no_closed_tour_can_make_is_refused_by_label():
    table = TransitionTable.from_edges((3,), [0, 1, 1], [1, 0, 2], [0, 0, 0])
    demand = np.array([1, 1, 1])
    with pytest.raises(TourError, match="1->2"):
        exploration(table, demand=demand)


def test_a_partial_demand_is_joined_into_one_closed_tour_from_the_start_state():
    n = 4
    src = [a for a in range(n) for b in range(n) if a != b]
    dst = [b for a in range(n) for b in range(n) if a != b]
    table = TransitionTable.from_edges((n,), src, dst, np.zeros(len(src)))
    demand = np.zeros(table.n_transitions, dtype=int)
    demand[table.lookup(2, 3)] = 2
    ex = exploration(table, demand=demand, start=0, seed=1)
    (tour,) = ex.tours
    assert tour.states[0] == tour.states[-1] == 0
    assert Counter(tour.transitions)[(2, 3)] >= 2


@settings(max_examples=80, deadline=None)
@given(st.integers(2, 3), st.integers(1, 3), st.floats(1.0, 4.0), st.floats(0.5, 4.0), st.integers(0, 1000))
def test_no_coil_is_planned_past_the_firmwares_on_time_budget(limbs, r, coil_s, payback, seed):
    """Oracle: the firmware's debt budget (docs/safety.md) replayed transition by transition:
    a coil is on while it raises its limb, every second not on pays back ``payback`` s."""
    from proleg import states

    levels = (2,) * limbs
    n = 2 ** limbs
    src = [a for a in range(n) for b in range(n) if a != b]
    dst = [b for a in range(n) for b in range(n) if a != b]
    table = TransitionTable.from_edges(levels, src, dst, np.zeros(len(src)))
    limits = PieceLimits(max_transitions=20, coil_of_limb=tuple(range(limbs)), max_coil_on_s=coil_s,
                         coil_payback=payback)
    for tour in exploration(table, r, seed=seed).tours:
        for p in split(table, tour.states, limits):
            if len(p.transitions) == 1:
                continue
            debt = [0.0] * limbs
            for a, b in p.transitions:
                up_a, up_b = states.limb_levels(a, levels), states.limb_levels(b, levels)
                debt = [x + 1.0 if y > w else max(0.0, x - payback) for x, w, y in zip(debt, up_a, up_b)]
                assert max(debt) <= coil_s + 1e-9


def test_a_held_limb_is_not_on_time_so_inchworm_3_reaches_every_state_in_one_piece_from_rest():
    """The regression behind issue 15's endless inchworm-3 exploration: counting a held limb as
    on-time made every state with three limbs up unreachable from the rest state 000."""
    from proleg.learn.pieces import limits_for
    from proleg.learn.tours import _bfs_path

    robot = load_robot(ROBOTS / "inchworm-3.toml")
    t = robot.transitions
    succ = [[b for a2, b in zip(t.src.tolist(), t.dst.tolist()) if a2 == a] for a in range(t.n_states)]
    limits = limits_for(robot)
    for a, b in zip(t.src.tolist(), t.dst.tolist()):
        way = _bfs_path(t.n_states, succ, 0, a) + [b]
        pieces = split(t, way, limits)
        assert len(pieces) == 1 and pieces[0].loadable, (t.label(a), t.label(b), pieces)


def test_a_piece_is_loadable_when_its_way_back_fits_the_gait_table():
    """Pieces need not end next to their start: the runner closes them by the shortest way
    back, so ``split`` keeps them long (the old rule cut them to a direct closing step)."""
    robot = load_robot(ROBOTS / "inchworm-3.toml")
    t = robot.transitions
    walk = [t.index(s) for s in ("000", "100", "110", "111")]
    (piece,) = split(t, walk, PieceLimits())
    assert piece.loadable and piece.states == tuple(walk)
    g = piece.gait()
    assert g[:4] == tuple(walk) and all(t.lookup(a, b) is not None for a, b in zip(g, g[1:] + g[:1]))
    short = split(t, walk, PieceLimits(max_gait_steps=4))  # 000 100 110 111 + 2 back > 4 states
    assert len(short) > 1 and all(p.loadable and len(p.gait()) <= 4 for p in short)
