"""Simple cycles of a (small) directed graph: strongly connected components and Johnson.

Graphs here are adjacency dicts ``{node: [successor, ...]}`` (every successor is also a
key). Both algorithms are iterative, so deep graphs cannot exhaust Python's stack.
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Iterable, Iterator

Adjacency = dict[int, list[int]]


def strongly_connected_components(adj: Adjacency) -> list[list[int]]:
    """Tarjan's algorithm with an explicit stack; components in reverse topological order."""
    index: dict[int, int] = {}
    low: dict[int, int] = {}
    on_stack: set[int] = set()
    stack: list[int] = []
    out: list[list[int]] = []
    counter = 0
    for root in adj:
        if root in index:
            continue
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on_stack.add(root)
        work: list[tuple[int, Iterator[int]]] = [(root, iter(adj[root]))]
        while work:
            v, it = work[-1]
            for w in it:
                if w not in index:
                    index[w] = low[w] = counter
                    counter += 1
                    stack.append(w)
                    on_stack.add(w)
                    work.append((w, iter(adj[w])))
                    break
                if w in on_stack and index[w] < low[v]:
                    low[v] = index[w]
            else:
                work.pop()
                if work:
                    u = work[-1][0]
                    if low[v] < low[u]:
                        low[u] = low[v]
                if low[v] == index[v]:
                    comp = []
                    while True:
                        w = stack.pop()
                        on_stack.discard(w)
                        comp.append(w)
                        if w == v:
                            break
                    out.append(comp)
    return out


def _restrict(adj: Adjacency, nodes: Iterable[int]) -> Adjacency:
    keep = set(nodes)
    return {v: [w for w in adj[v] if w in keep] for v in sorted(keep)}


def simple_cycles(
    adj: Adjacency, limit: int | None = None, max_states: int | None = None
) -> tuple[list[tuple[int, ...]], bool]:
    """Every simple cycle (no state twice), each starting at its lowest node; Johnson (1975).

    For each strongly connected component, take its lowest node s, list the cycles
    through s with Johnson's blocking rule (a node stays blocked until a cycle is found
    through it, so dead ends are never searched twice), then drop s and recurse into the
    components of what is left. Time O((n + e)(c + 1)) for c cycles. Returns the cycles
    (open: the start is not repeated) and whether the listing stopped early: at ``limit``
    cycles, or once the cycles hold ``max_states`` states in all (long cycles of a large
    flat graph would otherwise fill the memory).
    """
    cycles: list[tuple[int, ...]] = []
    listed = 0
    pending = [c for c in strongly_connected_components(adj) if len(c) > 1]
    while pending:
        comp = pending.pop()
        sub = _restrict(adj, comp)
        start = min(comp)
        path = [start]
        blocked = {start}
        closed: set[int] = set()
        b_sets: defaultdict[int, set[int]] = defaultdict(set)
        work: list[tuple[int, Iterator[int]]] = [(start, iter(sub[start]))]
        while work:
            v, it = work[-1]
            advanced = False
            for w in it:
                if w == start:
                    cycles.append(tuple(path))
                    listed += len(path)
                    if (limit is not None and len(cycles) >= limit) or (max_states is not None and listed >= max_states):
                        return cycles, True
                    closed.update(path)
                elif w not in blocked:
                    path.append(w)
                    work.append((w, iter(sub[w])))
                    closed.discard(w)
                    blocked.add(w)
                    advanced = True
                    break
            if advanced:
                continue
            if v in closed:
                todo = {v}
                while todo:
                    u = todo.pop()
                    if u in blocked:
                        blocked.remove(u)
                        todo.update(b_sets[u])
                        b_sets[u].clear()
            else:
                for w in sub[v]:
                    b_sets[w].add(v)
            work.pop()
            path.pop()
        rest = _restrict(sub, [v for v in comp if v != start])
        pending.extend(c for c in strongly_connected_components(rest) if len(c) > 1)
    return cycles, False


def short_cycles(
    adj: Adjacency, max_len: int, limit: int | None = None, max_states: int | None = None
) -> tuple[list[tuple[int, ...]], bool]:
    """Every simple cycle of at most ``max_len`` transitions, each starting at its lowest node.

    For each start s (ascending): a breadth-first search backwards from s over nodes > s
    gives each node's distance back to s; a depth-first search forwards from s then only
    steps to a node from which s is still reachable within the remaining budget. Cheap
    when ``max_len`` is small, however large the graph. Returns the cycles and whether
    ``limit`` / ``max_states`` stopped the listing early.
    """
    radj: defaultdict[int, list[int]] = defaultdict(list)
    for v, succ in adj.items():
        for w in succ:
            radj[w].append(v)
    cycles: list[tuple[int, ...]] = []
    listed = 0
    for s in sorted(adj):
        dist = {s: 0}
        frontier = [s]
        depth = 0
        while frontier and depth < max_len - 1:
            depth += 1
            nxt = []
            for v in frontier:
                for u in radj[v]:
                    if u > s and u not in dist:
                        dist[u] = depth
                        nxt.append(u)
            frontier = nxt
        path = [s]
        on_path = {s}
        work: list[Iterator[int]] = [iter(adj[s])]
        while work:
            for w in work[-1]:
                if w == s:
                    if len(path) >= 2:
                        cycles.append(tuple(path))
                        listed += len(path)
                        if (limit is not None and len(cycles) >= limit) or (
                            max_states is not None and listed >= max_states
                        ):
                            return cycles, True
                elif w > s and w not in on_path and w in dist and len(path) + dist[w] <= max_len:
                    path.append(w)
                    on_path.add(w)
                    work.append(iter(adj[w]))
                    break
            else:
                work.pop()
                on_path.discard(path.pop())
    return cycles, False
