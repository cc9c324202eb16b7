"""gait.entry: the entry-path search, against a brute-force oracle on random transition graphs."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from proleg.errors import GaitError
from proleg.gait.entry import EntryPath, entry_walk
from proleg.transitions import TransitionTable

LEVELS = (2, 2, 2)
N = 8


def _table(edges: set[tuple[int, int]]) -> TransitionTable:
    src, dst = zip(*sorted(edges)) if edges else ((), ())
    return TransitionTable.from_edges(LEVELS, list(src), list(dst), [0.0] * len(edges))


def _oracle(edges, cycle, rest, ok):
    """The contract by brute force: every simple walk from rest over ``ok`` steps that ends on
    its first gait state, the best by (length, gait position of its end, its states read back
    from the end), which is "shortest, ties to the gait state first in the gait, then each
    state reached from the lowest one a step nearer to rest"."""
    if rest in cycle:
        return EntryPath((rest,), cycle.index(rest))
    walks, stack = [], [(rest,)]
    while stack:
        w = stack.pop()
        for a, b in edges:
            if a == w[-1] and b not in w and ok(a, b):
                (walks if b in cycle else stack).append((*w, b))
    if not walks:
        return None
    best = min(walks, key=lambda w: (len(w), cycle.index(w[-1]), tuple(reversed(w))))
    return EntryPath(best, cycle.index(best[-1]))


graphs = st.sets(st.tuples(st.integers(0, N - 1), st.integers(0, N - 1)).filter(lambda e: e[0] != e[1]),
                 max_size=24)


@settings(max_examples=300, deadline=None)
@given(edges=graphs, data=st.data())
def test_the_entry_path_is_the_shortest_walk_keeping_out_of_trouble_where_one_does(edges, data):
    cycle = data.draw(st.lists(st.integers(0, N - 1), min_size=1, max_size=4, unique=True), "cycle")
    rest = data.draw(st.integers(0, N - 1), "rest")
    some_edges = st.sets(st.sampled_from(sorted(edges)), max_size=4) if edges else st.just(set())
    refused = data.draw(some_edges, "refused")  # steps the hardware cannot make
    blocked = data.draw(some_edges, "blocked")
    unheld = data.draw(st.sets(st.integers(0, N - 1), max_size=3), "unheld")
    table = _table(edges)

    def can_step(a, b):
        return (a, b) not in refused

    def clean(a, b):
        return can_step(a, b) and (b not in unheld or b in cycle) and (a, b) not in blocked

    want = _oracle(edges, cycle, rest, clean) or _oracle(edges, cycle, rest, can_step)
    if want is None:
        with pytest.raises(GaitError, match="no allowed path from the rest state"):
            entry_walk(table, cycle, rest, can_step, unheld, blocked)
        return
    got = entry_walk(table, cycle, rest, can_step, unheld, blocked)
    assert got == want
    assert got.states[0] == rest and got.states[-1] == cycle[got.gait_step]


def test_a_gait_through_rest_is_entered_where_it_passes_rest_without_a_step():
    table = _table({(0, 1), (1, 0)})
    assert entry_walk(table, [3, 0, 5], 0, lambda a, b: True) == EntryPath((0,), 1)


def test_a_way_in_through_a_state_the_body_cannot_hold_is_taken_only_when_there_is_no_other():
    # 0 -> 1 -> 3 is the shortest; 0 -> 2 -> 4 -> 3 keeps out of 1
    edges = {(0, 1), (1, 3), (0, 2), (2, 4), (4, 3)}
    table = _table(edges)
    assert entry_walk(table, [3], 0, lambda a, b: True, unheld={1}).states == (0, 2, 4, 3)
    assert entry_walk(table, [3], 0, lambda a, b: True, unheld={1, 2}).states == (0, 1, 3)
    assert entry_walk(table, [3], 0, lambda a, b: True, blocked={(2, 4)}, unheld={1}).states == (0, 1, 3)
