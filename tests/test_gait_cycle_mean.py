"""Howard policy iteration against Karp and a brute-force listing of simple cycles.

Random graphs that are sparse, split into several strongly connected components, or
have nodes without out-edges (and nodes that only lead to such dead ends).
"""

from __future__ import annotations

import itertools
import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from proleg.gait.bruteforce import brute_force_max_cycle_mean
from proleg.gait.cycles import short_cycles, simple_cycles, strongly_connected_components
from proleg.gait.howard import max_cycle_ratio
from proleg.gait.karp import max_cycle_mean


@st.composite
def graphs(draw, max_nodes: int = 7):
    n = draw(st.integers(1, max_nodes))
    pairs = [(a, b) for a in range(n) for b in range(n) if a != b]
    chosen = draw(st.lists(st.sampled_from(pairs), unique=True, max_size=len(pairs))) if pairs else []
    chosen.sort()
    weights = draw(
        st.lists(
            st.one_of(st.integers(-4, 4).map(float), st.floats(-10, 10).map(lambda v: round(v, 2))),
            min_size=len(chosen),
            max_size=len(chosen),
        )
    )
    src = np.array([a for a, _ in chosen], dtype=np.int64)
    dst = np.array([b for _, b in chosen], dtype=np.int64)
    return n, src, dst, np.array(weights, dtype=np.float64)


def close(a: float | None, b: float | None) -> bool:
    return (a is None and b is None) or (a is not None and b is not None and math.isclose(a, b, abs_tol=1e-9))


@settings(max_examples=300, deadline=None)
@given(graphs())
def test_howard_karp_and_brute_force_agree_on_the_maximum_cycle_mean(graph):
    n, src, dst, w = graph
    expected = brute_force_max_cycle_mean(n, src, dst, w)
    assert close(max_cycle_mean(n, src, dst, w), expected)
    assert close(max_cycle_ratio(n, src, dst, w).value, expected)


@settings(max_examples=150, deadline=None)
@given(graphs(), st.data())
def test_howard_finds_the_maximum_cycle_ratio_with_durations(graph, data):
    n, src, dst, w = graph
    t = np.array(data.draw(st.lists(st.sampled_from([0.25, 1.0, 2.0, 3.5]), min_size=len(w), max_size=len(w))))
    best = None
    edges = {(int(a), int(b)): (float(x), float(y)) for a, b, x, y in zip(src, dst, w, t)}
    for length in range(2, n + 1):
        for perm in itertools.permutations(range(n), length):
            steps = list(zip(perm, perm[1:] + perm[:1]))
            if perm[0] == min(perm) and all(s in edges for s in steps):
                r = math.fsum(edges[s][0] for s in steps) / math.fsum(edges[s][1] for s in steps)
                best = r if best is None else max(best, r)
    assert close(max_cycle_ratio(n, src, dst, w, t).value, best)


@settings(max_examples=300, deadline=None)
@given(graphs())
def test_howard_eta_is_the_best_cycle_reachable_from_each_node(graph):
    n, src, dst, w = graph
    sol = max_cycle_ratio(n, src, dst, w)
    cycles, _ = simple_cycles({v: [int(b) for a, b in zip(src, dst) if a == v] for v in range(n)})
    weight = {(int(a), int(b)): float(x) for a, b, x in zip(src, dst, w)}
    means = [math.fsum(weight[s] for s in zip(c, c[1:] + c[:1])) / len(c) for c in cycles]
    adj = {v: [int(b) for a, b in zip(src, dst) if a == v] for v in range(n)}
    for v in range(n):
        seen, todo = {v}, [v]
        while todo:
            for b in adj[todo.pop()]:
                if b not in seen:
                    seen.add(b)
                    todo.append(b)
        reach = [m for c, m in zip(cycles, means) if c[0] in seen]
        if reach:
            assert math.isclose(sol.eta[v], max(reach), abs_tol=1e-9)
        else:
            assert sol.eta[v] == -np.inf


@settings(max_examples=20, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(20, 300), st.sampled_from([1.5, 3.0, 8.0]))
def test_howard_and_karp_agree_on_larger_random_graphs(seed, n, degree):
    rng = np.random.default_rng(seed)
    m = int(n * degree)
    key = np.unique(rng.integers(0, n, m) * n + rng.integers(0, n, m))
    src, dst = key // n, key % n
    keep = src != dst
    src, dst = src[keep], dst[keep]
    w = rng.integers(-20, 21, len(src)).astype(float)
    karp = max_cycle_mean(n, src, dst, w)
    assert close(max_cycle_ratio(n, src, dst, w).value, karp)


def test_graph_without_cycles_has_no_cycle_mean():
    src, dst, w = np.array([0, 1]), np.array([1, 2]), np.array([1.0, 2.0])
    assert max_cycle_mean(3, src, dst, w) is None
    assert max_cycle_ratio(3, src, dst, w).value is None


def test_johnson_lists_every_simple_cycle_of_a_complete_graph():
    for n in range(1, 7):
        adj = {v: [u for u in range(n) if u != v] for v in range(n)}
        cycles, truncated = simple_cycles(adj)
        expected = sum(math.comb(n, k) * math.factorial(k - 1) for k in range(2, n + 1))
        assert not truncated and len(cycles) == len(set(cycles)) == expected
        assert all(c[0] == min(c) for c in cycles)


def test_johnson_stops_at_the_limit_and_says_so():
    adj = {v: [u for u in range(8) if u != v] for v in range(8)}
    cycles, truncated = simple_cycles(adj, limit=100)
    assert truncated and len(cycles) == 100


def test_scc_and_johnson_are_iterative_on_a_100k_node_ring():
    n = 100_000
    adj = {v: [(v + 1) % n] for v in range(n)}
    assert len(strongly_connected_components(adj)) == 1
    cycles, _ = simple_cycles(adj)
    assert cycles == [tuple(range(n))]


@settings(max_examples=200, deadline=None)
@given(graphs(), st.integers(2, 7))
def test_short_cycles_are_the_simple_cycles_up_to_the_length(graph, max_len):
    n, src, dst, _ = graph
    adj = {v: [int(b) for a, b in zip(src, dst) if a == v] for v in range(n)}
    every, _ = simple_cycles(adj)
    short, truncated = short_cycles(adj, max_len)
    assert not truncated and len(short) == len(set(short))
    assert set(short) == {c for c in every if len(c) <= max_len}
