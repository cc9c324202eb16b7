"""Exploration tours: state sequences that make every allowed transition at least R times.

pMFC (Freeman, Mahendran & Vikas, "pMFC", IEEE T-RO 2025) learns a soft robot's transition
statistics from randomised Euler tours of its transition graph. An Euler tour exists only
when every state has as many allowed transitions in as out; a robot file with forbidden
transitions usually breaks that, so some transitions must be made more often than asked.
``exploration_tour`` adds the fewest extra transitions (the directed Chinese postman
problem, Edmonds & Johnson 1973), solved exactly as a min-cost flow: each state with more
transitions in than out supplies the surplus, each with more out than in absorbs it, every
allowed transition costs 1 and has no capacity limit; successive shortest paths with
Bellman–Ford on the residual graph (``_min_cost_balance``) give an integral optimum.
Hierholzer's algorithm with shuffled successor lists then walks a random Euler circuit.

A graph that is not strongly connected has transitions between its strongly connected
parts that no closed tour can make (the robot could not return); they are reported in
``Tour.uncoverable`` with their labels, and each part gets its own tour.

When only some transitions are asked for (a resumed run, an adaptive plan), the postman
problem becomes the rural postman problem (NP-hard): the balancing is still minimal, and
parts of the demand that end up disconnected are joined by shortest round trips from the
start state (a heuristic; documented in ``Tour.joined``).
"""

from __future__ import annotations

import random
from collections import deque
from dataclasses import dataclass, field

import numpy as np

from ..transitions import TransitionTable


class TourError(ValueError):
    """The demand cannot be met by a closed tour (e.g. a demanded transition between parts)."""


@dataclass(frozen=True)
class Tour:
    """A closed walk ``states[0] → … → states[-1] == states[0]`` (or one state, no demand)."""

    states: tuple[int, ...]
    extra: int = 0                      # transitions beyond the demand added to balance degrees
    joined: int = 0                     # transitions added to join disconnected demand (heuristic)

    @property
    def transitions(self) -> list[tuple[int, int]]:
        return list(zip(self.states, self.states[1:]))

    def __len__(self) -> int:
        return max(0, len(self.states) - 1)


@dataclass(frozen=True)
class Exploration:
    """Tours for each strongly connected part that has demand, and what no tour can make."""

    tours: tuple[Tour, ...]
    uncoverable: tuple[tuple[int, int], ...] = ()
    uncoverable_labels: tuple[str, ...] = field(default=())

    @property
    def n_transitions(self) -> int:
        return sum(len(t) for t in self.tours)


# ------------------------------------------------------------------------- graph helpers
def strongly_connected_components(n: int, edges: list[tuple[int, int]]) -> list[int]:
    """Component id per state (iterative Tarjan; ids in reverse topological order)."""
    succ: list[list[int]] = [[] for _ in range(n)]
    for a, b in edges:
        succ[a].append(b)
    index = [-1] * n
    low = [0] * n
    on = [False] * n
    comp = [-1] * n
    stack: list[int] = []
    counter = 0
    ncomp = 0
    for root in range(n):
        if index[root] != -1:
            continue
        work = [(root, 0)]
        while work:
            v, i = work.pop()
            if i == 0:
                index[v] = low[v] = counter
                counter += 1
                stack.append(v)
                on[v] = True
            recurse = False
            while i < len(succ[v]):
                w = succ[v][i]
                i += 1
                if index[w] == -1:
                    work.append((v, i))
                    work.append((w, 0))
                    recurse = True
                    break
                if on[w]:
                    low[v] = min(low[v], index[w])
            if recurse:
                continue
            if low[v] == index[v]:
                while True:
                    w = stack.pop()
                    on[w] = False
                    comp[w] = ncomp
                    if w == v:
                        break
                ncomp += 1
            if work:
                u = work[-1][0]
                low[u] = min(low[u], low[v])
    return comp


def successors(t: TransitionTable) -> list[list[int]]:
    """Per state, the states one allowed transition of ``t`` leads to."""
    succ: list[list[int]] = [[] for _ in range(t.n_states)]
    for a, b in zip(t.src.tolist(), t.dst.tolist()):
        succ[a].append(b)
    return succ


def reached_from(t: TransitionTable, start: int = 0) -> set[int]:
    """The states some way of allowed transitions leads to from ``start`` (the rest state)."""
    succ = successors(t)
    seen, todo = {start}, [start]
    while todo:
        for b in succ[todo.pop()]:
            if b not in seen:
                seen.add(b)
                todo.append(b)
    return seen


def _bfs_path(n: int, succ: list[list[int]], a: int, b: int) -> list[int] | None:
    """Shortest state path a → … → b (fewest transitions), or None."""
    prev = [-1] * n
    seen = [False] * n
    seen[a] = True
    q = deque([a])
    while q:
        v = q.popleft()
        if v == b:
            break
        for w in succ[v]:
            if not seen[w]:
                seen[w] = True
                prev[w] = v
                q.append(w)
    if not seen[b]:
        return None
    path = [b]
    while path[-1] != a:
        path.append(prev[path[-1]])
    return path[::-1]


def _min_cost_balance(n: int, edges: list[tuple[int, int]], imbalance: list[int]) -> list[int]:
    """Extra copies per edge, fewest in total, so that out − in + imbalance = 0 at every
    state. ``imbalance[v]`` = (in − out) of the demanded multigraph: > 0 needs more out.
    Min-cost flow by successive shortest paths (Bellman–Ford on the residual graph); raises
    TourError when the supplies cannot reach the demands."""
    m = len(edges)
    flow = [0] * m
    supply = list(imbalance)
    total = sum(x for x in supply if x > 0)
    inf = float("inf")
    for _ in range(total):
        # residual arcs: forward (cost +1, unbounded), backward (cost −1, while flow > 0)
        dist = [inf] * n
        pred: list[tuple[int, int] | None] = [None] * n  # (edge, +1 / −1)
        for v in range(n):
            if supply[v] > 0:
                dist[v] = 0
        for _round in range(n):
            changed = False
            for e, (a, b) in enumerate(edges):
                if dist[a] + 1 < dist[b]:
                    dist[b], pred[b], changed = dist[a] + 1, (e, 1), True
                if flow[e] > 0 and dist[b] - 1 < dist[a]:
                    dist[a], pred[a], changed = dist[b] - 1, (e, -1), True
            if not changed:
                break
        sinks = [v for v in range(n) if supply[v] < 0 and dist[v] < inf]
        if not sinks:
            raise TourError("the transitions asked for cannot be balanced into a closed tour")
        t = min(sinks, key=lambda v: dist[v])
        v, path = t, []
        while pred[v] is not None:  # back along the shortest-path tree to a supplying state
            e, sign = pred[v]  # type: ignore[misc]
            path.append((e, sign))
            v = edges[e][0] if sign == 1 else edges[e][1]
            if len(path) > n:
                raise AssertionError("negative cycle in the residual graph")  # SSP keeps optimality
        for e, sign in path:
            flow[e] += sign
        supply[v] -= 1
        supply[t] += 1
    return flow


def balance(n: int, edges: list[tuple[int, int]], demand: list[int]) -> list[int]:
    """Fewest extra copies per edge (list aligned with ``edges``) that make the multigraph
    with ``demand[e]`` copies of edge e balanced (in-degree = out-degree everywhere)."""
    imb = [0] * n
    for (a, b), k in zip(edges, demand):
        imb[b] += k
        imb[a] -= k
    return _min_cost_balance(n, edges, imb)


def _euler_circuit(n: int, multi: list[tuple[int, int]], start: int, rng: random.Random) -> list[int]:
    """Hierholzer with shuffled successor order: a random Euler circuit from ``start``."""
    succ: list[list[int]] = [[] for _ in range(n)]
    for a, b in multi:
        succ[a].append(b)
    for lst in succ:
        rng.shuffle(lst)
    stack = [start]
    out: list[int] = []
    while stack:
        v = stack[-1]
        if succ[v]:
            stack.append(succ[v].pop())
        else:
            out.append(stack.pop())
    return out[::-1]


# ------------------------------------------------------------------------- public
def exploration(
    table: TransitionTable,
    repeats: int = 1,
    *,
    demand: np.ndarray | None = None,
    start: int = 0,
    seed: int | None = None,
) -> Exploration:
    """Randomised closed tours making each allowed transition ``repeats`` times (or
    ``demand[e]`` times, aligned with ``table.src``/``table.dst``), with the fewest extra
    transitions. One tour per strongly connected part with demand; the tour of ``start``'s
    part comes first and starts at ``start``. Transitions between parts are returned in
    ``uncoverable`` (and get no tour); asking for them explicitly in ``demand`` raises
    ``TourError``."""
    n = table.n_states
    edges = list(zip(table.src.tolist(), table.dst.tolist()))
    if demand is None:
        want = [int(repeats)] * len(edges)
    else:
        want = [int(x) for x in np.asarray(demand).tolist()]
        if len(want) != len(edges) or min(want, default=0) < 0:
            raise ValueError("demand needs one count ≥ 0 per allowed transition")
    comp = strongly_connected_components(n, edges)
    inner = [comp[a] == comp[b] for a, b in edges]
    cross = [e for e, ok in enumerate(inner) if not ok]
    if demand is not None and any(want[e] for e in cross):
        bad = [f"{table.label(edges[e][0])}->{table.label(edges[e][1])}" for e in cross if want[e]]
        raise TourError(f"no closed tour can make {', '.join(bad)}: the robot cannot come back from there")
    rng = random.Random(seed)
    tours: list[Tour] = []
    parts = sorted({comp[a] for e, (a, b) in enumerate(edges) if inner[e] and want[e] > 0},
                   key=lambda c: (c != comp[start], c))
    for c in parts:
        idx = [e for e, (a, _b) in enumerate(edges) if inner[e] and comp[a] == c]
        sub = [edges[e] for e in idx]
        sub_want = [want[e] for e in idx]
        extra = balance(n, sub, sub_want)
        multi: list[tuple[int, int]] = []
        for (a, b), k, x in zip(sub, sub_want, extra):
            multi += [(a, b)] * (k + x)
        s = start if comp[start] == c else min(a for a, _b in sub)
        joined = _join(n, sub, multi, s)
        walk = _euler_circuit(n, multi, s, rng)
        tours.append(Tour(tuple(walk), extra=sum(extra), joined=joined))
    unc = tuple(edges[e] for e in cross)
    labels = tuple(f"{table.label(a)}->{table.label(b)}" for a, b in unc)
    return Exploration(tuple(tours), unc, labels)


def unexplorable(table: TransitionTable, uncoverable: tuple[tuple[int, int], ...], start: int = 0
                 ) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """Why no closed tour from ``start`` (the rest state) makes a transition, as ``a->b``
    labels: (every transition whose start no allowed way reaches from ``start``, whether or
    not it lies on a closed tour of its own part: the robot, resting at ``start``, never gets
    there; the other ``uncoverable`` ones (``Exploration.uncoverable``): one-way, no allowed
    way leads back from where they end). A part the rest state cannot reach was planned, and
    learning stopped at its first piece with "no piece within the thermal limits"."""
    seen = reached_from(table, start)
    unreachable = tuple(f"{table.label(a)}->{table.label(b)}"
                        for a, b in zip(table.src.tolist(), table.dst.tolist()) if a not in seen)
    one_way = tuple(f"{table.label(a)}->{table.label(b)}" for a, b in uncoverable if a in seen)
    return unreachable, one_way


def _join(n: int, sub: list[tuple[int, int]], multi: list[tuple[int, int]], start: int) -> int:
    """Append shortest round trips from ``start`` to every piece of ``multi`` not yet
    reachable from it (balanced pieces are strongly connected). Returns transitions added."""
    succ: list[list[int]] = [[] for _ in range(n)]
    for a, b in sub:
        succ[a].append(b)
    added = 0
    while True:
        comp = _weak_components(n, multi, start)
        others = sorted({comp[v] for a, b in multi for v in (a, b)} - {comp[start]})
        if not others:
            return added
        target = min(v for a, b in multi for v in (a, b) if comp[v] == others[0])
        there = _bfs_path(n, succ, start, target)
        back = _bfs_path(n, succ, target, start)
        assert there is not None and back is not None  # same strongly connected part
        hops = list(zip(there, there[1:])) + list(zip(back, back[1:]))
        multi += hops
        added += len(hops)


def _weak_components(n: int, multi: list[tuple[int, int]], start: int) -> list[int]:
    parent = list(range(n))

    def find(x: int) -> int:
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x

    for a, b in multi:
        parent[find(a)] = find(b)
    return [find(v) for v in range(n)]
